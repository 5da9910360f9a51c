// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: the block flow's windows and its grid at each pyramid level.
#pragma once

#include "tacse3/dsp/pyramid.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// Square matching window, in pixels of the pyramid level it is applied to. 8 x 8 working px
// (16 x 16 sensor px) centred on a grid point: neighbouring windows overlap by half.
inline constexpr int kFlowWindow = 8;
inline constexpr int kFlowWindowPixels = kFlowWindow * kFlowWindow;  // 64 = 2^6

// Grid of level l: the level-0 grid decimated by 2^l. Point j of level l sits at level-l
// coordinate 4 j + 1.5 and stands for the 2^l x 2^l block of level-0 points it covers.
constexpr int flow_grid_width(int level) noexcept {
  return kGridWidth >> level;
}
constexpr int flow_grid_height(int level) noexcept {
  return kGridHeight >> level;
}
constexpr int flow_grid_count(int level) noexcept {
  return flow_grid_width(level) * flow_grid_height(level);
}
constexpr int flow_grid_offset(int level) noexcept {
  int off = 0;
  for (int l = 0; l < level; ++l) off += flow_grid_count(l);
  return off;
}
inline constexpr int kFlowModelCount = flow_grid_offset(kMaxPyramidLevels);  // 1200+300+70

}  // namespace tacse3::dsp
