// SPDX-License-Identifier: Apache-2.0
// dsp::CoarseRegion: the coarse windows a coarse-to-fine retry draws on.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

#include "tacse3/dsp/coarse_region.hpp"

namespace tacse3::dsp {
namespace {

using Retry = std::array<std::uint8_t, kGridCount>;

// The tracked windows of one level as (x, y) pairs, row-major.
std::vector<std::array<int, 2>> tracked_cells(const CoarseRegion& r, int level) {
  std::vector<std::array<int, 2>> cells;
  for (int y = 0; y < flow_grid_height(level); ++y) {
    for (int x = 0; x < flow_grid_width(level); ++x) {
      if (r.tracked(level, y * flow_grid_width(level) + x)) cells.push_back({x, y});
    }
  }
  return cells;
}

// A block of cells x0..x1 by y0..y1, row-major.
std::vector<std::array<int, 2>> block(int x0, int x1, int y0, int y1) {
  std::vector<std::array<int, 2>> cells;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) cells.push_back({x, y});
  }
  return cells;
}

TEST(UpsampleTaps, NearIsTheCoveringCellAndFarItsNeighbourOnTheSideOfTheFineCell) {
  int near = -1, far = -1;
  upsample_taps(10, 20, near, far);  // even: the left half of coarse cell 5
  EXPECT_EQ(near, 5);
  EXPECT_EQ(far, 4);
  upsample_taps(11, 20, near, far);  // odd: the right half
  EXPECT_EQ(near, 5);
  EXPECT_EQ(far, 6);
  upsample_taps(0, 20, near, far);  // clamped at the borders
  EXPECT_EQ(far, 0);
  upsample_taps(14, 7, near, far);  // a fine axis with an odd count: the last cell clamps
  EXPECT_EQ(near, 6);
  EXPECT_EQ(far, 6);
}

TEST(CoarseRegion, NothingToRetryTracksNothing) {
  const Retry retry{};
  CoarseRegion r;
  r.build(retry.data(), 3);
  EXPECT_EQ(r.tracked_count(), 0);
}

// One failed window at (10, 10): its correction comes from level-1 cells {4, 5} x {4, 5}, which
// are tracked with their neighbours {3..6}^2; those take theirs from level-2 cells {1, 2, 3}^2,
// tracked with their neighbours {0..4}^2.
TEST(CoarseRegion, OneFailedWindowTracksItsTapsAndTheirNeighbours) {
  Retry retry{};
  retry[10 * kGridWidth + 10] = 1;
  CoarseRegion r;
  r.build(retry.data(), 3);
  EXPECT_EQ(tracked_cells(r, 1), block(3, 6, 3, 6));
  EXPECT_EQ(tracked_cells(r, 2), block(0, 4, 0, 4));
  EXPECT_EQ(r.tracked_count(), 16 + 25);
  r.build(retry.data(), 2);  // two levels: level 1 alone
  EXPECT_EQ(tracked_cells(r, 1), block(3, 6, 3, 6));
  EXPECT_EQ(r.tracked_count(), 16);
}

TEST(CoarseRegion, AFailedCornerWindowStaysInsideTheGrid) {
  Retry retry{};
  retry[kGridCount - 1] = 1;  // (39, 29)
  CoarseRegion r;
  r.build(retry.data(), 3);
  // Level 1 (20 x 15): taps x {19}, y {14}; tracked {18, 19} x {13, 14}.
  EXPECT_EQ(tracked_cells(r, 1), block(18, 19, 13, 14));
  // Level 2 (10 x 7): taps of x 18, 19 are {8, 9}, of y 13, 14 are {6}; tracked {7..9} x {5, 6}.
  EXPECT_EQ(tracked_cells(r, 2), block(7, 9, 5, 6));
}

TEST(CoarseRegion, EveryWindowFailedTracksEveryCoarseWindow) {
  Retry retry;
  retry.fill(1);
  CoarseRegion r;
  r.build(retry.data(), 3);
  EXPECT_EQ(r.tracked_count(), flow_grid_count(1) + flow_grid_count(2));
}

// Rebuilding forgets the previous region.
TEST(CoarseRegion, ABuildReplacesThePreviousRegion) {
  Retry all;
  all.fill(1);
  Retry one{};
  one[10 * kGridWidth + 10] = 1;
  CoarseRegion r;
  r.build(all.data(), 3);
  r.build(one.data(), 3);
  EXPECT_EQ(r.tracked_count(), 16 + 25);
}

}  // namespace
}  // namespace tacse3::dsp
