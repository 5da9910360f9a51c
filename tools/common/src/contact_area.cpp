// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the contact mask's minimum area, from the noise's own components before contact.
#include "tacse3/tools/contact_area.hpp"

#include <algorithm>

namespace tacse3::tools {

int largest_component(const FzGrid& fz, double tau_on) noexcept {
  constexpr int kW = dsp::kGridWidth, kH = dsp::kGridHeight, kN = dsp::kGridCount;
  const auto tau = static_cast<float>(tau_on);
  std::array<bool, static_cast<std::size_t>(kN)> seen{};
  std::array<int, static_cast<std::size_t>(kN)> queue{};
  auto on = [&](int i) { return fz[static_cast<std::size_t>(i)] > tau; };  // NaN: not on
  int largest = 0;
  for (int seed = 0; seed < kN; ++seed) {
    if (!on(seed) || seen[static_cast<std::size_t>(seed)]) continue;
    int head = 0, tail = 0;
    queue[static_cast<std::size_t>(tail++)] = seed;
    seen[static_cast<std::size_t>(seed)] = true;
    while (head < tail) {
      const int c = queue[static_cast<std::size_t>(head++)];
      const int cx = c % kW, cy = c / kW;
      const int nbr[4][2] = {{cx - 1, cy}, {cx + 1, cy}, {cx, cy - 1}, {cx, cy + 1}};
      for (const auto& p : nbr) {
        if (p[0] < 0 || p[0] >= kW || p[1] < 0 || p[1] >= kH) continue;
        const int q = p[1] * kW + p[0];
        if (!on(q) || seen[static_cast<std::size_t>(q)]) continue;
        seen[static_cast<std::size_t>(q)] = true;
        queue[static_cast<std::size_t>(tail++)] = q;
      }
    }
    largest = std::max(largest, tail);
  }
  return largest;
}

std::size_t contact_start(const std::vector<int>& sizes) noexcept {
  std::size_t i = sizes.size();
  while (i > 0 && sizes[i - 1] > 0) --i;
  return i == sizes.size() ? sizes.size() : i;
}

NoiseComponents noise_components(const PreMotionFz& fz, double tau_on) {
  NoiseComponents out;
  std::array<std::vector<int>, 2> sizes;
  std::array<std::size_t, 2> start{};
  std::size_t onset = 0;
  for (std::size_t p = 0; p < 2; ++p) {
    for (const FzGrid& g : fz.frames(p)) sizes[p].push_back(largest_component(g, tau_on));
    start[p] = contact_start(sizes[p]);
    if (start[p] == sizes[p].size()) continue;
    out.contact_cells[p] = sizes[p].back();
    onset = std::max(onset, start[p]);
  }
  // A recording in which neither pad touches before the motion gives no quiet run it can vouch
  // for (the motion may be the grasp itself).
  if (out.contact_cells[0] == 0 && out.contact_cells[1] == 0) return out;
  out.quiet_frames = onset;
  // Frames before each pad's own last empty frame are noise for sure.
  for (std::size_t p = 0; p < 2; ++p) {
    const std::size_t end = std::min({onset, start[p], sizes[p].size()});
    for (std::size_t i = 0; i < end; ++i) out.largest = std::max(out.largest, sizes[p][i]);
  }
  // A pad whose components run without a gap into its contact, from before the other pad's
  // contact: its contact grows from the end of that run down to the noise's size, so the frames
  // before the last one no larger than the sure noise are noise too.
  const int sure = out.largest;
  for (std::size_t p = 0; p < 2; ++p) {
    std::size_t end = std::min(onset, sizes[p].size());
    if (start[p] >= end) continue;
    while (end > start[p] && sizes[p][end - 1] > sure) --end;
    for (std::size_t i = start[p]; i < end; ++i) out.largest = std::max(out.largest, sizes[p][i]);
  }
  return out;
}

}  // namespace tacse3::tools
