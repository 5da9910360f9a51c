// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: the coarse-level windows a coarse-to-fine retry needs (block flow, stage 1).
#pragma once

#include <array>
#include <cstdint>

#include "tacse3/dsp/flow_grid.hpp"

namespace tacse3::dsp {

// Cell-centred 2x upsampling taps of fine index k on a coarse axis of n samples: weight 3/4 on
// `near`, 1/4 on `far` (BlockFlow's coarse-to-fine corrections).
constexpr void upsample_taps(int k, int n, int& near, int& far) noexcept {
  const int m = k >> 1;
  near = m < n - 1 ? m : n - 1;
  const int f = (k & 1) ? m + 1 : m - 1;
  far = f < 0 ? 0 : (f > n - 1 ? n - 1 : f);
}

// The coarse fallback retries only the level-0 windows that failed, and each takes its coarse
// correction from four cells of level 1, which took theirs from four cells of level 2, and so on.
// So only the windows below those cells need tracking, with their 8-neighbours (the consensus
// test reads them). Built top-down from the retried set, this gives the retried windows the
// same corrections as a pass over every coarse window, except where the gap filling needs a
// second sweep (a 3x3 block of cells with no tracked one), at a cost that follows the number of
// failed windows instead of the grid size.
class CoarseRegion {
 public:
  // retry: kGridCount flags of the level-0 windows the coarse pass serves (1 = retried).
  void build(const std::uint8_t* retry, int levels) noexcept;

  // Whether window j of level l (1 <= l < levels) is tracked.
  bool tracked(int level, int j) const noexcept {
    return track_[static_cast<std::size_t>(flow_grid_offset(level) + j)] != 0;
  }
  int tracked_count() const noexcept { return count_; }  // over all coarse levels

 private:
  std::array<std::uint8_t, kFlowModelCount> track_{};  // level l at flow_grid_offset(l)
  int count_ = 0;
};

}  // namespace tacse3::dsp
