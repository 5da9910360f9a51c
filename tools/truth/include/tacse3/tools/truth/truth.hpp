// SPDX-License-Identifier: Apache-2.0
// tacse3-truth: the object's pose in the grasp frame G from robot pose logs (docs/truth.md).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "tacse3/recording/recording.hpp"
#include "tacse3/tools/truth/pose_log.hpp"

namespace tacse3::tools::truth {

// What moves. T_wg(t) = T_w,tcp(t) T_tcp,g; with no gripper log the TCP stays at fixed_tcp.
// With no object log the object stays still in the world.
struct Rig {
  const PoseLog* gripper = nullptr;  // TCP pose in the world over time
  const PoseLog* object = nullptr;   // object pose in the world over time
  Pose tcp_to_grasp;                 // G in the TCP frame
  Pose fixed_tcp;                    // TCP in the world when the gripper does not move
};

// The object's pose in G relative to the first frame at each frame time (recording clock), the
// logs read at t + offset_ns:
//   truth(t) = T_wg(t)^-1 T_wo(t) T_wo(t0)^-1 T_wg(t0).
// Quaternions are kept sign-continuous from the identity. Returns "" or an error naming the log
// that does not cover the recording.
std::string make_truth(const Rig& rig, const std::vector<std::int64_t>& frame_t_ns,
                       std::int64_t offset_ns, std::vector<recording::TruthSample>* out);

// truth.csv text in the documented format (docs/recording-format.md).
std::string truth_csv(const std::vector<recording::TruthSample>& rows);

}  // namespace tacse3::tools::truth
