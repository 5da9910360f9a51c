// SPDX-License-Identifier: Apache-2.0
// tacse3-calibrate: fit a calibration file from recordings with truth, or check one on recordings
// with truth (docs/calibration.md).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "tacse3/config/calibration_file.hpp"
#include "tacse3/tools/calibrate.hpp"
#include "tacse3/tools/calibration_check.hpp"
#include "tacse3/tools/calibration_plan.hpp"
#include "tacse3/tools/cli.hpp"
#include "tacse3/tools/pitch_fit.hpp"
#include "tacse3/tools/progress.hpp"
#include "tacse3/tools/source.hpp"

namespace {

namespace tt = tacse3::tools;

// Exit codes (docs/calibration.md): 0 written / explained, 1 refused, failed or an error, 2 usage.
constexpr int kFailed = 1;
constexpr int kUsage = 2;
// The calibration file's range of pixel_pitch_m (dsp/calibration_fields.hpp), in mm.
constexpr double kMinPitchMm = 0.001, kMaxPitchMm = 0.2;

int fail(const std::string& msg) {
  std::fprintf(stderr, "tacse3-calibrate: error: %s\n", msg.c_str());
  return kFailed;
}

void warn(const std::string& msg) {
  std::fprintf(stderr, "tacse3-calibrate: warning: %s\n", msg.c_str());
}

std::string fmt4(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

struct Recordings {
  std::vector<std::unique_ptr<tt::FrameSource>> owned;
  std::vector<tt::FrameSource*> sources;
};

// The pixel pitch the fit uses: the one given (pitch_mm > 0), or the one fitted from the stick
// translations, reported on stdout. Then every source carries it.
std::string set_pixel_pitch(double pitch_mm, int jobs, bool quiet, Recordings* rec) {
  if (pitch_mm <= 0.0) {
    tt::PitchFit fit;
    if (std::string e =
            tt::fit_pixel_pitch(rec->sources, jobs, !quiet && tt::stderr_is_tty(), &fit);
        !e.empty()) {
      return e;
    }
    // Four significant digits, as the file keeps the other fitted values.
    fit.pitch_mm = std::strtod(fmt4(fit.pitch_mm).c_str(), nullptr);
    if (!quiet) std::printf("%s", tt::format_pitch(fit).c_str());
    pitch_mm = fit.pitch_mm;
    if (!(pitch_mm >= kMinPitchMm && pitch_mm <= kMaxPitchMm)) {
      char b[256];
      std::snprintf(b, sizeof b,
                    "the fitted pixel pitch %.4g mm/px is outside %g .. %g: check that the stick "
                    "translations' truth.csv is in metres and in G, or give --pixel-pitch MM",
                    pitch_mm, kMinPitchMm, kMaxPitchMm);
      return b;
    }
  } else if (!quiet) {
    std::printf(
        "pixel pitch: given %.5g mm/px (--pixel-pitch); replaces the recordings' "
        "rig.pixel_pitch_mm %.5g (given / claimed %.4f)\n",
        pitch_mm, rec->sources.front()->info().pixel_pitch_mm,
        pitch_mm / rec->sources.front()->info().pixel_pitch_mm);
  }
  for (auto& s : rec->sources) {
    rec->owned.push_back(std::make_unique<tt::PitchOverrideSource>(*s, pitch_mm));
    s = rec->owned.back().get();
  }
  return {};
}

// Opens every directory; each must carry truth.
std::string open_recordings(const std::vector<std::string>& dirs, Recordings* out) {
  for (const auto& d : dirs) {
    std::string err;
    auto s = tt::RecordingSource::open(d, &err);
    if (!s) return err;
    if (!s->info().has_truth()) {
      return d + "/truth.csv: missing; calibration and its check need recordings with truth";
    }
    out->sources.push_back(s.get());
    out->owned.push_back(std::move(s));
  }
  return {};
}

int run_check(const std::string& cal_file, const std::vector<std::string>& dirs, int jobs,
              bool quiet) {
  tacse3::config::CalibrationSet cal;
  if (auto s = tacse3::config::load_calibration(cal_file, &cal); !s) return fail(s.message());
  Recordings rec;
  if (std::string e = open_recordings(dirs, &rec); !e.empty()) return fail(e);
  tt::CheckReport report;
  if (std::string e =
          tt::check_calibration(rec.sources, cal, jobs, !quiet && tt::stderr_is_tty(), &report);
      !e.empty()) {
    return fail(e);
  }
  if (!quiet) std::printf("%s", tt::format_check(report).c_str());
  if (report.passed()) return 0;
  for (const auto& r : report.recordings) {
    if (!r.passed()) fail("not explained by " + cal_file + ": " + r.name + ": " + r.reason());
  }
  return kFailed;
}

int run_fit(const std::vector<std::string>& dirs, const std::string& out_file,
            const std::string& start_file, double pitch_mm, int jobs, bool quiet, bool force) {
  // Before the fit: a fit can take minutes, and a typo in --out must not cost them.
  if (auto s = tacse3::config::check_calibration_output(out_file); !s) {
    return fail("--out: " + s.message());
  }
  tt::CalibrateOptions opt;
  opt.jobs = jobs;
  opt.pitch_given = pitch_mm > 0.0;
  opt.progress = !quiet && tt::stderr_is_tty();
  if (!quiet)
    opt.log = [](const std::string& m) {
      std::fprintf(stderr, "tacse3-calibrate: %s\n", m.c_str());
    };
  if (!start_file.empty()) {
    if (auto s = tacse3::config::load_calibration(start_file, &opt.start); !s) {
      return fail(s.message());
    }
  }
  Recordings rec;
  if (std::string e = open_recordings(dirs, &rec); !e.empty()) return fail(e);
  for (auto* s : rec.sources) {
    if (std::string e = tt::check_calibration_recording(s->info()); !e.empty()) return fail(e);
  }
  // What the truth alone says is missing is refused before the fit.
  std::vector<tt::MotionContent> motions;
  for (auto* s : rec.sources) motions.push_back(tt::motion_from_truth(s->info()));
  if (std::string m = tt::coverage_message(tt::missing_motions(motions, false, opt.pitch_given));
      !m.empty()) {
    if (!force) return fail("refused: " + m + "\n(or fit anyway with --force)");
    warn(m);
  }
  // With --force and no stick translation the recordings' own pitch stands.
  const bool has_stick_translation =
      std::any_of(motions.begin(), motions.end(),
                  [](const tt::MotionContent& m) { return m[tt::Motion::kStickTranslation]; });
  if (opt.pitch_given || has_stick_translation) {
    if (std::string e = set_pixel_pitch(pitch_mm, jobs, quiet, &rec); !e.empty()) return fail(e);
  }
  tt::CalibrateReport report;
  if (std::string err = tt::calibrate(rec.sources, opt, &report); !err.empty()) return fail(err);
  if (!quiet) std::printf("%s", tt::format_report(report).c_str());
  for (const auto& p : report.problems) force ? warn(p) : static_cast<void>(fail(p));
  if (!report.problems.empty() && !force) {
    return fail("not written: " + out_file + " (" + std::to_string(report.problems.size()) +
                " problem(s) above; fix them, or write the file anyway with --force)");
  }
  if (auto s = tacse3::config::save_calibration(out_file, report.calibration); !s) {
    return fail(s.message());
  }
  if (!report.problems.empty()) {
    warn("wrote " + out_file + " with --force although it fails its check: do not install it");
  } else if (!quiet) {
    std::printf("tacse3-calibrate: wrote %s\n", out_file.c_str());
  }
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{
      "Fits a tacse3 calibration file from recordings that carry truth.csv, by running the "
      "firmware's fixed-point pipeline over them, and checks that the fit explains them "
      "(docs/calibration.md). The recordings may mix stick and slide motions; no label is "
      "needed.\n"
      "  tacse3-calibrate REC_DIR... --out FILE     fit, self-check, write\n"
      "  tacse3-calibrate --check CAL REC_DIR...    check CAL on recordings with truth\n"
      "  tacse3-calibrate --plan [--format csv]     the motions to record for a fit\n"
      "The fit also fits the pixel pitch from the stick translations (a pure translation of "
      "0.2-1 mm), unless --pixel-pitch gives it.\n"
      "A recording is explained when it has valid frames and tacse3-replay's defaults end "
      "within the tolerance of its truth: 25 % of the motion at the pads, M = |p| + |theta| "
      "W/2 (W the finger separation), but at least one pixel pitch P; in rotation the same "
      "divided by W/2.\n"
      "Exit status: 0 written (or explained), 1 refused, not explained or an error (the file "
      "is not written), 2 usage error."};
  std::vector<std::string> dirs;
  std::string out_file, start_file, check_file;
  std::string format = "text";
  int jobs = 2;
  double pitch_mm = 0.0;
  bool quiet = false, force = false, plan = false;
  const CLI::Validator path = tt::non_empty_path();
  app.add_option("REC_DIR", dirs, "recording directories with truth.csv")->check(path);
  app.add_flag("--plan", plan,
               "print the motions to record (axis, magnitude, regime, duration, why) and exit");
  app.add_option("--format", format, "--plan's output: text or csv (default text)")
      ->check(CLI::IsMember({"text", "csv"}));
  app.add_option("--pixel-pitch", pitch_mm,
                 "the pixel pitch in mm/px instead of fitting it from stick translations")
      ->check(CLI::Range(kMinPitchMm, kMaxPitchMm));
  auto* out = app.add_option("--out", out_file, "calibration file to write (TOML)")->check(path);
  app.add_option("--check", check_file,
                 "evaluate this calibration on the recordings instead of fitting one")
      ->check(path)
      ->excludes(out);
  app.add_option("--start", start_file,
                 "calibration to start from (default: the documented defaults)")
      ->check(path);
  app.add_flag("--force", force,
               "write the file even if the set lacks motions, a value stops at a bound or the "
               "self-check fails (each is a warning then)");
  app.add_option("-j,--jobs", jobs, "recordings processed in parallel (default 2)")
      ->check(CLI::Range(1, 64));
  app.add_flag("-q,--quiet", quiet, "no progress bar and no report (errors still go to stderr)");
  if (const int rc = tt::parse_command_line(app, argc, argv); rc >= 0) return rc;
  if (plan) {
    if (!dirs.empty() || !out_file.empty() || !check_file.empty()) {
      std::fprintf(stderr,
                   "tacse3-calibrate: error: --plan takes no recordings, --out or --check\n");
      return kUsage;
    }
    std::printf("%s", tt::format_plan(format == "csv").c_str());
    return 0;
  }
  if (format != "text") {
    std::fprintf(stderr, "tacse3-calibrate: error: --format is --plan's\n");
    return kUsage;
  }
  if (dirs.empty()) {
    std::fprintf(stderr,
                 "tacse3-calibrate: error: REC_DIR is required (or --plan)\nRun with --help for "
                 "more information.\n");
    return kUsage;
  }
  if (!check_file.empty()) {
    if (!start_file.empty() || force || pitch_mm > 0.0) {
      std::fprintf(stderr,
                   "tacse3-calibrate: error: --check takes no --start, --force or --pixel-pitch\n");
      return kUsage;
    }
    return run_check(check_file, dirs, jobs, quiet);
  }
  if (out_file.empty()) {
    std::fprintf(stderr,
                 "tacse3-calibrate: error: give --out FILE to fit a calibration, or --check CAL "
                 "to check one\nRun with --help for more information.\n");
    return kUsage;
  }
  return run_fit(dirs, out_file, start_file, pitch_mm, jobs, quiet, force);
}

}  // namespace

int main(int argc, char** argv) {
  // Every path out of run() goes through here: the fit report is on stdout.
  return tt::finish_stdout("tacse3-calibrate", run(argc, argv));
}
