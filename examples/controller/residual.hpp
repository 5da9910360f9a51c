// SPDX-License-Identifier: Apache-2.0
// tacse3 example: the paper's residual post-processor a_corr = a_base + Gamma * theta_hat.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "tacse3/protocol/codec.hpp"

namespace tacse3::example {

using protocol::Quaternion;
using protocol::Vec3;

inline Quaternion conjugate(const Quaternion& q) {
  return {q.w, -q.x, -q.y, -q.z};
}

inline Quaternion multiply(const Quaternion& a, const Quaternion& b) {
  return {
      a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
      a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

inline Quaternion normalized(const Quaternion& q) {
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}

// Rotation vector (axis * angle, |angle| <= pi) of a unit quaternion: the SO(3) logarithm.
inline Vec3 log_map(Quaternion q) {
  if (q.w < 0.0) q = {-q.w, -q.x, -q.y, -q.z};  // shortest rotation
  const double s = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
  // angle / s = 2 atan2(s, w) / s, which tends to 2 / w as s -> 0.
  const double k = s < 1e-9 ? 2.0 / q.w : 2.0 * std::atan2(s, q.w) / s;
  return {k * q.x, k * q.y, k * q.z};
}

enum class ThetaSource : std::uint8_t {
  kPose,   // theta_hat from the orientation frames: log(q_now * q_last_step^-1), in G
  kTwist,  // theta_hat = sum of omega * dt over the cycles since the last step, in G
};

// The post-processor of the paper's policy experiment (Sec. V, "Rotation Output as a
// Post-Processor under an Existing Policy"): a_corr_t = a_base_t + Gamma * theta_hat_t, where
// theta_hat_t is the object's incremental rotation since the previous control step and Gamma
// (N x 3) maps it into the policy's action space. The controller may run at any rate: observe()
// every decoded cycle, step() once per control step.
template <std::size_t N>
class ResidualPostProcessor {
 public:
  using Action = std::array<double, N>;
  using Gamma = std::array<std::array<double, 3>, N>;

  struct Config {
    Gamma gamma{};
    ThetaSource source = ThetaSource::kPose;
    double max_step_angle_rad = 0.2;    // |theta_hat| is clamped to this (safety)
    std::uint64_t max_gap_us = 100000;  // twist source: a longer gap between cycles is skipped
  };

  explicit ResidualPostProcessor(const Config& c) : config_(c) {}

  // Feed every complete cycle. Cycles without a valid estimate or orientation are ignored. A
  // pose reset (tare / reset pose) is a jump of the pose, not a motion: the increment is cut
  // there and restarted from the reset pose.
  void observe(const protocol::Cycle& c) {
    if (!c.estimate_valid) return;
    if (config_.source == ThetaSource::kTwist) {
      if (!protocol::all_finite(c.angular)) return;
      if (have_time_ && c.timestamp_us > last_time_us_ &&
          c.timestamp_us - last_time_us_ <= config_.max_gap_us) {
        const double dt = static_cast<double>(c.timestamp_us - last_time_us_) * 1e-6;
        pending_.x += c.angular.x * dt;
        pending_.y += c.angular.y * dt;
        pending_.z += c.angular.z * dt;
      }
      have_time_ = true;
      last_time_us_ = c.timestamp_us;
      return;
    }
    if (!protocol::all_finite(c.orientation)) return;
    const Quaternion q = normalized(c.orientation);
    if (!have_ref_) {
      reference_ = latest_ = q;
      have_ref_ = true;
      return;
    }
    if (c.pose_reset) {
      accumulate(log_map(multiply(latest_, conjugate(reference_))));
      reference_ = q;
    }
    latest_ = q;
  }

  // theta_hat since the previous call, clamped to max_step_angle_rad; restarts the increment.
  Vec3 take_increment() {
    Vec3 t = pending_;
    if (config_.source == ThetaSource::kPose && have_ref_) {
      const Vec3 d = log_map(multiply(latest_, conjugate(reference_)));
      t = {t.x + d.x, t.y + d.y, t.z + d.z};
      reference_ = latest_;
    }
    pending_ = Vec3{};
    const double angle = std::sqrt(t.x * t.x + t.y * t.y + t.z * t.z);
    if (angle > config_.max_step_angle_rad) {
      const double k = config_.max_step_angle_rad / angle;
      t = {t.x * k, t.y * k, t.z * k};
      ++clamped_;
    }
    return t;
  }

  // a_corr = a_base + Gamma * theta.
  Action correct(const Action& a_base, const Vec3& theta) const {
    Action a = a_base;
    for (std::size_t i = 0; i < N; ++i) {
      a[i] += config_.gamma[i][0] * theta.x + config_.gamma[i][1] * theta.y +
              config_.gamma[i][2] * theta.z;
    }
    return a;
  }

  // One control step: theta_hat since the last step, applied to the nominal action.
  Action step(const Action& a_base, Vec3* theta_out = nullptr) {
    const Vec3 t = take_increment();
    if (theta_out != nullptr) *theta_out = t;
    return correct(a_base, t);
  }

  std::uint64_t clamped_steps() const { return clamped_; }

 private:
  void accumulate(const Vec3& d) {
    pending_ = {pending_.x + d.x, pending_.y + d.y, pending_.z + d.z};
  }

  Config config_;
  bool have_ref_ = false;
  Quaternion reference_;
  Quaternion latest_;
  Vec3 pending_;
  bool have_time_ = false;
  std::uint64_t last_time_us_ = 0;
  std::uint64_t clamped_ = 0;
};

}  // namespace tacse3::example
