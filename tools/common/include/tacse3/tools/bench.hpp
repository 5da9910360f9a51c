// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: simulated accuracy cases: scenario specs, calibration, evaluation per config.
#pragma once

#include <array>
#include <atomic>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tacse3/sim/simulator.hpp"
#include "tacse3/tools/calibrate.hpp"
#include "tacse3/tools/replay.hpp"

namespace tacse3::tools {

// One simulated recording, described like a tacse3-sim command line.
struct SimCase {
  std::string profile = "reference";  // sensor profile (tacse3-sim --profile)
  std::string object = "sphere";      // preset name (tacse3-sim --object)
  std::string motion = "rz";          // rx, ry, rz, tx, ty
  double magnitude = 30.0;            // deg or mm
  std::uint64_t seed = 1;
  double radius_mm = 0.0;  // 0 = the preset's size
  // Indentation relative to the profile's nominal one (mm for a profile pressing 1 mm, as the
  // reference does).
  double indentation_mm = 1.0;
  double friction = 0.0;  // object-gel friction (tacse3-sim --friction); 0 = the preset's
  double hold_s = 0.4;    // hold after the motion
  double approach_s = 0.1, grasp_s = 0.4, settle_s = 0.1;
  double release_s = 0.0;     // pads opening after the hold (0 = none)
  std::string label() const;  // "sphere rz 30"
  // The equivalent tacse3-sim options (for docs and messages).
  std::string sim_arguments() const;
};

// A grasp with tacse3-sim's default timeline: the fields the benchmark's tables vary.
inline SimCase make_sim_case(const char* object, const char* motion, double magnitude,
                             std::uint64_t seed = 1, double radius_mm = 0.0,
                             double indentation_mm = 1.0) {
  SimCase c;
  c.object = object;
  c.motion = motion;
  c.magnitude = magnitude;
  c.seed = seed;
  c.radius_mm = radius_mm;
  c.indentation_mm = indentation_mm;
  return c;
}

// "all", a name, or a comma-separated list of names → the profiles, in the simulator's order
// for "all". Error text names the unknown profile.
std::string parse_profile_list(const std::string& text, std::vector<std::string>* out);

// Whether the gel's shear can show the case's motion at every instant: false for an in-plane
// rotation whose peak surface speed at the deepest contact point exceeds the slide law's cap
// speed mu kappa d / c, beyond which the motion leaves no trace in the shear
// (docs/accuracy.md, stress rows). Always true for torsions and translations.
bool shear_carries_speed(const SimCase& c);

// The simulator configuration tacse3-sim would use for the case (both sensors).
std::string make_sim_config(const SimCase& c, sim::SimConfig* out);

// A configuration evaluated on a case.
struct EvalConfig {
  dsp::FusionMethod method = dsp::FusionMethod::kJoint;
  ProxyMode mode = ProxyMode::kAuto;
  SensorChoice sensors = SensorChoice::kBoth;
  bool reference = false;  // also run dsp_ref::DualPipelineRef (double) in lock step
};

struct EvalResult {
  PoseErrors errors{};
  TrackingError tracking{};
  std::optional<double> reference_error_deg;     // the double reference's final rotation error
  std::optional<double> fixed_vs_reference_deg;  // angle between the two final orientations
  // The same against a reference that takes the fixed pipeline's per-frame discrete decisions
  // (dsp_ref::FixedDecisions: flow validity and keyframe switches, contact mask, stick/slip),
  // i.e. the arithmetic difference without the threshold crossings (tools::DecisionFollower).
  std::optional<double> fixed_vs_locked_reference_deg;
  std::optional<double> reference_translation_error_mm;
  SlipScore slip{};
  bool slip_scored = false;
};

// Renders the case once (in memory, grey) and runs every config in lock step.
std::string evaluate_case(const SimCase& c, const config::CalibrationSet& cal,
                          const std::vector<EvalConfig>& configs, std::vector<EvalResult>* out,
                          std::atomic<std::int64_t>* frames_done = nullptr);

// Calibrates on simulated cases (rendered in memory, grey) with tacse3-calibrate's fit.
std::string calibrate_cases(const std::vector<SimCase>& cases, const CalibrateOptions& options,
                            CalibrateReport* report);

// Writes the case as a recording directory, like tacse3-sim (grey or RGB PNGs, truth.csv,
// sim_labels.csv, recording.json with a "sim" block holding the regime). `sensors` selects the
// recorded pads.
std::string write_case_recording(const SimCase& c, const std::filesystem::path& dir, int channels,
                                 SensorChoice sensors = SensorChoice::kBoth);

// Frames the case renders (for progress bars).
std::int64_t case_frames(const SimCase& c);

}  // namespace tacse3::tools
