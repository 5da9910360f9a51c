// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: scenario timeline, indentation schedule and analytic truth trajectory.
#include "tacse3/sim/scenario.hpp"

#include <cmath>
#include <numbers>

namespace tacse3::sim {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

bool finite_in(double v, double lo, double hi) {
  return std::isfinite(v) && v >= lo && v <= hi;
}

}  // namespace

const char* to_string(MotionAxis a) noexcept {
  switch (a) {
    case MotionAxis::kRx:
      return "rx";
    case MotionAxis::kRy:
      return "ry";
    case MotionAxis::kRz:
      return "rz";
    case MotionAxis::kTx:
      return "tx";
    case MotionAxis::kTy:
      return "ty";
  }
  return "unknown";
}

const char* to_string(Regime r) noexcept {
  switch (r) {
    case Regime::kStick:
      return "stick";
    case Regime::kSlide:
      return "slide";
    case Regime::kAuto:
      return "auto";
  }
  return "unknown";
}

const char* to_string(Phase p) noexcept {
  switch (p) {
    case Phase::kApproach:
      return "approach";
    case Phase::kGrasp:
      return "grasp";
    case Phase::kSettle:
      return "settle";
    case Phase::kMotion:
      return "motion";
    case Phase::kHold:
      return "hold";
    case Phase::kRelease:
      return "release";
  }
  return "unknown";
}

bool parse_axis(std::string_view s, MotionAxis* out) noexcept {
  for (int i = 0; i <= static_cast<int>(MotionAxis::kTy); ++i) {
    if (s == to_string(static_cast<MotionAxis>(i))) {
      *out = static_cast<MotionAxis>(i);
      return true;
    }
  }
  return false;
}

bool parse_regime(std::string_view s, Regime* out) noexcept {
  for (int i = 0; i <= static_cast<int>(Regime::kAuto); ++i) {
    if (s == to_string(static_cast<Regime>(i))) {
      *out = static_cast<Regime>(i);
      return true;
    }
  }
  return false;
}

std::string validate(const ScenarioSpec& s) {
  if (std::string e = validate(s.object); !e.empty()) return e;
  if (static_cast<int>(s.axis) > static_cast<int>(MotionAxis::kTy)) return "unknown motion axis";
  if (static_cast<int>(s.regime) > static_cast<int>(Regime::kAuto)) return "unknown regime";
  if (is_rotation(s.axis) ? !finite_in(s.magnitude, -360.0, 360.0)
                          : !finite_in(s.magnitude, -50.0, 50.0)) {
    return "motion magnitude must be within +-360 deg (rotations) or +-50 mm (translations)";
  }
  if (!finite_in(s.indentation_mm, 0.05, 5.0)) return "indentation_mm must be in [0.05, 5]";
  if (!finite_in(s.approach_gap_mm, 0.0, 20.0)) return "approach_gap_mm must be in [0, 20]";
  if (!finite_in(s.approach_s, 0.0, 60.0)) return "approach_s must be in [0, 60]";
  if (!finite_in(s.grasp_s, 0.01, 60.0)) return "grasp_s must be in [0.01, 60]";
  if (!finite_in(s.settle_s, 0.0, 60.0)) return "settle_s must be in [0, 60]";
  if (!finite_in(s.motion_s, 0.0, 600.0)) return "motion_s must be in [0, 600] (0 = auto)";
  if (!finite_in(s.hold_s, 0.0, 600.0)) return "hold_s must be in [0, 600]";
  if (!finite_in(s.release_s, 0.0, 60.0)) return "release_s must be in [0, 60]";
  if (!finite_in(s.fps, 1.0, 10000.0)) return "fps must be in [1, 10000]";
  return {};
}

