// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: pays back, at a detected slip onset, what the velocity proxy read during the stick.
#pragma once

#include "tacse3/dsp/se3.hpp"  // Vector6d

namespace tacse3::dsp {

// kAuto (docs/dsp/motion.md). The stick/slip detector recognises a slide only once its shear
// relaxes, so the first part of every slide is read with the displacement proxy. Beside the
// fused twist of the chosen proxies, the dual pipeline fuses the same frame read with the
// velocity proxy; the difference, integrated (the deficit D, [rad; m] in G), is what kVelocity
// would have added to the pose. At a slip onset D is paid back over k = slip_catchup_frames
// frames (D/left per frame, so the pose catches up without a jump); once every sensor in contact
// has confirmed its stick, D is dropped, unless a payback is under way (the slide was detected).
// Keeping D in the fused twist, not per grid cell, makes the payback exactly the integral of what
// was missed, whatever Ω and its levers did meanwhile.
// Scaling: all in double (SI); D is bounded by what the fused twists can reach (finite inputs).
class SlipPayback {
 public:
  // Frames over which a payback is spread, ≥ 1 (clamped).
  void configure(int catchup_frames) noexcept;
  void reset() noexcept;

  struct Frame {
    Vector6d chosen = Vector6d::Zero();    // fused twist of the chosen proxies (0 if invalid)
    Vector6d velocity = Vector6d::Zero();  // fused twist of the velocity readings (0 if invalid)
    bool differs = false;    // some sensor stuck this frame: `velocity` is a different reading
    bool contact = false;    // some sensor sees contact
    bool onset = false;      // some sensor's detector switched to slip this frame
    bool confirmed = false;  // every sensor in contact confirmed its stick this frame
  };
  // The twist to use this frame: `chosen` plus this frame's share of the payback (rad/s, m/s).
  // dt_s: finite, > 0. No contact: D is dropped.
  Vector6d update(const Frame& f, double dt_s) noexcept;

  const Vector6d& deficit() const noexcept { return deficit_; }
  int frames_left() const noexcept { return left_; }

 private:
  int catchup_frames_ = 1;
  int left_ = 0;
  Vector6d deficit_ = Vector6d::Zero();
};

}  // namespace tacse3::dsp
