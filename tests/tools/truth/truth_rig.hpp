// SPDX-License-Identifier: Apache-2.0
// tacse3-truth tests: a simulated robot rig. From a recording's truth it writes the log a robot
// would have taken (sim::ArmLog): a random world pose, a TCP offset, 125 Hz with +-1 ms jitter, a
// clock offset, pose noise of a real arm (rms 0.05 mm and 0.01 deg per sample).
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "tacse3/fileio/file_io.hpp"
#include "tacse3/sim/arm_log.hpp"
#include "tacse3/tools/bench.hpp"
#include "tacse3/tools/metrics.hpp"
#include "tacse3/tools/truth/pose_log.hpp"

namespace tacse3::tools::truth_test {

namespace sim = tacse3::sim;

// Two short stick-regime grasps, a turn about G's z and one about its x (~1.3 s each).
inline std::vector<SimCase> cases() {
  std::vector<SimCase> out;
  for (const char* m : {"rz", "rx"}) {
    SimCase c;
    c.object = "sphere";
    c.motion = m;
    c.magnitude = 4.0;  // the simulator's auto regime: stick up to 5 deg
    c.approach_s = 0.05;
    c.grasp_s = 0.25;
    c.settle_s = 0.1;
    c.hold_s = 0.2;
    out.push_back(c);
  }
  return out;
}

inline constexpr double kNoiseMm = 0.05;   // rms of a logged position's error
inline constexpr double kNoiseDeg = 0.01;  // rms of a logged orientation's error

// sim::ArmLog (the simulated rig's robot of tacse3d, too) over a recording's truth samples.
class RigLog {
 public:
  explicit RigLog(unsigned seed, double noise_scale = 1.0)
      : arm_(seed, tcp_to_grasp(), spec(noise_scale)) {}

  std::string tcp_to_grasp_text() const { return text(arm_.tcp_to_grasp()); }
  // The fixed TCP for the object-log rig.
  std::string fixed_tcp_text() const {
    return text(arm_.world_to_grasp0() * arm_.tcp_to_grasp().inverse());
  }

  // Gripper moves, object still: T_w,tcp(t) = T_wg0 truth(t)^-1 T_tcp,g^-1.
  std::string write_gripper_log(const std::vector<recording::TruthSample>& truth,
                                const std::vector<std::int64_t>& t_ns, std::int64_t offset_ns,
                                const std::filesystem::path& file, bool rotation_vector) {
    return save(file, arm_.gripper_log(at(truth), t_ns.front() - kMarginNs, t_ns.back() + kMarginNs,
                                       offset_ns, format(rotation_vector)));
  }
  // Gripper still at T_wg0, object moved: T_wo(t) = T_wg0 truth(t) T_wg0^-1 T_wo0.
  std::string write_object_log(const std::vector<recording::TruthSample>& truth,
                               const std::vector<std::int64_t>& t_ns, std::int64_t offset_ns,
                               const std::filesystem::path& file) {
    sim::RigidPose wo0;
    wo0.p = arm_.world_to_grasp0().p + Eigen::Vector3d(0.001, 0.002, -0.003);
    wo0.q = Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitY()));
    const sim::RigidPose wg0 = arm_.world_to_grasp0();
    return save(file,
                arm_.log(at(truth), t_ns.front() - kMarginNs, t_ns.back() + kMarginNs, offset_ns,
                         sim::ArmLogFormat::kQuaternion,
                         [&](const sim::RigidPose& m) { return wg0 * m * wg0.inverse() * wo0; }));
  }

 private:
  // The log runs from 1.5 s before the first frame to 1.5 s after the last.
  static constexpr std::int64_t kMarginNs = 1'500'000'000;

  static sim::RigidPose tcp_to_grasp() {
    sim::RigidPose g;  // G 16 cm along the flange's axis, tilted 17 deg
    g.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1, 0).normalized()));
    g.p = Eigen::Vector3d(0.01, -0.005, 0.16);
    return g;
  }
  static sim::ArmSpec spec(double noise_scale) {
    sim::ArmSpec s;
    s.noise_mm = noise_scale * kNoiseMm;
    s.noise_deg = noise_scale * kNoiseDeg;
    return s;
  }
  static sim::ArmLogFormat format(bool rotation_vector) {
    return rotation_vector ? sim::ArmLogFormat::kRotationVector : sim::ArmLogFormat::kQuaternion;
  }
  static sim::ArmLog::Truth at(const std::vector<recording::TruthSample>& truth) {
    return [&truth](std::int64_t t) {
      const dsp::Pose m = truth_pose_at(truth, t);
      return sim::RigidPose{m.q, m.p};
    };
  }
  static std::string text(const sim::RigidPose& p) {
    char buf[256];
    std::snprintf(buf, sizeof(buf), "%.12f %.12f %.12f %.15f %.15f %.15f %.15f", p.p.x(), p.p.y(),
                  p.p.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z());
    return buf;
  }
  static std::string save(const std::filesystem::path& file, const std::string& s) {
    std::string err;
    return fileio::write_file_atomically(file, s, &err) ? std::string() : err;
  }

  sim::ArmLog arm_;
};

}  // namespace tacse3::tools::truth_test
