// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: synthetic dual-pad grasp sequences (indentation bulge + rigid object motion).
#pragma once

#include <cstdint>
#include <vector>

#include "support/synthetic.hpp"
#include "tacse3/dsp/se3.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::test {

// A grasp followed by a small rigid motion of the object in the gripper frame G, seen by both
// mirrored pads while the gel sticks (so the gel surface inside each contact patch follows the
// object's surface points exactly). Per pad, in sensor pixels:
//   u(m) = bulge(m) + s(m) · (x(m) − m)
// where bulge is the radial in-plane push-out of the indentation (grows during the grasp), x(m)
// is where the object's rigid motion carries the contact point seen at m (projected on the pad),
// and s is 1 inside the patch and decays smoothly outside it (elastic spreading).
struct GraspScene {
  double pixel_pitch_m = 0.075e-3;
  double separation_m = 0.030;                    // W, distance between the pad surfaces
  double patch_radius_px = 36.0;                  // contact patch radius, sensor px
  double spread_px = 14.0;                        // decay length of the field outside the patch
  double bulge_px = 1.2;                          // peak radial push-out of the indentation
  std::array<double, 2> centre_px{159.5, 119.5};  // patch centre on the left pad (image px)
  int grasp_frames = 8;                           // indentation ramps up
  int motion_frames = 24;                         // then the object moves (smooth-step profile)
  int hold_frames = 8;
  dsp::Vector6d motion = dsp::Vector6d::Zero();  // total rigid motion [φ; ρ] of the object in G
  double fps = 120.0;
  std::uint64_t seed = 7;
};

// Object pose in G at frame i (identity before the motion starts).
dsp::Pose scene_pose(const GraspScene& s, int frame);
int scene_frames(const GraspScene& s);

// Renders frame `frame` of pad 0 (left) or 1 (right) as RGB888 320x240.
std::vector<std::uint8_t> render_scene_frame(const GraspScene& s, const DotTexture& texture,
                                             int pad, int frame, const Photometric& ph = {});

}  // namespace tacse3::test
