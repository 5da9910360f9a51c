// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: how much of the velocity proxy's rate persists once the object rests
// (tacse3-calibrate's label-free slide/stick assignment).
#pragma once

#include <Eigen/Geometry>
#include <vector>

namespace tacse3::tools {

// The mean |ω̄| over the frames at rest after the motion, over the mean |ω̄| while it moves. The
// velocity proxy reads shear as velocity: when a slide stops its shear relaxes (ratio ≈ 0); while
// the contact sticks the shear is the displacement and stays (ratio ≈ 1 or more).
//
// `truth` is the true orientation at each frame. The motion is told from the orientations, not
// from their rates: a robot log's pose noise (0.01° at 125 Hz), differentiated, is larger than 2 %
// of a 20° slide's peak rate, so a rate threshold would never see the rest. With P the largest
// angle from the first orientation, the motion runs from the first frame P/50 from the start to
// the last frame more than P/50 from the final orientation; the rest starts 12 frames (0.1 s at
// 120 Hz, the gel's relaxation) after it. -1 without motion, or with fewer than 6 frames at rest.
double rest_persistence(const std::vector<Eigen::Vector3d>& est,
                        const std::vector<Eigen::Quaterniond>& truth);

}  // namespace tacse3::tools
