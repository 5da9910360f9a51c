// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the replay engine: a recording through dsp::DualPipeline, row by row.
#include "tacse3/tools/replay.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "tacse3/config/board_file.hpp"
#include "tacse3/dsp/calibration_fields.hpp"
#include "tacse3/tools/can_log.hpp"
#include "tacse3/tools/field_dump.hpp"
#include "tacse3/tools/progress.hpp"

namespace tacse3::tools {

bool parse_mode(std::string_view s, ProxyMode* out) noexcept {
  if (s == "auto") {
    *out = ProxyMode::kAuto;
  } else if (s == "velocity") {
    *out = ProxyMode::kVelocity;
  } else if (s == "displacement") {
    *out = ProxyMode::kDisplacement;
  } else {
    return false;
  }
  return true;
}

bool parse_method(std::string_view s, dsp::FusionMethod* out) noexcept {
  if (s == "joint") {
    *out = dsp::FusionMethod::kJoint;
  } else if (s == "paper") {
    *out = dsp::FusionMethod::kPaper;
  } else {
    return false;
  }
  return true;
}

bool parse_sensors(std::string_view s, SensorChoice* out) noexcept {
  if (s == "both") {
    *out = SensorChoice::kBoth;
  } else if (s == "left") {
    *out = SensorChoice::kLeft;
  } else if (s == "right") {
    *out = SensorChoice::kRight;
  } else {
    return false;
  }
  return true;
}

const char* to_string(ProxyMode m) noexcept {
  switch (m) {
    case ProxyMode::kAuto:
      return "auto";
    case ProxyMode::kVelocity:
      return "velocity";
    case ProxyMode::kDisplacement:
      return "displacement";
  }
  return "?";
}

const char* method_name(dsp::FusionMethod m) noexcept {
  return m == dsp::FusionMethod::kPaper ? "paper" : "joint";
}

const char* to_string(SensorChoice s) noexcept {
  switch (s) {
    case SensorChoice::kBoth:
      return "both";
    case SensorChoice::kLeft:
      return "left";
    case SensorChoice::kRight:
      return "right";
  }
  return "?";
}

// ---- the places that change when dsp::VelocityProxy::kAuto lands ---------------------------
// (see docs/replay.md, "--mode auto"):
//   pipeline_proxy:   ProxyMode::kAuto -> dsp::VelocityProxy::kAuto
//   pipeline_has_auto: true
//   detected_slip:    return r.slipping (the per-frame SensorResult flag)
dsp::VelocityProxy pipeline_proxy(ProxyMode m) noexcept {
  switch (m) {
    case ProxyMode::kDisplacement:
      return dsp::VelocityProxy::kDisplacement;
    case ProxyMode::kVelocity:
      return dsp::VelocityProxy::kVelocity;
    case ProxyMode::kAuto:
      // The pipeline's per-frame, per-sensor stick/slip detector (docs/dsp/motion.md).
      return dsp::VelocityProxy::kAuto;
  }
  return dsp::VelocityProxy::kVelocity;
}

bool pipeline_has_auto() noexcept {
  return true;
}

namespace {

// The rig's finger separation must be one a board file allows: a value far outside it (1e-9 mm)
// would otherwise run with a meaningless lever arm and report nothing.
std::string check_separation(const SourceInfo& info) {
  const double lo_mm = config::kMinFingerSeparationM * 1e3;
  const double hi_mm = config::kMaxFingerSeparationM * 1e3;
  const double w = info.finger_separation_mm;
  if (w >= lo_mm && w <= hi_mm) return {};
  char buf[192];
  std::snprintf(buf, sizeof buf,
                "/recording.json: rig.finger_separation_mm %.6g is outside %g .. %g mm, the range "
                "of board files; correct the rig block",
                w, lo_mm, hi_mm);
  return info.name + buf;
}

// Why the calibration rescaled to the rig's pitch is invalid, blaming what is out of range: the
// pitch itself, or a proxy gain that the pitch ratio pushed over its bound. %g keeps 1e300 and
// 1e-300 readable.
std::string rescale_error(const SourceInfo& info, const char* side, const dsp::Calibration& given,
                          const dsp::Calibration& rescaled) {
  char buf[384];
  const dsp::CalibrationField* pitch = dsp::find_calibration_field("pixel_pitch_m");
  if (pitch != nullptr && !dsp::field_valid(*pitch, rescaled)) {
    std::snprintf(buf, sizeof buf,
                  "/recording.json: rig.pixel_pitch_mm %g is outside %g .. %g mm; correct the rig "
                  "block",
                  info.pixel_pitch_mm, pitch->lo * 1e3, pitch->hi * 1e3);
    return info.name + buf;
  }
  for (const char* key : {"c_velocity", "c_displacement"}) {
    const dsp::CalibrationField* f = dsp::find_calibration_field(key);
    if (f == nullptr || f->real == nullptr || dsp::field_valid(*f, rescaled)) continue;
    std::snprintf(buf, sizeof buf,
                  "/recording.json: rig.pixel_pitch_mm %g is %g times the %s calibration's pitch, "
                  "which rescales its %s %g to %g, outside %g .. %g %s; lower %s in the "
                  "calibration or check the pitch",
                  info.pixel_pitch_mm, rescaled.pixel_pitch_m / given.pixel_pitch_m, side, key,
                  given.*(f->real), rescaled.*(f->real), f->lo, f->hi, f->unit, key);
    return info.name + buf;
  }
  std::snprintf(buf, sizeof buf,
                "/recording.json: rig.pixel_pitch_mm %g makes the %s calibration invalid; check "
                "the calibration",
                info.pixel_pitch_mm, side);
  return info.name + buf;
}

}  // namespace

std::optional<bool> detected_slip(const dsp::SensorResult& r) noexcept {
  if (!r.processed || r.degraded) return std::nullopt;
  return r.slipping;
}
// ---------------------------------------------------------------------------------------------

std::string make_setup(const SourceInfo& info, const ReplayOptions& options, EngineSetup* out) {
  EngineSetup s;
  const char* names[2] = {"left", "right"};
  switch (options.sensors) {
    case SensorChoice::kBoth:
      s.use = info.has_sensor;
      break;
    case SensorChoice::kLeft:
    case SensorChoice::kRight: {
      const std::size_t k = options.sensors == SensorChoice::kLeft ? 0 : 1;
      if (!info.has_sensor[k]) {
        return info.name + "/recording.json: --sensors " + names[k] +
               ", but the recording has no " + names[k] + " sensor";
      }
      s.use[k] = true;
      break;
    }
  }
  if (!s.use[0] && !s.use[1]) return info.name + "/recording.json: no sensor to replay";

  s.cal = options.calibration.for_method(options.method);
  const double pitch_m = info.pixel_pitch_mm * 1e-3;
  for (std::size_t k = 0; k < 2; ++k) {
    dsp::Calibration& c = s.cal[k];
    // The rig's pixel pitch replaces the calibration's. The proxy gains are metres (per second)
    // per pixel of shear, so they scale with the pitch. That keeps the units; the grid and the
    // smoothing are in pixels, so a slide still reads a few per cent differently at another
    // pitch (docs/replay.md).
    const dsp::Calibration given = c;
    const double ratio = pitch_m / c.pixel_pitch_m;
    c.pixel_pitch_m = pitch_m;
    c.c_velocity *= ratio;
    c.c_displacement *= ratio;
    c.velocity_proxy = pipeline_proxy(options.mode);
    if (dsp::validate(c) != dsp::Status::kOk) return rescale_error(info, names[k], given, c);
  }
  s.dual.fusion.method = options.method;
  s.dual.finger_separation_m = info.finger_separation_mm * 1e-3;
  if (std::string e = check_separation(info); !e.empty()) return e;
  // Nominal period: the median frame step (used for the first frame only).
  if (info.t_ns.size() >= 2) {
    std::vector<std::int64_t> d;
    d.reserve(info.t_ns.size() - 1);
    // Clamped: a source that is not a checked recording may hold any time stamps.
    for (std::size_t i = 1; i < info.t_ns.size(); ++i)
      d.push_back(recording::clamped_difference(info.t_ns[i], info.t_ns[i - 1]));
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
    const double p = static_cast<double>(d[d.size() / 2]) * 1e-9;
    if (p >= 1e-4 && p <= 1.0) s.dual.nominal_frame_period_s = p;
    // A recording at a lower rate must not be treated as a stream of gaps.
    s.dual.max_frame_gap_s = std::clamp(std::max(s.dual.max_frame_gap_s, 4.0 * p), 1e-4, 1.0);
  }
  if (dsp::validate(s.dual) != dsp::Status::kOk) {
    return info.name + ": the dual-pipeline configuration is invalid";
  }
  *out = s;
  return {};
}

Replayer::Replayer() : pipeline_(std::make_unique<dsp::DualPipeline>()) {}
Replayer::~Replayer() = default;

std::string Replayer::init(const SourceInfo& info, const ReplayOptions& options) {
  name_ = info.name;
  if (std::string e = make_setup(info, options, &setup_); !e.empty()) return e;
  const dsp::Status st = pipeline_->configure(setup_.dual, setup_.cal);
  if (st != dsp::Status::kOk) {
    return info.name + ": the pipeline rejected the configuration: " + dsp::to_string(st);
  }
  return {};
}

std::string Replayer::step(FrameSource& source, std::size_t index, FrameResult* out) {
  std::array<const dsp::FrameView*, 2> views{};
  if (std::string e = source.read(index, &views); !e.empty()) return e;
  return step_views(views, source.info().t_ns[index], index, out);
}

std::string Replayer::step_views(std::array<const dsp::FrameView*, 2> views, std::int64_t t,
                                 std::size_t index, FrameResult* out) {
  for (std::size_t k = 0; k < 2; ++k) {
    if (!setup_.use[k]) views[k] = nullptr;
  }
  pipeline_->process(views[0], views[1], t, result_);
  const char* names[2] = {"left", "right"};
  for (std::size_t k = 0; k < 2; ++k) {
    const dsp::Status s = result_.sensors[k].status;
    if (views[k] != nullptr && s != dsp::Status::kOk) {
      return name_ + ": frame " + std::to_string(index) + " (" + names[k] +
             "): rejected by the pipeline: " + dsp::to_string(s);
    }
  }
  FrameResult& r = *out;
  r = FrameResult{};
  r.t_ns = t;
  r.twist = result_.twist;
  r.pose = result_.pose;
  r.estimate_valid = result_.valid;
  r.single_sensor = result_.single_sensor;
  r.confidence = result_.confidence;
  r.dt_s = result_.dt_s;
  const std::uint8_t used = result_.fused.rotation_sensors | result_.fused.translation_sensors;
  for (std::size_t k = 0; k < 2; ++k) {
    const dsp::SensorResult& sr = result_.sensors[k];
    r.present[k] = views[k] != nullptr;
    r.valid[k] = (used & (k == 0 ? dsp::kSensor1 : dsp::kSensor2)) != 0;
    r.contact[k] = sr.processed && sr.motion.contact;
    if (r.present[k]) r.slipping[k] = detected_slip(sr);
  }
  return {};
}

void write_csv_row(std::FILE* f, const FrameResult& r) {
  const auto& w = r.twist;
  std::fprintf(f,
               "%lld,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.12f,%.12f,%.12f,%.12f,%.9g,%.9g,%.9g,%d,%d\n",
               static_cast<long long>(r.t_ns), w[0], w[1], w[2], w[3], w[4], w[5], r.pose.q.w(),
               r.pose.q.x(), r.pose.q.y(), r.pose.q.z(), r.pose.p.x(), r.pose.p.y(), r.pose.p.z(),
               r.valid[0] ? 1 : 0, r.valid[1] ? 1 : 0);
}

ReplayRun run_replay(FrameSource& source, const ReplayOptions& options, const ReplaySinks& sinks) {
  ReplayRun run;
  Replayer engine;
  if (std::string e = engine.init(source.info(), options); !e.empty()) {
    run.error = e;
    return run;
  }
  const std::size_t n = source.info().frame_count();
  run.frames.reserve(n);
  if (sinks.csv != nullptr) std::fprintf(sinks.csv, "%s\n", kCsvHeader);
  for (std::size_t i = 0; i < n; ++i) {
    FrameResult r;
    if (std::string e = engine.step(source, i, &r); !e.empty()) {
      run.error = e;
      return run;
    }
    if (sinks.csv != nullptr) write_csv_row(sinks.csv, r);
    if (sinks.dump != nullptr) {
      std::array<const dsp::SensorFields*, 2> f{nullptr, nullptr};
      for (std::size_t k = 0; k < 2; ++k) {
        if (r.present[k])
          f[k] = &engine.pipeline().sensor(static_cast<dsp::SensorSlot>(k)).fields();
      }
      if (std::string e = sinks.dump->append(r.t_ns, f); !e.empty()) {
        run.error = e;
        return run;
      }
    }
    if (sinks.can != nullptr) {
      if (std::string e = sinks.can->append(r); !e.empty()) {
        run.error = e;
        return run;
      }
    }
    if (sinks.on_frame) sinks.on_frame(i, r, engine);
    run.frames.push_back(r);
    if (sinks.progress != nullptr) sinks.progress->update(static_cast<std::int64_t>(i + 1));
  }
  return run;
}

RunSummary summarize(const SourceInfo& info, const std::vector<FrameResult>& frames,
                     SensorChoice sensors) {
  RunSummary s;
  if (frames.empty()) return s;
  std::int64_t valid = 0, confident = 0;
  std::vector<double> confidence;
  for (const auto& f : frames) {
    if (!f.estimate_valid) continue;
    ++valid;
    confident += f.confidence >= dsp::kConfidenceThreshold ? 1 : 0;
    confidence.push_back(f.confidence);
  }
  s.valid_fraction = static_cast<double>(valid) / static_cast<double>(frames.size());
  s.confident_fraction = static_cast<double>(confident) / static_cast<double>(frames.size());
  if (!confidence.empty()) {
    const auto mid = confidence.begin() + static_cast<std::ptrdiff_t>(confidence.size() / 2);
    std::nth_element(confidence.begin(), mid, confidence.end());
    s.confidence_median = *mid;
  }
  if (info.has_truth()) {
    s.has_truth = true;
    std::vector<dsp::Pose> poses;
    std::vector<std::int64_t> t;
    poses.reserve(frames.size());
    for (const auto& f : frames) {
      poses.push_back(f.pose);
      t.push_back(f.t_ns);
    }
    s.errors = pose_errors(poses, info.truth, t);
    s.tracking = tracking_error(poses, info.truth, t);
    s.truth_end_ns = info.truth.back().t_ns;
    s.last_frame_ns = frames.back().t_ns;
    s.truth_ends_early = s.truth_end_ns < s.last_frame_ns;
  }
  if (!info.labels.empty()) {
    for (const auto& l : info.labels) {
      const std::size_t k = static_cast<std::size_t>(l.sensor);
      if (sensors == SensorChoice::kLeft && k != 0) continue;
      if (sensors == SensorChoice::kRight && k != 1) continue;
      if (l.index < 0 || static_cast<std::size_t>(l.index) >= frames.size() || !l.in_contact) {
        continue;
      }
      const auto& det = frames[static_cast<std::size_t>(l.index)].slipping[k];
      if (!det.has_value()) continue;
      s.has_slip_score = true;
      s.slip.add(*det, l.slipping);
    }
  }
  return s;
}

}  // namespace tacse3::tools
