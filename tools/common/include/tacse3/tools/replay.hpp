// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the replay engine shared by tacse3-replay, tacse3-calibrate and the benchmark.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tacse3/config/calibration_file.hpp"
#include "tacse3/dsp/pipeline.hpp"
#include "tacse3/tools/metrics.hpp"
#include "tacse3/tools/source.hpp"

namespace tacse3::tools {

// --mode of the tools. kAuto: per-frame, per-sensor stick/slip detection picks the proxy.
enum class ProxyMode : std::uint8_t { kAuto = 0, kVelocity, kDisplacement };
enum class SensorChoice : std::uint8_t { kBoth = 0, kLeft, kRight };

bool parse_mode(std::string_view s, ProxyMode* out) noexcept;
bool parse_method(std::string_view s, dsp::FusionMethod* out) noexcept;
bool parse_sensors(std::string_view s, SensorChoice* out) noexcept;
const char* to_string(ProxyMode m) noexcept;
const char* method_name(dsp::FusionMethod m) noexcept;
const char* to_string(SensorChoice s) noexcept;

// THE one place where a tool mode becomes the pipeline's dsp::VelocityProxy.
dsp::VelocityProxy pipeline_proxy(ProxyMode m) noexcept;
// True when the pipeline implements kAuto itself (false: kAuto runs as documented in
// docs/replay.md until dsp::VelocityProxy::kAuto exists).
bool pipeline_has_auto() noexcept;
// The pipeline's per-frame stick/slip decision for one sensor, if it makes one.
std::optional<bool> detected_slip(const dsp::SensorResult& r) noexcept;

struct ReplayOptions {
  dsp::FusionMethod method = dsp::FusionMethod::kJoint;
  ProxyMode mode = ProxyMode::kAuto;
  SensorChoice sensors = SensorChoice::kBoth;
  config::CalibrationSet calibration{};  // documented defaults unless loaded from a file
};

// The per-sensor calibrations and dual config the engine runs with for a recording: the
// calibration for the fusion method, the rig's pixel pitch (proxy gains rescaled with it), the
// rig's finger separation, the mode's proxy. Exposed so tests and docs can check the rules.
struct EngineSetup {
  dsp::DualConfig dual{};
  std::array<dsp::Calibration, 2> cal{};
  std::array<bool, 2> use{false, false};  // sensors fed to the pipeline
};
std::string make_setup(const SourceInfo& info, const ReplayOptions& options, EngineSetup* out);

// One output row (OUT.csv) plus what the summary needs.
struct FrameResult {
  std::int64_t t_ns = 0;
  dsp::Vector6d twist = dsp::Vector6d::Zero();  // [ω rad/s; v m/s] in G (moving average)
  dsp::Pose pose{};                             // object pose in G since the first frame
  std::array<bool, 2> valid{false, false};      // sensor contributed to this frame's estimate
  std::array<bool, 2> contact{false, false};
  std::array<bool, 2> present{false, false};
  std::array<std::optional<bool>, 2> slipping{};  // detector output, if the pipeline has one
  bool estimate_valid = false;
  bool single_sensor = false;
  double confidence = 0.0;
  double dt_s = 0.0;  // integration step the pipeline used for this frame
};

// Runs dsp::DualPipeline frame by frame (the firmware's fixed-point code).
class Replayer {
 public:
  Replayer();
  ~Replayer();
  std::string init(const SourceInfo& info, const ReplayOptions& options);
  // Feeds frame `index` of `source`; *out is the row. Errors name the file.
  std::string step(FrameSource& source, std::size_t index, FrameResult* out);
  // The same with frames already read (several engines can share one decoded frame).
  std::string step_views(std::array<const dsp::FrameView*, 2> views, std::int64_t t_ns,
                         std::size_t index, FrameResult* out);

  const dsp::DualPipeline& pipeline() const noexcept { return *pipeline_; }
  const dsp::DualResult& result() const noexcept { return result_; }
  const EngineSetup& setup() const noexcept { return setup_; }

 private:
  std::unique_ptr<dsp::DualPipeline> pipeline_;
  dsp::DualResult result_{};
  EngineSetup setup_{};
  std::string name_;
};

// Optional outputs of a replay run.
struct ReplaySinks {
  std::FILE* csv = nullptr;               // OUT.csv rows (header written by run_replay)
  class FieldDumper* dump = nullptr;      // --dump-fields
  class CanLogger* can = nullptr;         // --can-log
  class ProgressBar* progress = nullptr;  // updated per frame
  // Called after every frame with the engine (fields, per-sensor results) available.
  std::function<void(std::size_t, const FrameResult&, const Replayer&)> on_frame;
};

struct ReplayRun {
  std::vector<FrameResult> frames;
  std::string error;  // empty on success
};

ReplayRun run_replay(FrameSource& source, const ReplayOptions& options, const ReplaySinks& sinks);

inline constexpr const char* kCsvHeader =
    "t_ns,wx,wy,wz,vx,vy,vz,qw,qx,qy,qz,px,py,pz,valid_left,valid_right";
void write_csv_row(std::FILE* f, const FrameResult& r);

// Accuracy of a run against the source's truth (and slip labels, when both exist).
struct RunSummary {
  bool has_truth = false;
  PoseErrors errors{};
  TrackingError tracking{};  // per frame from the motion's start (with truth)
  // The truth ends before the last frame: later frames are compared with its last pose, so the
  // final errors say little (the summary warns).
  bool truth_ends_early = false;
  std::int64_t truth_end_ns = 0;
  std::int64_t last_frame_ns = 0;
  bool has_slip_score = false;
  SlipScore slip{};
  double valid_fraction = 0.0;  // frames with a valid estimate
  // Frames with a valid estimate and confidence ≥ dsp::kConfidenceThreshold, and the median
  // confidence over the frames with a valid estimate (0 without one).
  double confident_fraction = 0.0;
  double confidence_median = 0.0;
};
RunSummary summarize(const SourceInfo& info, const std::vector<FrameResult>& frames,
                     SensorChoice sensors);

}  // namespace tacse3::tools
