// SPDX-License-Identifier: Apache-2.0
// dsp/flow_grid.hpp: the block flow's grid at each pyramid level.
#include <gtest/gtest.h>

#include "tacse3/dsp/flow_grid.hpp"
#include "tacse3/dsp/geometry.hpp"

namespace tacse3::dsp {
namespace {

TEST(FlowGrid, EachLevelHalvesTheGridAndTheLevelsArePackedInOrder) {
  EXPECT_EQ(flow_grid_width(0), 40);
  EXPECT_EQ(flow_grid_height(0), 30);
  EXPECT_EQ(flow_grid_count(1), 20 * 15);
  EXPECT_EQ(flow_grid_count(2), 10 * 7);  // an odd height rounds down
  EXPECT_EQ(flow_grid_offset(0), 0);
  EXPECT_EQ(flow_grid_offset(1), 1200);
  EXPECT_EQ(flow_grid_offset(2), 1500);
  EXPECT_EQ(kFlowModelCount, 1570);
}

// A window of level l covers 8 level-l px, i.e. 2^(l+3) working px, and the level-l grid step is
// 4 level-l px: every level's windows overlap their neighbours by half.
TEST(FlowGrid, TheWindowIsTwiceTheGridStepAtLevelZero) {
  EXPECT_EQ(kFlowWindow, 2 * kGridStride);
  EXPECT_EQ(kFlowWindowPixels, 64);
  EXPECT_EQ(flow_grid_width(0) * kGridStride, kWorkWidth);
}

}  // namespace
}  // namespace tacse3::dsp
