// SPDX-License-Identifier: Apache-2.0
// tacse3-truth tests: a simulated robot rig. From a recording's truth it writes the log a robot
// would have taken: a random world pose, a TCP offset, 125 Hz with +-1 ms jitter, a clock offset,
// pose noise of a real arm (rms 0.05 mm and 0.01 deg per sample).
#pragma once

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "tacse3/fileio/file_io.hpp"
#include "tacse3/tools/bench.hpp"
#include "tacse3/tools/metrics.hpp"
#include "tacse3/tools/truth/pose_log.hpp"

namespace tacse3::tools::truth_test {

namespace tr = tacse3::tools::truth;

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

class RigLog {
 public:
  explicit RigLog(unsigned seed, double noise_scale = 1.0) : rng_(seed), noise_scale_(noise_scale) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const Eigen::Vector3d axis(u(rng_), u(rng_), u(rng_));
    world_g0_.q = Eigen::Quaterniond(Eigen::AngleAxisd(3.0 * u(rng_), axis.normalized()));
    world_g0_.p = Eigen::Vector3d(0.4 + 0.1 * u(rng_), 0.2 * u(rng_), 0.3 + 0.1 * u(rng_));
    tcp_g_.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1, 0).normalized()));
    tcp_g_.p = Eigen::Vector3d(0.01, -0.005, 0.16);  // G 16 cm along the flange's axis
  }

  std::string tcp_to_grasp_text() const { return text(tcp_g_); }
  // The fixed TCP for the object-log rig.
  std::string fixed_tcp_text() const { return text(world_g0_ * tr::inverse(tcp_g_)); }

  // Gripper moves, object still: T_w,tcp(t) = T_wg0 truth(t)^-1 T_tcp,g^-1.
  std::string write_gripper_log(const std::vector<recording::TruthSample>& truth,
                                const std::vector<std::int64_t>& t_ns, std::int64_t offset_ns,
                                const std::filesystem::path& file, bool rotation_vector) {
    return write(truth, t_ns, offset_ns, file, rotation_vector, [&](const tr::Pose& m) {
      return world_g0_ * tr::inverse(m) * tr::inverse(tcp_g_);
    });
  }
  // Gripper still at T_wg0, object moved: T_wo(t) = T_wg0 truth(t) T_wg0^-1 T_wo0.
  std::string write_object_log(const std::vector<recording::TruthSample>& truth,
                               const std::vector<std::int64_t>& t_ns, std::int64_t offset_ns,
                               const std::filesystem::path& file) {
    tr::Pose wo0;
    wo0.p = world_g0_.p + Eigen::Vector3d(0.001, 0.002, -0.003);
    wo0.q = Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitY()));
    return write(truth, t_ns, offset_ns, file, false,
                 [&](const tr::Pose& m) { return world_g0_ * m * tr::inverse(world_g0_) * wo0; });
  }

 private:
  static std::string text(const tr::Pose& p) {
    char buf[256];
    std::snprintf(buf, sizeof(buf), "%.12f %.12f %.12f %.15f %.15f %.15f %.15f", p.p.x(), p.p.y(),
                  p.p.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z());
    return buf;
  }

  template <class F>
  std::string write(const std::vector<recording::TruthSample>& truth,
                    const std::vector<std::int64_t>& t_ns, std::int64_t offset_ns,
                    const std::filesystem::path& file, bool rotation_vector, F world_pose) {
    std::uniform_int_distribution<std::int64_t> jitter(-1'000'000, 1'000'000);
    const double sp = noise_scale_ * kNoiseMm * 1e-3 / std::sqrt(3.0);
    const double sr = noise_scale_ * kNoiseDeg * std::numbers::pi / 180.0 / std::sqrt(3.0);
    std::normal_distribution<double> np(0.0, sp > 0 ? sp : 1e-300), nr(0.0, sr > 0 ? sr : 1e-300);
    std::string s = rotation_vector ? "t,x,y,z,rx,ry,rz,speed_scaling\n" : "t,x,y,z,qw,qx,qy,qz\n";
    // From 1.5 s before the first frame to 1.5 s after the last, on the robot's clock.
    const std::int64_t first = t_ns.front() + offset_ns - 1'500'000'000;
    const std::int64_t last = t_ns.back() + offset_ns + 1'500'000'000;
    char buf[320];
    for (std::int64_t k = 0;; ++k) {
      const std::int64_t t = first + k * 8'000'000 + jitter(rng_);
      if (t > last) break;
      const dsp::Pose m = truth_pose_at(truth, t - offset_ns);
      tr::Pose p = world_pose(tr::Pose{m.q, m.p});
      p.p += Eigen::Vector3d(np(rng_), np(rng_), np(rng_));
      p.q = (p.q * tr::from_rotation_vector(Eigen::Vector3d(nr(rng_), nr(rng_), nr(rng_))))
                .normalized();
      const double ts = static_cast<double>(t) * 1e-9;
      if (rotation_vector) {
        const Eigen::AngleAxisd aa(p.q);
        const Eigen::Vector3d r = aa.axis() * aa.angle();
        std::snprintf(buf, sizeof(buf), "%.9f,%.9f,%.9f,%.9f,%.12f,%.12f,%.12f,1.0\n", ts, p.p.x(),
                      p.p.y(), p.p.z(), r.x(), r.y(), r.z());
      } else {
        std::snprintf(buf, sizeof(buf), "%.9f,%.9f,%.9f,%.9f,%.12f,%.12f,%.12f,%.12f\n", ts,
                      p.p.x(), p.p.y(), p.p.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z());
      }
      s += buf;
    }
    std::string err;
    return fileio::write_file_atomically(file, s, &err) ? std::string() : err;
  }

  std::mt19937 rng_;
  double noise_scale_;
  tr::Pose world_g0_;
  tr::Pose tcp_g_;
};

}  // namespace tacse3::tools::truth_test
