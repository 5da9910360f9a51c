// SPDX-License-Identifier: Apache-2.0
// tacse3-calibrate: fit a calibration file from recordings with truth (docs/calibration.md).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "tacse3/config/calibration_file.hpp"
#include "tacse3/tools/calibrate.hpp"
#include "tacse3/tools/cli.hpp"
#include "tacse3/tools/progress.hpp"
#include "tacse3/tools/source.hpp"

namespace {

namespace tt = tacse3::tools;

int fail(const std::string& msg) {
  std::fprintf(stderr, "tacse3-calibrate: error: %s\n", msg.c_str());
  return 1;
}

int run(int argc, char** argv) {
  CLI::App app{
      "Fits a tacse3 calibration file from recordings that carry truth.csv, by running the "
      "firmware's fixed-point pipeline over them (docs/calibration.md). The recordings may mix "
      "stick and slide motions; no label is needed."};
  std::vector<std::string> dirs;
  std::string out_file, start_file;
  int jobs = 2;
  bool quiet = false;
  const CLI::Validator path = tt::non_empty_path();
  app.add_option("REC_DIR", dirs, "recording directories with truth.csv")->required()->check(path);
  app.add_option("--out", out_file, "calibration file to write (TOML)")->required()->check(path);
  app.add_option("--start", start_file,
                 "calibration to start from (default: the documented defaults)")
      ->check(path);
  app.add_option("-j,--jobs", jobs, "recordings processed in parallel (default 2)")
      ->check(CLI::Range(1, 64));
  app.add_flag("-q,--quiet", quiet, "no progress bar and no fit report");
  if (const int rc = tt::parse_command_line(app, argc, argv); rc >= 0) return rc;
  // Before the fit: a fit can take minutes, and a typo in --out must not cost them.
  if (auto s = tacse3::config::check_calibration_output(out_file); !s) {
    return fail("--out: " + s.message());
  }

  tt::CalibrateOptions opt;
  opt.jobs = jobs;
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
  std::vector<std::unique_ptr<tt::RecordingSource>> owned;
  std::vector<tt::FrameSource*> sources;
  for (const auto& d : dirs) {
    std::string err;
    auto s = tt::RecordingSource::open(d, &err);
    if (!s) return fail(err);
    if (!s->info().has_truth()) {
      return fail(d + "/truth.csv: missing; calibration needs recordings with truth");
    }
    sources.push_back(s.get());
    owned.push_back(std::move(s));
  }
  tt::CalibrateReport report;
  if (std::string err = tt::calibrate(sources, opt, &report); !err.empty()) return fail(err);
  if (auto s = tacse3::config::save_calibration(out_file, report.calibration); !s) {
    return fail(s.message());
  }
  if (!quiet) {
    std::printf("%s", tt::format_report(report).c_str());
    std::printf("tacse3-calibrate: wrote %s\n", out_file.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Every path out of run() goes through here: the fit report is on stdout.
  return tt::finish_stdout("tacse3-calibrate", run(argc, argv));
}
