// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: the pose log a robot arm takes of its TCP (docs/truth.md, "Log format"), made from
// the object's exact pose in the grasp frame G.
#pragma once

#include <cstdint>
#include <functional>
#include <random>
#include <string>

#include "tacse3/sim/types.hpp"

namespace tacse3::sim {

// A rigid pose in metres: it maps coordinates in its own frame to those of its parent frame,
// x = q * x' + p.
struct RigidPose {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();

  RigidPose operator*(const RigidPose& b) const noexcept { return {q * b.q, q * b.p + p}; }
  RigidPose inverse() const noexcept {
    const Eigen::Quaterniond qi = q.conjugate();
    return {qi, -(qi * p)};
  }
};

// What an arm's log looks like: its sampling and its pose error (a UR-class arm: 125 Hz with
// +-1 ms of jitter, repeatability of a few hundredths of a millimetre).
struct ArmSpec {
  double rate_hz = 125.0;
  std::int64_t jitter_ns = 1'000'000;  // each sample uniformly within +-jitter of its slot
  double noise_mm = 0.05;              // rms of a logged position's error (3-D)
  double noise_deg = 0.01;             // rms of a logged orientation's error (3-D)
};

enum class ArmLogFormat : std::uint8_t {
  kQuaternion,      // t (s), x, y, z, qw, qx, qy, qz
  kRotationVector,  // t (s), x, y, z, rx, ry, rz, speed_scaling (a UR controller's columns)
  kQuaternionNs,    // t_ns, x, y, z, qw, qx, qy, qz (integer time: exact on any clock's epoch)
};

// The robot of the object-clamped rig: the object is still in the world and the arm moves the
// gripper, so T_world,G(t) = T_world,G0 * truth(t)^-1 and the logged TCP pose is
// T_world,G(t) * T_tcp,G^-1. The world pose of G at the first frame is drawn from the seed
// (any orientation, 0.3-0.5 m in front of the robot); the same seed gives the same log.
class ArmLog {
 public:
  ArmLog(std::uint64_t seed, const RigidPose& tcp_to_grasp, const ArmSpec& spec = {});

  const RigidPose& world_to_grasp0() const noexcept { return world_g0_; }
  const RigidPose& tcp_to_grasp() const noexcept { return tcp_g_; }

  // The object's pose in G relative to the first frame (metres) at a time on the board's clock.
  using Truth = std::function<RigidPose(std::int64_t board_ns)>;
  // The logged pose in the world of the object's pose in G (what the arm holds).
  using WorldPose = std::function<RigidPose(const RigidPose& truth)>;

  // The CSV text (header included) of the gripper's TCP log from board time from_ns to to_ns;
  // sample times are on the arm's clock: board time + offset_ns.
  std::string gripper_log(const Truth& truth, std::int64_t from_ns, std::int64_t to_ns,
                          std::int64_t offset_ns, ArmLogFormat format);
  // The same with any world pose of the truth (a second arm moving the object, ...).
  std::string log(const Truth& truth, std::int64_t from_ns, std::int64_t to_ns,
                  std::int64_t offset_ns, ArmLogFormat format, const WorldPose& world_pose);

 private:
  ArmSpec spec_;
  std::mt19937 rng_;
  RigidPose world_g0_;
  RigidPose tcp_g_;
};

}  // namespace tacse3::sim
