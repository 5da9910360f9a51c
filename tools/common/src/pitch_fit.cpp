// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the pixel pitch from stick translations.
#include "tacse3/tools/pitch_fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "tacse3/dsp/geometry.hpp"
#include "tacse3/tools/metrics.hpp"
#include "tacse3/tools/replay.hpp"

namespace tacse3::tools {
namespace {

constexpr double kQ16 = 65536.0;
// The motion starts after the last frame within this fraction of the peak of the start position,
// before the translation reaches kHalfway of it. Searched back from there, so that a robot log's
// pose noise (tenths of the stick translation) before the motion is not taken for its start.
constexpr double kStartFraction = 0.05;
constexpr double kHalfway = 0.5;
// Fewest contact points a frame's mean displacement is taken over (one grid cell's neighbours).
constexpr int kMinPoints = 9;

// In-plane translation (mm) of each frame's truth relative to the first frame's.
std::vector<Eigen::Vector2d> truth_xy_mm(const SourceInfo& info) {
  std::vector<Eigen::Vector2d> xy;
  xy.reserve(info.t_ns.size());
  const Eigen::Vector3d p0 = truth_pose_at(info.truth, info.t_ns.front()).p;
  for (std::int64_t t : info.t_ns) {
    xy.emplace_back(((truth_pose_at(info.truth, t).p - p0) * 1e3).head<2>());
  }
  return xy;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// Per sensor: the displacement field and the contact points (Ω ∩ tracked) at the motion start.
struct StartField {
  dsp::VectorField flow{};
  dsp::GridMask points{};
};

}  // namespace

bool is_stick_translation(const SourceInfo& info) {
  return motion_from_truth(info)[Motion::kStickTranslation];
}

double StickShift::pitch_mm() const noexcept {
  double ts = 0.0, ss = 0.0;
  for (std::size_t i = 0; i < truth_mm.size(); ++i) {
    ts += truth_mm[i] * shift_px[i];
    ss += shift_px[i] * shift_px[i];
  }
  return ss > 0.0 ? ts / ss : 0.0;
}

std::string measure_stick_shift(FrameSource& source, StickShift* out) {
  const SourceInfo& info = source.info();
  *out = StickShift{};
  out->name = info.name;
  const std::vector<Eigen::Vector2d> xy = truth_xy_mm(info);
  double peak = 0.0;
  for (const auto& v : xy) peak = std::max(peak, v.norm());
  std::size_t half = 0;
  while (half + 1 < xy.size() && xy[half].norm() < kHalfway * peak) ++half;
  std::size_t start = half;
  while (start > 0 && xy[start].norm() >= kStartFraction * peak) --start;
  std::array<StartField, 2> ref{};
  ReplaySinks sinks;
  sinks.on_frame = [&](std::size_t i, const FrameResult&, const Replayer& engine) {
    if (i < start) return;
    for (std::size_t k = 0; k < 2; ++k) {
      const dsp::SensorFields& f =
          engine.pipeline().sensor(static_cast<dsp::SensorSlot>(k)).fields();
      if (i == start) {
        ref[k].flow = f.flow;
        for (std::size_t g = 0; g < ref[k].points.v.size(); ++g) {
          ref[k].points.v[g] = f.contact.mask.v[g] != 0 && f.flow_valid.v[g] != 0 ? 1 : 0;
        }
        continue;
      }
      double sx = 0.0, sy = 0.0;
      int n = 0;
      for (std::size_t g = 0; g < ref[k].points.v.size(); ++g) {
        if (ref[k].points.v[g] == 0 || f.flow_valid.v[g] == 0) continue;
        sx += f.flow.x.v[g] - ref[k].flow.x.v[g];
        sy += f.flow.y.v[g] - ref[k].flow.y.v[g];
        ++n;
      }
      if (n < kMinPoints) continue;
      // Q16 working px to sensor px.
      const double px = std::hypot(sx, sy) / n / kQ16 * dsp::kWorkScale;
      out->shift_px.push_back(px);
      out->truth_mm.push_back((xy[i] - xy[start]).norm());
    }
  };
  ReplayOptions options;
  options.mode = ProxyMode::kDisplacement;
  const ReplayRun run = run_replay(source, options, sinks);
  if (!run.error.empty()) return run.error;
  if (out->shift_px.empty()) {
    return info.name + ": no contact seen when the translation starts (frame " +
           std::to_string(start) + "): record the stick translation after the grasp has settled";
  }
  return {};
}

std::string fit_pixel_pitch(const std::vector<FrameSource*>& sources, int jobs, bool progress,
                            PitchFit* out) {
  *out = PitchFit{};
  if (!sources.empty()) out->claimed_mm = sources.front()->info().pixel_pitch_mm;
  std::vector<FrameSource*> stick;
  for (auto* s : sources) {
    if (is_stick_translation(s->info())) stick.push_back(s);
  }
  if (stick.empty()) {
    char b[160];
    std::snprintf(b, sizeof b, "a translation along x or y of %.1f-%.1f mm without rotation",
                  kPitchMinTranslationMm, kExciteTranslationMm);
    return std::string(
               "the recordings do not determine pixel_pitch_m: no stick translation\n"
               "  record ") +
           b + " (a stick translation), then a hold\n(or give the pitch with --pixel-pitch MM)";
  }
  out->recordings.resize(stick.size());
  if (std::string e =
          run_stage(stick, jobs, progress, "pixel pitch",
                    [&](std::size_t i, std::atomic<std::int64_t>* done) {
                      std::string err = measure_stick_shift(*stick[i], &out->recordings[i]);
                      *done += static_cast<std::int64_t>(stick[i]->info().frame_count());
                      return err;
                    });
      !e.empty()) {
    return e;
  }
  double ts = 0.0, ss = 0.0;
  std::vector<double> per_recording, ratios;
  for (const auto& r : out->recordings) {
    for (std::size_t i = 0; i < r.truth_mm.size(); ++i) {
      ts += r.truth_mm[i] * r.shift_px[i];
      ss += r.shift_px[i] * r.shift_px[i];
      // The frames with a shift of a pixel or more give a ratio worth its noise.
      if (r.shift_px[i] >= 1.0) ratios.push_back(r.truth_mm[i] / r.shift_px[i]);
    }
    per_recording.push_back(r.pitch_mm());
  }
  out->pitch_mm = ts / ss;
  // Scatter as a robust sigma (1.4826 MAD) over the square root of the count.
  const std::vector<double>& v = per_recording.size() >= 2 ? per_recording : ratios;
  if (v.size() >= 2) {
    const double m = median(v);
    std::vector<double> dev;
    for (double x : v) dev.push_back(std::abs(x - m));
    out->relative_se =
        1.4826 * median(dev) / std::sqrt(static_cast<double>(v.size())) / out->pitch_mm;
  }
  return {};
}

std::string format_pitch(const PitchFit& fit) {
  char b[320];
  std::snprintf(b, sizeof b,
                "pixel pitch: fitted %.4g mm/px (relative standard error %.2g %%) from %zu stick "
                "translation(s); replaces the recordings' rig.pixel_pitch_mm %.5g (fitted / "
                "claimed %.4f)\n",
                fit.pitch_mm, 100.0 * fit.relative_se, fit.recordings.size(), fit.claimed_mm,
                fit.pitch_mm / fit.claimed_mm);
  std::string o = b;
  for (const auto& r : fit.recordings) {
    std::snprintf(b, sizeof b, "  %-32s %.5g mm/px over %zu frame(s)\n", r.name.c_str(),
                  r.pitch_mm(), r.truth_mm.size());
    o += b;
  }
  return o;
}

PitchOverrideSource::PitchOverrideSource(FrameSource& inner, double pixel_pitch_mm)
    : inner_(inner), info_(inner.info()) {
  info_.pixel_pitch_mm = pixel_pitch_mm;
}

}  // namespace tacse3::tools
