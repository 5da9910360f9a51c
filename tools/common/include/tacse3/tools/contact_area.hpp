// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the contact mask's minimum area, from the noise's own components before contact
// (tacse3-calibrate).
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "tacse3/dsp/types.hpp"

namespace tacse3::tools {

// One pad's filter(f^z) on the flow grid, NaN where the grid point is not valid.
using FzGrid = std::array<float, static_cast<std::size_t>(dsp::kGridCount)>;

// Size of the largest 4-connected component of grid points with f^z above tau_on: what the
// contact mask's minimum-area rule (dsp::ContactDetector) sees in a frame with no mask before it.
int largest_component(const FzGrid& fz, double tau_on) noexcept;

// The first frame of the contact that holds at the end of `sizes` (one pad's largest component
// per frame, the last frame just before the motion): the frame after the last one with no
// component. A grasp's area grows and may overshoot and settle, but it does not vanish while the
// grasp holds. Returns sizes.size() when the last frame has no component (no contact).
std::size_t contact_start(const std::vector<int>& sizes) noexcept;

// The frames of one recording before its motion starts, both pads, for the area fit.
class PreMotionFz {
 public:
  void add(std::size_t pad, const FzGrid& fz) { frames_[pad].push_back(fz); }
  const std::vector<FzGrid>& frames(std::size_t pad) const noexcept { return frames_[pad]; }

 private:
  std::array<std::vector<FzGrid>, 2> frames_;
};

// What one recording says about the noise's components at tau_on.
struct NoiseComponents {
  std::size_t quiet_frames = 0;  // frames before the grasp's contact, per pad
  int largest = 0;               // the largest component in them, either pad
  // Each pad's contact at the motion start (its largest component in the last frame; 0: none).
  std::array<int, 2> contact_cells{0, 0};
};

// The quiet frames end where the later pad's contact starts (contact_start): a grasp closes on
// both pads within a few frames, so noise in one pad that runs into its contact is still told
// apart by the other pad. Within such a run, the frames from the last one no larger than the
// noise seen elsewhere are taken as the contact's growth; a noise component larger than that
// which runs straight into the contact is counted as contact.
NoiseComponents noise_components(const PreMotionFz& fz, double tau_on);

}  // namespace tacse3::tools
