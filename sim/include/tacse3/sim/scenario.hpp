// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: grasp scenario (phases, indentation schedule, commanded motion) and exact truth.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "tacse3/sim/object.hpp"
#include "tacse3/sim/types.hpp"

namespace tacse3::sim {

// Commanded motion of the object in G: rotation about, or translation along, a G axis through
// the grasp centre (G's origin).
enum class MotionAxis : std::uint8_t { kRx = 0, kRy, kRz, kTx, kTy };
// Tangential contact regime (docs/simulator.md, "Tangential response").
enum class Regime : std::uint8_t { kStick = 0, kSlide, kAuto };
enum class Phase : std::uint8_t { kApproach = 0, kGrasp, kSettle, kMotion, kHold, kRelease };

const char* to_string(MotionAxis a) noexcept;
const char* to_string(Regime r) noexcept;
const char* to_string(Phase p) noexcept;
bool parse_axis(std::string_view s, MotionAxis* out) noexcept;
bool parse_regime(std::string_view s, Regime* out) noexcept;
constexpr bool is_rotation(MotionAxis a) noexcept {
  return a == MotionAxis::kRx || a == MotionAxis::kRy || a == MotionAxis::kRz;
}

// Regime::kAuto picks stick for motions up to these magnitudes, slide above.
inline constexpr double kAutoStickMaxDeg = 5.0;
inline constexpr double kAutoStickMaxMm = 1.0;

struct ScenarioSpec {
  ObjectSpec object;
  MotionAxis axis = MotionAxis::kRz;
  double magnitude = 30.0;  // degrees for rotations, millimetres for translations; sign = direction
  Regime regime = Regime::kAuto;
  double indentation_mm = 1.0;   // peak gel indentation held after the grasp
  double approach_gap_mm = 0.5;  // pad-to-object gap while the pads are open
  double approach_s = 0.1;       // pads open, no contact (a clean reference for tare)
  double grasp_s = 0.4;          // pads close; indentation ramps -gap -> indentation
  double settle_s = 0.1;         // static grasp before the motion
  double motion_s = 0.0;         // 0 = auto: 0.5 s + |angle|/(60 deg/s) or + |d|/(20 mm/s)
  double hold_s = 0.4;           // static after the motion
  double release_s = 0.0;        // pads open again at the end (useful with loop)
  bool loop = false;             // repeat the whole timeline forever (live backend)
  double fps = 120.0;
  // Translations start at -magnitude/2 along their axis so the patch sweeps across the pad
  // centre instead of running off the edge. The truth is relative to the first frame either way.
  bool centre_translation = true;
};

// Empty string if usable, else a message naming the field.
std::string validate(const ScenarioSpec& spec);

// Pure function of time: everything here is analytic, so it is the ground truth. Times in
// seconds from the first frame (t = 0). With loop, t wraps modulo duration_s().
class Scenario {
 public:
  explicit Scenario(const ScenarioSpec& spec) noexcept;  // precondition: validate(spec) empty

  const ScenarioSpec& spec() const noexcept { return spec_; }
  // The object as simulated (centre_translation applied to its offset).
  const ObjectSpec& object() const noexcept { return object_; }
  bool sliding() const noexcept { return sliding_; }  // effective regime after kAuto

  double motion_duration_s() const noexcept { return motion_s_; }
  double motion_start_s() const noexcept { return t_motion_; }
  double motion_end_s() const noexcept { return t_hold_; }
  double grasp_end_s() const noexcept { return t_settle_; }
  double duration_s() const noexcept { return duration_; }
  int frame_count() const noexcept { return frames_; }
  std::int64_t frame_time_ns(int index) const noexcept;
  double local_time(double t) const noexcept;

  Phase phase(double t) const noexcept;
  // Commanded indentation: negative while the pads are open (a gap).
  double indentation_mm(double t) const noexcept;
  // Normalised motion progress s in [0, 1] (minimum-jerk profile) and its time derivative.
  double progress(double t) const noexcept;
  double progress_rate(double t) const noexcept;

  Pose pose(double t) const noexcept;    // truth: relative to the first frame
  Twist twist(double t) const noexcept;  // spatial twist in G (rad/s, mm/s)

 private:
  ScenarioSpec spec_;
  ObjectSpec object_;
  bool sliding_ = false;
  double motion_s_ = 0.0;
  double t_grasp_ = 0.0, t_settle_ = 0.0, t_motion_ = 0.0, t_hold_ = 0.0, t_release_ = 0.0;
  double duration_ = 0.0;
  int frames_ = 0;
  Eigen::Vector3d axis_ = Eigen::Vector3d::UnitZ();
  double amount_ = 0.0;  // radians or millimetres
};

// Minimum-jerk (quintic) profile on x in [0, 1]: zero velocity and acceleration at both ends.
constexpr double min_jerk(double x) noexcept {
  x = x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
  return x * x * x * (10.0 + x * (-15.0 + 6.0 * x));
}
constexpr double min_jerk_rate(double x) noexcept {
  if (x <= 0.0 || x >= 1.0) return 0.0;
  const double y = x * (1.0 - x);
  return 30.0 * y * y;
}

}  // namespace tacse3::sim
