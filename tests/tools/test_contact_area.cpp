// SPDX-License-Identifier: Apache-2.0
// The contact mask's minimum area fitted from the noise's components before contact.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "tacse3/tools/contact_area.hpp"

namespace tt = tacse3::tools;
namespace dsp = tacse3::dsp;

namespace {

constexpr float kTau = 0.01f;

tt::FzGrid quiet() {
  tt::FzGrid g;
  g.fill(0.0f);
  return g;
}

// A w x h block of grid points over the bar, top-left at (x, y).
void block(tt::FzGrid& g, int x, int y, int w, int h, float v = 2 * kTau) {
  for (int gy = y; gy < y + h; ++gy) {
    for (int gx = x; gx < x + w; ++gx) g[static_cast<std::size_t>(gy * dsp::kGridWidth + gx)] = v;
  }
}

}  // namespace

TEST(LargestComponent, CountsFourConnectedPointsOverTheBar) {
  tt::FzGrid g = quiet();
  EXPECT_EQ(tt::largest_component(g, kTau), 0);
  block(g, 2, 2, 3, 3);  // 9 points
  block(g, 10, 10, 1, 1);
  block(g, 20, 5, 4, 1);  // 4 points
  EXPECT_EQ(tt::largest_component(g, kTau), 9);
  // Diagonal neighbours are not connected: a checkerboard of 5 points is five components of 1.
  tt::FzGrid c = quiet();
  for (const auto& p : {std::pair{30, 20}, {31, 21}, {32, 20}, {30, 22}, {32, 22}}) {
    block(c, p.first, p.second, 1, 1);
  }
  EXPECT_EQ(tt::largest_component(c, kTau), 1);
  // Exactly at the bar is not over it (the detector's f > tau_on); NaN is not valid.
  tt::FzGrid e = quiet();
  block(e, 0, 0, 2, 2, kTau);
  EXPECT_EQ(tt::largest_component(e, kTau), 0);
  block(e, 0, 0, 2, 2, std::numeric_limits<float>::quiet_NaN());
  EXPECT_EQ(tt::largest_component(e, kTau), 0);
  // Components touching the grid's edges and corners are counted whole.
  tt::FzGrid edge = quiet();
  block(edge, dsp::kGridWidth - 3, dsp::kGridHeight - 2, 3, 2);
  EXPECT_EQ(tt::largest_component(edge, kTau), 6);
}

TEST(ContactStart, IsTheFrameAfterTheLastEmptyOne) {
  EXPECT_EQ(tt::contact_start({}), 0u);
  EXPECT_EQ(tt::contact_start({0, 2, 0, 0}), 4u);           // no contact at the end
  EXPECT_EQ(tt::contact_start({0, 3, 0, 14, 30, 60}), 3u);  // noise, a gap, the grasp
  EXPECT_EQ(tt::contact_start({0, 40, 60, 58, 55}), 1u);    // overshoot and settle
  EXPECT_EQ(tt::contact_start({2, 3, 2, 20, 50}), 0u);      // noise runs into the contact
}

TEST(NoiseComponents, QuietFramesEndAtTheLaterPadsContact) {
  tt::PreMotionFz fz;
  // Left pad: one 5-point blob at frame 2, contact from frame 6 (12 x 4 points at the end).
  // Right pad: components of 3, 8, 2 and 2 points at frames 1-4 that run without a gap into its
  // earlier contact, from frame 5 (5 x 9 points, then growing).
  const int right[] = {0, 3, 8, 2, 2};
  for (int i = 0; i < 9; ++i) {
    tt::FzGrid l = quiet(), r = quiet();
    if (i == 2) block(l, 0, 0, 5, 1);
    if (i >= 6) block(l, 10, 10, 4 + i, 4);
    if (i < 5) block(r, 30, 2, right[i], 1);
    if (i >= 5) block(r, 10, 10, 5, 4 + i);
    fz.add(0, l);
    fz.add(1, r);
  }
  const tt::NoiseComponents nc = tt::noise_components(fz, kTau);
  EXPECT_EQ(nc.quiet_frames, 6u);
  // The 8-point component is noise (a 2-point frame follows it); the right pad's contact frame 5
  // (45 points, before the left pad's onset) is not.
  EXPECT_EQ(nc.largest, 8);
  EXPECT_EQ(nc.contact_cells[0], 12 * 4);
  EXPECT_EQ(nc.contact_cells[1], 5 * 12);
}

TEST(NoiseComponents, ALargerComponentRunningIntoTheContactCountsAsContact) {
  tt::PreMotionFz fz;
  const int right[] = {0, 3, 2, 9};  // the 9 runs straight into the contact at frame 4
  for (int i = 0; i < 7; ++i) {
    tt::FzGrid l = quiet(), r = quiet();
    if (i == 1) block(l, 0, 0, 4, 1);
    if (i >= 5) block(l, 10, 10, 6, 6);
    if (i < 4) block(r, 30, 2, right[i], 1);
    if (i >= 4) block(r, 10, 10, 6, 6);
    fz.add(0, l);
    fz.add(1, r);
  }
  const tt::NoiseComponents nc = tt::noise_components(fz, kTau);
  EXPECT_EQ(nc.quiet_frames, 5u);
  EXPECT_EQ(nc.largest, 4);
}

TEST(NoiseComponents, NoContactBeforeTheMotionGivesNoQuietRun) {
  tt::PreMotionFz fz;
  for (int i = 0; i < 5; ++i) {
    tt::FzGrid g = quiet();
    if (i == 3) block(g, 1, 1, 2, 2);
    fz.add(0, g);
    fz.add(1, quiet());
  }
  const tt::NoiseComponents nc = tt::noise_components(fz, kTau);
  EXPECT_EQ(nc.quiet_frames, 0u);
  EXPECT_EQ(nc.largest, 0);
  EXPECT_EQ(nc.contact_cells[0], 0);
  EXPECT_EQ(nc.contact_cells[1], 0);
}
