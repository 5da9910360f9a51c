// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: dsp::velocity_reads_anchor, the velocity proxy's drag-region rule, at its edges.
#include <gtest/gtest.h>

#include "tacse3/dsp/motion.hpp"

namespace tacse3::dsp {
namespace {

// Planar content [L·θ, t_x, t_y]: a drag has |t| > |L·θ|, a torsion not.
const Eigen::Vector3d kDrag(0.3e-6, 0.0, 0.4e-6);        // |t| = 0.4 > 0.3
const Eigen::Vector3d kTorsion(0.5e-6, 0.3e-6, 0.4e-6);  // |t| = 0.5 = |L·θ|: not strictly more

TEST(DragRegion, ADragWithHalfTheSmallerSetReadsTheAnchor) {
  // Ω of 200 cells, anchor of 100: the overlap must reach 0.5 · 100 (inclusive).
  EXPECT_TRUE(velocity_reads_anchor(kDrag, 50, 100, 200));
  EXPECT_FALSE(velocity_reads_anchor(kDrag, 49, 100, 200));
  // A shrunken Ω (a tilting face keeps a strip of its anchor): half of Ω suffices.
  EXPECT_TRUE(velocity_reads_anchor(kDrag, 20, 100, 40));
  EXPECT_FALSE(velocity_reads_anchor(kDrag, 19, 100, 40));
}

TEST(DragRegion, TorsionShearFreeFramesAndNoAnchorReadAllOfOmega) {
  EXPECT_FALSE(velocity_reads_anchor(kTorsion, 100, 100, 100));
  EXPECT_FALSE(velocity_reads_anchor(Eigen::Vector3d::Zero(), 100, 100, 100));
  EXPECT_FALSE(velocity_reads_anchor(kDrag, 0, 0, 100));
}

}  // namespace
}  // namespace tacse3::dsp
