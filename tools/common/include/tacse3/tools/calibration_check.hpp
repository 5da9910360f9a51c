// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: what a calibration set must contain (coverage) and whether a calibration explains
// recordings with truth (the self-check of tacse3-calibrate and its --check).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "tacse3/config/calibration_file.hpp"
#include "tacse3/tools/source.hpp"

namespace tacse3::tools {

// ---- coverage --------------------------------------------------------------------------------
// What a recording shows. The axes come from its truth alone; the regime (stick: the contact
// follows the object, read by the displacement proxy; slide: it does not, read by the velocity
// proxy) and the pre-contact frames only from the fit.
enum class Motion : std::uint8_t {
  kRx,
  kRy,
  kRz,
  kTx,
  kTy,
  kSlide,
  kStick,
  kPadsOpen,
  kStickTranslation
};

// A rotation excites an axis from this angle on, a translation from this distance.
inline constexpr double kExciteRotationDeg = 1.0;
inline constexpr double kExciteTranslationMm = 1.0;
// A stick translation measures the pixel pitch (pitch_fit.hpp): its truth is a pure in-plane
// translation (no rotation of kExciteRotationDeg) of at least this and below
// kExciteTranslationMm (the set's larger translations are slides, which the contact does not
// follow). 0.2 mm is two pixels at the coarsest simulated pitch (docs/sim-profiles.md).
inline constexpr double kPitchMinTranslationMm = 0.2;

// The motion that satisfies a rule in the recording plan (tacse3-calibrate --plan). A rule whose
// axis is null is satisfied by other rules' motions; `regime_note` then says which.
struct PlanMotion {
  const char* axis;         // rx ry rz (deg) or tx ty (mm); nullptr: no motion of its own
  double magnitude;         // deg or mm
  double duration_s;        // of the motion itself
  const char* regime;       // stick | slide
  const char* regime_note;  // for a rule without a motion: which plan lines satisfy it
};

struct CoverageRule {
  Motion motion;
  bool from_truth;     // decidable from truth.csv alone (before the fit)
  const char* fields;  // the calibration values that need it
  const char* record;  // what to record, said to the user
  PlanMotion plan;
};

// Which motions determine which fitted values: a set without a rule's motion is refused, naming
// the rule's `record`. The plan motions are the set tacse3-calibrate --plan prints: one per rule
// that has one, and each rule either has one or is satisfied by the others' (tests/tools check
// both on a set rendered from the plan).
inline constexpr std::array<CoverageRule, 9> kCoverageRules{{
    {Motion::kRx,
     true,
     "rotation_scale x, paper rotation_scale x",
     "a rotation about x of 1 deg or more (a slide of tens of degrees, a stick motion of 1-3 deg)",
     {"rx", 20.0, 1.0, "slide", nullptr}},
    {Motion::kRy,
     true,
     "rotation_scale y, paper rotation_scale y",
     "a rotation about y of 1 deg or more (a slide of tens of degrees, a stick motion of 1-3 deg)",
     {"ry", 20.0, 1.0, "slide", nullptr}},
    {Motion::kRz,
     true,
     "rotation_scale z, paper rotation_scale z",
     "a rotation about z of 1 deg or more (a torsion of tens of degrees, a stick motion of 1-3 "
     "deg)",
     {"rz", 3.0, 0.5, "stick", nullptr}},
    {Motion::kTx,
     true,
     "translation_scale x (joint and paper)",
     "a translation along x of 1 mm or more (a slide of about 10 mm)",
     {"tx", 10.0, 1.0, "slide", nullptr}},
    {Motion::kTy,
     true,
     "translation_scale y (joint and paper)",
     "a translation along y of 1 mm or more (a slide of about 10 mm)",
     {"ty", 10.0, 1.0, "slide", nullptr}},
    {Motion::kSlide,
     false,
     "c_velocity, slip detector thresholds",
     "a slide: a motion the contact cannot follow (tens of degrees or about 10 mm), then a hold",
     {nullptr, 0.0, 0.0, "slide", "the slide lines"}},
    {Motion::kStick,
     false,
     "c_displacement, slip detector thresholds",
     "a stick motion: a small motion the contact follows (1-3 deg or a few tenths of a mm), then "
     "a hold",
     {nullptr, 0.0, 0.0, "stick", "the stick lines"}},
    {Motion::kPadsOpen,
     false,
     "contact_tau_on, contact_tau_off",
     "frames with the pads open before the grasp (the f^z noise is measured on them)",
     {nullptr, 0.0, 0.0, nullptr, "every line's pads-open start"}},
    {Motion::kStickTranslation,
     true,
     "pixel_pitch_m",
     "a translation along x or y of 0.2-1.0 mm without rotation (a stick translation), then a "
     "hold (or give the pitch with --pixel-pitch MM)",
     {"tx", 0.5, 0.5, "stick", nullptr}},
}};

// The rule of `m`.
constexpr const CoverageRule& coverage_rule(Motion m) noexcept {
  return kCoverageRules[static_cast<std::size_t>(m)];
}
constexpr bool coverage_rules_in_order() noexcept {
  for (std::size_t i = 0; i < kCoverageRules.size(); ++i) {
    if (static_cast<std::size_t>(kCoverageRules[i].motion) != i) return false;
  }
  return true;
}
static_assert(coverage_rules_in_order(), "kCoverageRules is in Motion's order");

// The motions one recording shows; from_truth() fills the axes, the fit the rest.
struct MotionContent {
  std::array<bool, kCoverageRules.size()> has{};
  bool operator[](Motion m) const noexcept { return has[static_cast<std::size_t>(m)]; }
  void set(Motion m) noexcept { has[static_cast<std::size_t>(m)] = true; }
};
MotionContent motion_from_truth(const SourceInfo& info);

// The rules no recording satisfies (only the from_truth rules when `fitted` is false; not the
// pixel pitch's when `pitch_given`: the user gave it).
std::vector<const CoverageRule*> missing_motions(const std::vector<MotionContent>& recordings,
                                                 bool fitted, bool pitch_given = false);
// "the recordings do not determine ...: record ...; ..." (empty when nothing is missing).
std::string coverage_message(const std::vector<const CoverageRule*>& missing);

// ---- the self-check --------------------------------------------------------------------------
// A recording is explained when the replay with the calibration (tacse3-replay's defaults: joint
// fusion, --mode auto, both pads) ends within the tolerance of the truth's final pose, in rotation
// and in translation, and has valid frames. The tolerance is relative to the motion's size at
// the pads, M = |p| + |θ|·W/2 (W the finger separation: a rotation about an in-plane axis moves
// each pad by |θ|·W/2, and an error in one pad's reading shows in both the rotation and the
// translation): kCheckRelative·M in translation and kCheckRelative·M/(W/2) in rotation, but at
// least one pixel pitch P and the angle P/(W/2), what one pixel at a pad resolves. kCheckRelative
// is twice the paper's largest relative error (11.9 deg at 90 deg, TacSE3 Table V-B): a
// calibration that reads its own recordings worse than that is not working.
inline constexpr double kCheckRelative = 0.25;

struct CheckTolerance {
  double rotation_deg = 0.0;
  double translation_mm = 0.0;
};
CheckTolerance check_tolerance(const SourceInfo& info, double truth_rotation_deg,
                               double truth_translation_mm) noexcept;

struct RecordingCheck {
  std::string name;
  double truth_rotation_deg = 0.0, truth_translation_mm = 0.0;
  double rotation_error_deg = 0.0, translation_error_mm = 0.0;
  CheckTolerance tolerance{};
  std::size_t frames = 0, valid_frames = 0;
  bool passed() const noexcept;
  std::string reason() const;  // why it failed (empty when it passed)
};

struct CheckReport {
  std::vector<RecordingCheck> recordings;
  bool passed() const noexcept;
};

// Replays every source with `calibration` (jobs in parallel, progress on stderr when asked).
// Returns an empty string or an error naming the recording.
std::string check_calibration(const std::vector<FrameSource*>& sources,
                              const config::CalibrationSet& calibration, int jobs, bool progress,
                              CheckReport* report);

// One line per recording, the tolerance rule, and a summary line.
std::string format_check(const CheckReport& report);

// ---- shared by the fit and the check ---------------------------------------------------------
// Runs job(i, frames_done) for every recording on `jobs` threads with a progress bar; the first
// error wins.
std::string run_stage(
    const std::vector<FrameSource*>& sources, int jobs, bool progress, const std::string& label,
    const std::function<std::string(std::size_t, std::atomic<std::int64_t>*)>& job);

}  // namespace tacse3::tools
