// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: the coarse-level windows a coarse-to-fine retry needs.
#include "tacse3/dsp/coarse_region.hpp"

#include <algorithm>
#include <cstddef>

namespace tacse3::dsp {

void CoarseRegion::build(const std::uint8_t* retry, int levels) noexcept {
  track_.fill(0);
  count_ = 0;
  const std::uint8_t* served = retry;  // cells of the level below whose corrections must be exact
  for (int l = 1; l < levels; ++l) {
    const int fw = flow_grid_width(l - 1), fh = flow_grid_height(l - 1);
    const int gw = flow_grid_width(l), gh = flow_grid_height(l);
    // The taps of the served cells: their corrections come from these.
    std::array<std::uint8_t, flow_grid_count(1)> taps{};
    for (int y = 0; y < fh; ++y) {
      int y0, y1;
      upsample_taps(y, gh, y0, y1);
      for (int x = 0; x < fw; ++x) {
        if (!served[y * fw + x]) continue;
        int x0, x1;
        upsample_taps(x, gw, x0, x1);
        taps[static_cast<std::size_t>(y0 * gw + x0)] = 1;
        taps[static_cast<std::size_t>(y0 * gw + x1)] = 1;
        taps[static_cast<std::size_t>(y1 * gw + x0)] = 1;
        taps[static_cast<std::size_t>(y1 * gw + x1)] = 1;
      }
    }
    // Tracked: the taps and their 8-neighbours, whose matches the taps' consensus test reads.
    std::uint8_t* track = track_.data() + flow_grid_offset(l);
    for (int y = 0; y < gh; ++y) {
      for (int x = 0; x < gw; ++x) {
        if (!taps[static_cast<std::size_t>(y * gw + x)]) continue;
        for (int ny = std::max(y - 1, 0); ny <= std::min(y + 1, gh - 1); ++ny) {
          for (int nx = std::max(x - 1, 0); nx <= std::min(x + 1, gw - 1); ++nx) {
            track[ny * gw + nx] = 1;
          }
        }
      }
    }
    for (int j = 0; j < gw * gh; ++j) count_ += track[j];
    served = track;  // their own warm starts take the next level's corrections
  }
}

}  // namespace tacse3::dsp
