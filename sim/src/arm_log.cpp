// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: a robot arm's TCP pose log with sampling jitter and pose noise.
#include "tacse3/sim/arm_log.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>

namespace tacse3::sim {

ArmLog::ArmLog(std::uint64_t seed, const RigidPose& tcp_to_grasp, const ArmSpec& spec)
    : spec_(spec), rng_(static_cast<std::mt19937::result_type>(seed)), tcp_g_(tcp_to_grasp) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double ax = u(rng_), ay = u(rng_), az = u(rng_);
  const Eigen::Vector3d axis(ax, ay, az);
  const double angle = 3.0 * u(rng_);
  world_g0_.q = Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
  const double px = u(rng_), py = u(rng_), pz = u(rng_);
  world_g0_.p = Eigen::Vector3d(0.4 + 0.1 * px, 0.2 * py, 0.3 + 0.1 * pz);
}

std::string ArmLog::gripper_log(const Truth& truth, std::int64_t from_ns, std::int64_t to_ns,
                                std::int64_t offset_ns, ArmLogFormat format) {
  return log(truth, from_ns, to_ns, offset_ns, format,
             [this](const RigidPose& m) { return world_g0_ * m.inverse() * tcp_g_.inverse(); });
}

std::string ArmLog::log(const Truth& truth, std::int64_t from_ns, std::int64_t to_ns,
                        std::int64_t offset_ns, ArmLogFormat format, const WorldPose& world_pose) {
  std::uniform_int_distribution<std::int64_t> jitter(-spec_.jitter_ns, spec_.jitter_ns);
  // Per axis, so that the 3-D error has the rms asked for.
  const double sp = spec_.noise_mm * 1e-3 / std::sqrt(3.0);
  const double sr = spec_.noise_deg * std::numbers::pi / 180.0 / std::sqrt(3.0);
  std::normal_distribution<double> np(0.0, sp > 0 ? sp : 1e-300), nr(0.0, sr > 0 ? sr : 1e-300);
  std::string s = format == ArmLogFormat::kRotationVector ? "t,x,y,z,rx,ry,rz,speed_scaling\n"
                  : format == ArmLogFormat::kQuaternionNs ? "t_ns,x,y,z,qw,qx,qy,qz\n"
                                                          : "t,x,y,z,qw,qx,qy,qz\n";
  const auto period = static_cast<std::int64_t>(std::llround(1e9 / spec_.rate_hz));
  const std::int64_t first = from_ns + offset_ns;
  const std::int64_t last = to_ns + offset_ns;
  char buf[320];
  for (std::int64_t k = 0;; ++k) {
    const std::int64_t t = first + k * period + jitter(rng_);
    if (t > last) break;
    RigidPose p = world_pose(truth(t - offset_ns));
    const double ex = np(rng_), ey = np(rng_), ez = np(rng_);
    p.p += Eigen::Vector3d(ex, ey, ez);
    const double rx = nr(rng_), ry = nr(rng_), rz = nr(rng_);
    const Eigen::Vector3d r(rx, ry, rz);
    const Eigen::Quaterniond dq =
        r.norm() > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(r.norm(), r.normalized()))
                     : Eigen::Quaterniond::Identity();
    p.q = (p.q * dq).normalized();
    if (format == ArmLogFormat::kRotationVector) {
      const Eigen::AngleAxisd aa(p.q);
      const Eigen::Vector3d v = aa.axis() * aa.angle();
      std::snprintf(buf, sizeof(buf), "%.9f,%.9f,%.9f,%.9f,%.12f,%.12f,%.12f,1.0\n",
                    static_cast<double>(t) * 1e-9, p.p.x(), p.p.y(), p.p.z(), v.x(), v.y(), v.z());
    } else if (format == ArmLogFormat::kQuaternionNs) {
      std::snprintf(buf, sizeof(buf), "%lld,%.9f,%.9f,%.9f,%.12f,%.12f,%.12f,%.12f\n",
                    static_cast<long long>(t), p.p.x(), p.p.y(), p.p.z(), p.q.w(), p.q.x(), p.q.y(),
                    p.q.z());
    } else {
      std::snprintf(buf, sizeof(buf), "%.9f,%.9f,%.9f,%.9f,%.12f,%.12f,%.12f,%.12f\n",
                    static_cast<double>(t) * 1e-9, p.p.x(), p.p.y(), p.p.z(), p.q.w(), p.q.x(),
                    p.q.y(), p.q.z());
    }
    s += buf;
  }
  return s;
}

}  // namespace tacse3::sim