Scenario::Scenario(const ScenarioSpec& spec) noexcept : spec_(spec), object_(spec.object) {
  const bool rot = is_rotation(spec.axis);
  const double mag = std::abs(spec.magnitude);
  switch (spec.regime) {
    case Regime::kStick:
      sliding_ = false;
      break;
    case Regime::kSlide:
      sliding_ = true;
      break;
    case Regime::kAuto:
      sliding_ = rot ? mag > kAutoStickMaxDeg : mag > kAutoStickMaxMm;
      break;
  }
  motion_s_ = spec.motion_s > 0.0 ? spec.motion_s : 0.5 + (rot ? mag / 60.0 : mag / 20.0);
  switch (spec.axis) {
    case MotionAxis::kRx:
    case MotionAxis::kTx:
      axis_ = Eigen::Vector3d::UnitX();
      break;
    case MotionAxis::kRy:
    case MotionAxis::kTy:
      axis_ = Eigen::Vector3d::UnitY();
      break;
    case MotionAxis::kRz:
      axis_ = Eigen::Vector3d::UnitZ();
      break;
  }
  amount_ = rot ? spec.magnitude * kDeg : spec.magnitude;
  if (!rot && spec.centre_translation) {
    object_.offset_mm -= 0.5 * spec.magnitude * axis_.head<2>();
  }
  t_grasp_ = spec.approach_s;
  t_settle_ = t_grasp_ + spec.grasp_s;
  t_motion_ = t_settle_ + spec.settle_s;
  t_hold_ = t_motion_ + motion_s_;
  t_release_ = t_hold_ + spec.hold_s;
  duration_ = t_release_ + spec.release_s;
  frames_ = static_cast<int>(std::llround(duration_ * spec.fps));
  if (frames_ < 1) frames_ = 1;
}

std::int64_t Scenario::frame_time_ns(int index) const noexcept {
  return std::llround(static_cast<double>(index) * 1e9 / spec_.fps);
}

double Scenario::local_time(double t) const noexcept {
  if (t < 0.0) return 0.0;
  if (spec_.loop && duration_ > 0.0) return std::fmod(t, duration_);
  return t;
}

Phase Scenario::phase(double t) const noexcept {
  t = local_time(t);
  if (t < t_grasp_) return Phase::kApproach;
  if (t < t_settle_) return Phase::kGrasp;
  if (t < t_motion_) return Phase::kSettle;
  if (t < t_hold_) return Phase::kMotion;
  if (t < t_release_ || spec_.release_s <= 0.0) return Phase::kHold;
  return Phase::kRelease;
}

double Scenario::indentation_mm(double t) const noexcept {
  t = local_time(t);
  const double open = -spec_.approach_gap_mm;
  const double closed = spec_.indentation_mm;
  if (t < t_grasp_) return open;
  if (t < t_settle_) return open + (closed - open) * min_jerk((t - t_grasp_) / spec_.grasp_s);
  if (spec_.release_s <= 0.0 || t < t_release_) return closed;
  return closed + (open - closed) * min_jerk((t - t_release_) / spec_.release_s);
}

double Scenario::progress(double t) const noexcept {
  return min_jerk((local_time(t) - t_motion_) / motion_s_);
}

double Scenario::progress_rate(double t) const noexcept {
  return min_jerk_rate((local_time(t) - t_motion_) / motion_s_) / motion_s_;
}

Pose Scenario::pose(double t) const noexcept {
  Pose p;
  const double s = progress(t);
  if (is_rotation(spec_.axis)) {
    p.q = Eigen::Quaterniond(Eigen::AngleAxisd(amount_ * s, axis_));
  } else {
    p.p = amount_ * s * axis_;
  }
  return p;
}

Twist Scenario::twist(double t) const noexcept {
  Twist tw;
  const double rate = amount_ * progress_rate(t);
  if (is_rotation(spec_.axis)) {
    tw.w = rate * axis_;  // rotation about G's origin: point velocity w x g
  } else {
    tw.v = rate * axis_;
  }
  return tw;
}

}  // namespace tacse3::sim
