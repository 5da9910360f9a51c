// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: fits a calibration from recordings with truth by running the pipeline (calibrate).
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "tacse3/config/calibration_file.hpp"
#include "tacse3/tools/calibration_check.hpp"
#include "tacse3/tools/replay.hpp"
#include "tacse3/tools/source.hpp"

namespace tacse3::tools {

// Fewest frames a recording must have for the fit. The first frame is the pipeline's reference
// and the moving average and the slip detector need several more before a twist means anything;
// a real grasp has hundreds, so this only stops stubs (a 1-frame recording gave a "calibration").
inline constexpr std::size_t kMinCalibrationFrames = 16;

// Why a recording cannot take part in a fit (no truth, too few frames), or an empty string.
std::string check_calibration_recording(const SourceInfo& info);

struct CalibrateOptions {
  config::CalibrationSet start{};  // starting values (the documented defaults)
  int jobs = 1;                    // recordings processed in parallel (one thread each)
  bool progress = false;           // progress bar on stderr
  std::function<void(const std::string&)> log;  // stage messages (may be empty)
  bool pitch_given = false;  // the user gave the pixel pitch: no stick translation needed
};

// What the fit says about one recording.
struct RecordingFit {
  std::string name;
  Eigen::Vector3d truth_rotation_deg = Eigen::Vector3d::Zero();  // final truth rotation vector
  double truth_translation_mm = 0.0;
  ProxyMode explained_by = ProxyMode::kVelocity;  // proxy whose calibrated estimate fits best
  std::string sim_regime;  // "stick"/"slide" from recording.json's "sim" block: REPORT ONLY
  // Velocity-proxy rate left at rest / rate in motion (-1: not measurable); decides the proxy.
  double rest_persistence = -1.0;
  double before_deg = 0.0;       // joint, starting calibration, that proxy: rotation error
  double after_deg = 0.0;        // joint, fitted calibration, that proxy (measured)
  double after_other_deg = 0.0;  // joint, fitted calibration, the other proxy (measured)
  double after_paper_deg = 0.0;  // paper fusion, fitted paper scales (linear prediction)
  // joint, fitted (translation scales applied linearly), with the proxy whose translation is
  // closer to the truth (the one the translation scales are fitted on)
  double translation_after_mm = 0.0;
  // Stage 1: σ of filter(f^z) over the frames before contact (-1: the recording gives none),
  // the quiet frames it was measured on, and the contact onset's frame (-1: none seen).
  double noise_sigma = -1.0;
  std::size_t quiet_frames = 0;
  std::int64_t contact_onset_frame = -1;
};

struct CalibrateReport {
  config::CalibrationSet calibration;
  std::vector<RecordingFit> recordings;
  double fz_noise_sigma = 0.0;  // median over the recordings of their pre-contact f^z σ
  double contact_tau_on = 0.0, contact_tau_off = 0.0;
  // The noise's largest component over contact_tau_on in the frames before contact, the frames
  // that was over, and the minimum area fitted from it (contact_area.hpp).
  int noise_largest_component = 0;
  std::size_t noise_component_frames = 0;
  int contact_min_area_cells = 0;
  std::array<double, 3> shear_gains{0.0, 1.0, 1.0};  // fitted (d, r, k), max = 1
  std::array<int, 2> recordings_per_mode{0, 0};      // [velocity, displacement]
  int iterations = 0;
  std::vector<std::string> notes;  // parts not fitted, recordings left out of a stage
  // Why the calibration must not be used: a value stopped at a bound (naming the field and the
  // recordings that drove it), motions the set lacks, recordings the self-check does not explain.
  std::vector<std::string> problems;
  std::vector<MotionContent> motions;  // per recording: axes (truth), regime, pads open (fit)
  CheckReport check;                   // the fitted calibration replayed on its recordings
  // Summed relative final-pose cost of each kAuto onset-threshold candidate (calibrate.cpp).
  std::vector<double> detector_cost;
};

// Runs the pipeline over every source in four stages (τ from the f^z noise before contact; the
// shear gains, both proxy gains and the per-axis rotation scales from component-wise runs with
// that τ; validation runs that also fit the paper fusion's scales and the translation scales; the
// self-check). Sources must carry truth. Returns an empty string or an error naming the
// recording when no calibration can be fitted at all; a calibration that was fitted but must not
// be used comes back with report->problems set. A fit with problems is repeated with the
// binomial working image (antialias_filter), which is kept if it has fewer problems.
std::string calibrate(const std::vector<FrameSource*>& sources, const CalibrateOptions& options,
                      CalibrateReport* report);

// Human-readable fit quality (one line per recording plus the fitted values), the self-check and
// the problems.
std::string format_report(const CalibrateReport& report);

}  // namespace tacse3::tools
