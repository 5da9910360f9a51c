// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: calibration coverage rules and the self-check (replay against the truth).
#include "tacse3/tools/calibration_check.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <numbers>
#include <thread>

#include "tacse3/tools/metrics.hpp"
#include "tacse3/tools/progress.hpp"
#include "tacse3/tools/replay.hpp"

namespace tacse3::tools {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

std::string for_each_recording(std::size_t n, int jobs,
                               const std::function<std::string(std::size_t)>& job) {
  std::atomic<std::size_t> next{0};
  std::mutex m;
  std::string first_error;
  auto worker = [&] {
    for (;;) {
      const std::size_t i = next++;
      if (i >= n) return;
      {
        std::lock_guard<std::mutex> lock(m);
        if (!first_error.empty()) return;
      }
      std::string e = job(i);
      if (!e.empty()) {
        std::lock_guard<std::mutex> lock(m);
        if (first_error.empty()) first_error = e;
      }
    }
  };
  const int t = std::max(1, std::min<int>(jobs, static_cast<int>(n)));
  std::vector<std::thread> threads;
  for (int k = 1; k < t; ++k) threads.emplace_back(worker);
  worker();
  for (auto& th : threads) th.join();
  return first_error;
}

}  // namespace

std::string run_stage(
    const std::vector<FrameSource*>& sources, int jobs, bool progress, const std::string& label,
    const std::function<std::string(std::size_t, std::atomic<std::int64_t>*)>& job) {
  std::int64_t total = 0;
  for (auto* s : sources) total += static_cast<std::int64_t>(s->info().frame_count());
  std::atomic<std::int64_t> done{0};
  std::atomic<bool> finished{false};
  std::string err;
  std::thread runner([&] {
    err = for_each_recording(sources.size(), jobs, [&](std::size_t i) { return job(i, &done); });
    finished = true;
  });
  ProgressBar bar(label, total, progress);
  while (!finished.load()) {
    bar.update(done.load());
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  runner.join();
  if (err.empty()) bar.finish();
  return err;
}

MotionContent motion_from_truth(const SourceInfo& info) {
  MotionContent c;
  if (info.truth.empty()) return c;
  const dsp::Pose first = to_pose(info.truth.front());
  double peak_xy_mm = 0.0;
  for (const auto& s : info.truth) {
    const dsp::Pose p = to_pose(s);
    // The motion relative to the first row, in G.
    const Eigen::Vector3d th = dsp::so3_log(p.q * first.q.conjugate()) * kDeg;
    const Eigen::Vector3d tr = (p.p - first.p) * 1e3;
    for (int ax = 0; ax < 3; ++ax) {
      if (std::abs(th(ax)) >= kExciteRotationDeg) c.set(static_cast<Motion>(ax));
    }
    if (std::abs(tr(0)) >= kExciteTranslationMm) c.set(Motion::kTx);
    if (std::abs(tr(1)) >= kExciteTranslationMm) c.set(Motion::kTy);
    peak_xy_mm = std::max(peak_xy_mm, tr.head<2>().norm());
  }
  const bool rotates = c[Motion::kRx] || c[Motion::kRy] || c[Motion::kRz];
  const bool slides = c[Motion::kTx] || c[Motion::kTy];
  if (!rotates && !slides && peak_xy_mm >= kPitchMinTranslationMm) {
    c.set(Motion::kStickTranslation);
  }
  return c;
}

std::vector<const CoverageRule*> missing_motions(const std::vector<MotionContent>& recordings,
                                                 bool fitted, bool pitch_given) {
  std::vector<const CoverageRule*> out;
  for (const auto& rule : kCoverageRules) {
    if (!rule.from_truth && !fitted) continue;
    if (pitch_given && rule.motion == Motion::kStickTranslation) continue;
    const bool seen = std::any_of(recordings.begin(), recordings.end(),
                                  [&](const MotionContent& m) { return m[rule.motion]; });
    if (!seen) out.push_back(&rule);
  }
  return out;
}

std::string coverage_message(const std::vector<const CoverageRule*>& missing) {
  if (missing.empty()) return {};
  std::string fields, record;
  for (const CoverageRule* r : missing) {
    fields += std::string(fields.empty() ? "" : "; ") + r->fields;
    record += std::string("\n  record ") + r->record;
  }
  return "the recordings do not determine " + fields + ":" + record;
}

CheckTolerance check_tolerance(const SourceInfo& info, double truth_rotation_deg,
                               double truth_translation_mm) noexcept {
  const double pitch_mm = info.pixel_pitch_mm;
  const double lever_mm = 0.5 * info.finger_separation_mm;
  const double motion_mm = truth_translation_mm + truth_rotation_deg / kDeg * lever_mm;
  CheckTolerance t;
  t.rotation_deg = std::max(kCheckRelative * motion_mm, pitch_mm) / lever_mm * kDeg;
  t.translation_mm = std::max(kCheckRelative * motion_mm, pitch_mm);
  return t;
}

bool RecordingCheck::passed() const noexcept {
  return reason().empty();
}

std::string RecordingCheck::reason() const {
  char b[256];
  if (valid_frames == 0) {
    return "no valid frame: the pipeline never saw a contact it could read (check "
           "contact_tau_on against the contact's f^z, and that the pads touch the object)";
  }
  std::string r;
  if (!(rotation_error_deg <= tolerance.rotation_deg)) {
    std::snprintf(b, sizeof b, "rotation off by %.2f deg (tolerance %.2f deg)", rotation_error_deg,
                  tolerance.rotation_deg);
    r = b;
  }
  if (!(translation_error_mm <= tolerance.translation_mm)) {
    std::snprintf(b, sizeof b, "translation off by %.2f mm (tolerance %.2f mm)",
                  translation_error_mm, tolerance.translation_mm);
    r += std::string(r.empty() ? "" : "; ") + b;
  }
  return r;
}

bool CheckReport::passed() const noexcept {
  return std::all_of(recordings.begin(), recordings.end(),
                     [](const RecordingCheck& r) { return r.passed(); });
}

std::string check_calibration(const std::vector<FrameSource*>& sources,
                              const config::CalibrationSet& calibration, int jobs, bool progress,
                              CheckReport* report) {
  CheckReport rep;
  rep.recordings.resize(sources.size());
  ReplayOptions o;  // tacse3-replay's defaults
  o.calibration = calibration;
  const std::string err =
      run_stage(sources, jobs, progress, "check", [&](std::size_t r, auto* done) -> std::string {
        FrameSource& src = *sources[r];
        const SourceInfo& info = src.info();
        if (!info.has_truth()) return info.name + ": has no truth.csv; the check needs truth";
        Replayer engine;
        if (std::string e = engine.init(info, o); !e.empty()) return e;
        RecordingCheck& c = rep.recordings[r];
        c.name = info.name;
        FrameResult row;
        for (std::size_t i = 0; i < info.frame_count(); ++i) {
          if (std::string e = engine.step(src, i, &row); !e.empty()) return e;
          c.valid_frames += row.estimate_valid ? 1 : 0;
          ++*done;
        }
        c.frames = info.frame_count();
        const dsp::Pose first = truth_pose_at(info.truth, info.t_ns.front());
        const dsp::Pose last = truth_pose_at(info.truth, info.t_ns.back());
        const dsp::Pose truth{last.q * first.q.conjugate(), last.p - first.p};
        c.truth_rotation_deg = rotation_angle_deg(truth.q);
        c.truth_translation_mm = truth.p.norm() * 1e3;
        c.rotation_error_deg = rotation_error_deg(row.pose.q, truth.q);
        c.translation_error_mm = (row.pose.p - truth.p).norm() * 1e3;
        c.tolerance = check_tolerance(info, c.truth_rotation_deg, c.truth_translation_mm);
        return {};
      });
  if (!err.empty()) return err;
  *report = std::move(rep);
  return {};
}

std::string format_check(const CheckReport& rep) {
  std::string o =
      "check (tacse3-replay defaults: joint fusion, --mode auto, both pads; final pose against "
      "the truth):\n";
  char line[512];
  std::snprintf(line, sizeof line, "  %-32s %7s %7s %7s %8s %7s %7s %11s  %s\n", "recording",
                "truth", "error", "tol", "truth mm", "err mm", "tol mm", "valid", "verdict");
  o += line;
  int failed = 0;
  for (const auto& r : rep.recordings) {
    std::string name = r.name;
    if (name.size() > 32) name = "..." + name.substr(name.size() - 29);
    char valid[32];
    std::snprintf(valid, sizeof valid, "%zu/%zu", r.valid_frames, r.frames);
    const std::string why = r.reason();
    failed += why.empty() ? 0 : 1;
    std::snprintf(line, sizeof line, "  %-32s %7.2f %7.2f %7.2f %8.2f %7.2f %7.2f %11s  %s\n",
                  name.c_str(), r.truth_rotation_deg, r.rotation_error_deg,
                  r.tolerance.rotation_deg, r.truth_translation_mm, r.translation_error_mm,
                  r.tolerance.translation_mm, valid, why.empty() ? "ok" : "FAILED");
    o += line;
  }
  std::snprintf(line, sizeof line,
                "  tolerance: %.0f %% of the motion at the pads (|p| + |theta| W/2), at least one "
                "pixel there; in rotation divided by W/2\n",
                kCheckRelative * 100.0);
  o += line;
  std::snprintf(line, sizeof line, "check: %zu of %zu recording(s) explained\n",
                rep.recordings.size() - static_cast<std::size_t>(failed), rep.recordings.size());
  o += line;
  return o;
}

}  // namespace tacse3::tools
