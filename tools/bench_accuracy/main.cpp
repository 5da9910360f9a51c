// SPDX-License-Identifier: Apache-2.0
// tacse3-bench-accuracy: the paper's Tables V-B, V-C, V-D (+ stick motions) on simulated grasps,
// per sensor profile, with a goal matrix across profiles and optional cross-calibration.
#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cases.hpp"
#include "report.hpp"
#include "tacse3/config/calibration_file.hpp"
#include "tacse3/fileio/file_io.hpp"
#include "tacse3/tools/bench.hpp"
#include "tacse3/tools/cli.hpp"
#include "tacse3/tools/progress.hpp"
#include "text.hpp"

namespace {

namespace tt = tacse3::tools;
namespace ba = tacse3::bench_accuracy;
constexpr const char* kProg = "tacse3-bench-accuracy";

struct Options {
  bool quick = false;
  int jobs = 2;
  std::string markdown, cal_out, cal_in, profile = "reference";
  tacse3::config::CalibrationSet loaded;  // --calibration, read before any run
  double friction = 0.0;
  bool cross = false;
  double fail_above = 0.0;
};

// Evaluates every row (simulated in memory) on `jobs` threads.
std::string evaluate_rows(std::vector<ba::Row>* rows, const tacse3::config::CalibrationSet& cal,
                          const Options& opt, const std::string& label) {
  std::int64_t total = 0;
  for (const auto& r : *rows) total += tt::case_frames(r.c);
  std::atomic<std::size_t> next{0};
  std::atomic<std::int64_t> done{0};
  std::atomic<bool> failed{false};
  std::mutex m;
  std::string error;
  auto worker = [&] {
    for (std::size_t i = next++; i < rows->size() && !failed; i = next++) {
      ba::Row& r = (*rows)[i];
      std::string e = tt::evaluate_case(r.c, cal, r.configs, &r.results, &done);
      if (e.empty()) continue;
      std::lock_guard<std::mutex> lock(m);
      if (error.empty()) error = e;
      failed = true;
    }
  };
  std::vector<std::thread> threads;
  for (int k = 0; k < opt.jobs; ++k) threads.emplace_back(worker);
  {
    tt::ProgressBar bar(label, total, tt::stderr_is_tty());
    while (done.load() < total && !failed.load()) {
      bar.update(done.load());
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
  for (auto& t : threads) t.join();
  return error;
}

// The profile's calibration: fitted on its own calibration set, or read from --calibration.
std::string profile_calibration(const std::string& profile, const Options& opt,
                                tacse3::config::CalibrationSet* cal, std::string* report,
                                std::size_t* problems) {
  if (!opt.cal_in.empty()) {
    *cal = opt.loaded;
    return {};
  }
  std::vector<tt::SimCase> cases = ba::calibration_set(opt.quick, profile);
  for (auto& c : cases) c.friction = opt.friction;
  std::fprintf(stderr, "%s: %s: calibrating on %zu simulated recordings\n", kProg, profile.c_str(),
               cases.size());
  tt::CalibrateOptions co;
  co.jobs = opt.jobs;
  co.progress = tt::stderr_is_tty();
  tt::CalibrateReport rep;
  if (std::string e = tt::calibrate_cases(cases, co, &rep); !e.empty()) return e;
  *cal = rep.calibration;
  *report = tt::format_report(rep);
  // The benchmark evaluates the fit whatever its self-check says, and says what it said.
  for (const auto& p : rep.problems) {
    std::fprintf(stderr, "%s: %s: warning: the calibration fit: %s\n", kProg, profile.c_str(),
                 p.c_str());
  }
  *problems = rep.problems.size();
  return {};
}

struct ProfileRun {
  ba::ProfileOutcome outcome;
  tacse3::config::CalibrationSet cal;
  std::string tables;  // markdown section
};

ProfileRun run_profile(const std::string& profile, const Options& opt) {
  ProfileRun run;
  run.outcome.name = profile;
  std::string cal_report;
  std::size_t problems = 0;
  const auto t0 = std::chrono::steady_clock::now();
  if (std::string e = profile_calibration(profile, opt, &run.cal, &cal_report, &problems);
      !e.empty()) {
    run.outcome.error = "calibration failed";
    run.tables = ba::cat({"### Profile ", profile, "\n\nCalibration failed: ", e, "\n"});
    std::fprintf(stderr, "%s: %s: calibration failed: %s\n", kProg, profile.c_str(), e.c_str());
    return run;
  }
  const auto t1 = std::chrono::steady_clock::now();
  std::vector<ba::Row> rows = ba::test_rows(opt.quick, profile, true);
  run.outcome.stress = true;
  for (auto& r : rows) {
    r.c.friction = opt.friction;
    r.carried = tt::shear_carries_speed(r.c);
    // A stress profile's shear cannot show even the 30-degree in-plane slides.
    if (r.vb && r.c.magnitude <= 30 && r.c.motion != "rz" && r.carried) run.outcome.stress = false;
  }
  // "random" draws another sensor for every recording, so its calibration is fitted across
  // three sensors and tested on a fourth: the cost of a wrong calibration (--cross), not a goal.
  if (profile == "random") run.outcome.stress = true;
  std::fprintf(stderr, "%s: %s: evaluating %zu simulated test recordings\n", kProg, profile.c_str(),
               rows.size());
  if (std::string e = evaluate_rows(&rows, run.cal, opt, profile); !e.empty()) {
    run.outcome.error = "evaluation failed";
    run.tables = ba::cat({"### Profile ", profile, "\n\nEvaluation failed: ", e, "\n"});
    return run;
  }
  const auto t2 = std::chrono::steady_clock::now();
  run.outcome.goals = ba::measure_goals(rows);
  run.outcome.calibration_problems = problems;
  char line[256];
  std::snprintf(line, sizeof(line), "Calibration %.0f s, evaluation of %zu recordings %.0f s.\n\n",
                std::chrono::duration<double>(t1 - t0).count(), rows.size(),
                std::chrono::duration<double>(t2 - t1).count());
  run.tables = ba::cat({"### Profile ", profile, run.outcome.stress ? " (stress: no goal)" : "",
                        "\n\n", line, ba::profile_tables(rows)});
  if (!cal_report.empty()) {
    ba::append(&run.tables, {"\n#### Calibration fit\n\n```\n", cal_report, "```\n"});
  }
  return run;
}

// Cross-calibration: each profile's calibration on every other profile's quick rows.
std::string run_cross(const std::vector<ProfileRun>& runs, const Options& opt) {
  std::vector<std::string> names;
  std::vector<std::vector<ba::GoalValues>> cells(runs.size());
  for (const auto& r : runs) names.push_back(r.outcome.name);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    for (std::size_t j = 0; j < runs.size(); ++j) {
      ba::GoalValues g;
      g.v.fill(ba::kNaN);
      if (runs[i].outcome.error.empty()) {
        std::vector<ba::Row> rows = ba::cross_rows(names[j]);
        for (auto& r : rows) {
          r.c.friction = opt.friction;
          r.carried = tt::shear_carries_speed(r.c);
        }
        const std::string label = ba::cat({names[i], "→", names[j]});
        if (std::string e = evaluate_rows(&rows, runs[i].cal, opt, label); e.empty()) {
          g = ba::measure_goals(rows);
        }
      }
      cells[i].push_back(g);
    }
  }
  return ba::cross_matrix(names, cells);
}

std::string header(const std::string& cmd, const Options& opt, double seconds) {
  std::string o = ba::cat({"Command: `", cmd, "`\n\n"});
  char line[512];
  std::snprintf(
      line, sizeof(line),
      "Calibration: %s. Wall time %.0f s, %d job(s). Errors are those of one simulated "
      "trial per row, dual sensor, defaults (`--method joint --mode auto`) unless a "
      "column says otherwise. Tracking: the per-frame rotation error from the motion's "
      "start to the end, RMS / max, with the truth delayed by the lag (0-50 ms) that "
      "gives the lowest RMS. fixed−ref: fixed point vs the double reference "
      "(free-running / taking the same decisions).\n",
      opt.cal_in.empty() ? "each profile fitted on its own calibration set" : opt.cal_in.c_str(),
      seconds, opt.jobs);
  o += line;
  if (opt.friction > 0.0) {
    std::snprintf(line, sizeof(line),
                  "\nFriction: every recording simulated with object-gel friction %g.\n",
                  opt.friction);
    o += line;
  }
  return o;
}

std::string join_command(int argc, char** argv) {
  std::string cmd;
  for (int i = 0; i < argc; ++i) ba::append(&cmd, {i ? " " : "", argv[i]});
  return cmd;
}

int run(int argc, char** argv) {
  CLI::App app{
      "Accuracy benchmark: per sensor profile, simulates a calibration set and a separate test "
      "set, calibrates on the first with tacse3-calibrate's fit, evaluates the second through "
      "tacse3-replay's engine, prints the paper's Tables V-B, V-C, V-D and the stick motions, "
      "and a goal matrix across the profiles (docs/accuracy.md)."};
  Options opt;
  app.add_option("--profile", opt.profile,
                 "sensor profile(s): a name, random:N, a comma-separated list, or all: the "
                 "named ones and random:1..3 (tacse3-sim --profile list; docs/sim-profiles.md)")
      ->capture_default_str();
  app.add_flag("--quick", opt.quick, "a reduced set (a few recordings per table)");
  app.add_flag("--cross", opt.cross,
               "also evaluate each profile's calibration on every other profile (quick rows)");
  app.add_option("-j,--jobs", opt.jobs, "recordings simulated and evaluated in parallel")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  const CLI::Validator path = tt::non_empty_path();
  app.add_option("--markdown", opt.markdown, "also write the report (markdown) to this file")
      ->check(path);
  app.add_option("--calibration-out", opt.cal_out,
                 "write the fitted calibration to this file (one profile only)")
      ->check(path);
  app.add_option("--calibration", opt.cal_in,
                 "skip the calibration stage and use this calibration file for every profile")
      ->check(path);
  app.add_option("--friction", opt.friction,
                 "simulate every recording with this object-gel friction coefficient instead of "
                 "each preset's")
      ->check(CLI::Range(0.01, 5.0));
  app.add_option("--fail-above", opt.fail_above,
                 "exit 1 if a goal-bearing profile misses a goal by more than this factor "
                 "(e.g. 3: worse than three times the limit), or a profile fails to calibrate")
      ->check(CLI::Range(1.0, 1000.0));
  if (const int rc = tt::parse_command_line(app, argc, argv); rc >= 0) return rc;
  std::vector<std::string> profiles;
  if (std::string e = tt::parse_profile_list(opt.profile, &profiles); !e.empty()) {
    std::fprintf(stderr, "%s: error: --profile: %s\n", kProg, e.c_str());
    return 2;
  }
  if (!opt.cal_out.empty() && profiles.size() != 1) {
    std::fprintf(stderr, "%s: error: --calibration-out needs exactly one --profile\n", kProg);
    return 2;
  }
  // Before the runs, which take minutes: a typo in an output path must not cost them.
  for (const std::string* out : {&opt.cal_out, &opt.markdown}) {
    std::string e;
    if (!out->empty() && !tacse3::fileio::check_output_file(*out, &e)) {
      std::fprintf(stderr, "%s: error: %s\n", kProg, e.c_str());
      return 1;
    }
  }
  // A --calibration that cannot be read is the user's to fix before minutes of simulation.
  if (!opt.cal_in.empty()) {
    if (auto s = tacse3::config::load_calibration(opt.cal_in, &opt.loaded); !s) {
      std::fprintf(stderr, "%s: error: %s\n", kProg, s.message().c_str());
      return 1;
    }
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<ProfileRun> runs;
  std::vector<ba::ProfileOutcome> outcomes;
  for (const auto& p : profiles) {
    runs.push_back(run_profile(p, opt));
    outcomes.push_back(runs.back().outcome);
  }
  if (!opt.cal_out.empty() && runs[0].outcome.error.empty() && opt.cal_in.empty()) {
    if (auto s = tacse3::config::save_calibration(opt.cal_out, runs[0].cal); !s) {
      std::fprintf(stderr, "%s: error: %s\n", kProg, s.message().c_str());
      return 1;
    }
  }
  std::vector<std::string> failed;
  std::string matrix = ba::goal_matrix(outcomes, opt.fail_above, &failed);
  std::string cross = opt.cross && runs.size() > 1 ? run_cross(runs, opt) : std::string();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::string o = header(join_command(argc, argv), opt, seconds);
  o += "\n### Goals across profiles (worst row per profile; worst over goal-bearing profiles)\n\n";
  o += matrix;
  if (!cross.empty()) {
    o += "\n### Cross-calibration: tracking RMS over slide rotations / stick error (deg), quick "
         "rows\n\n" +
         cross;
  }
  for (const auto& r : runs) ba::append(&o, {"\n", r.tables});
  std::printf("%s", o.c_str());
  if (!opt.markdown.empty()) {
    if (std::string e; !tacse3::fileio::write_file_atomically(opt.markdown, o, &e)) {
      std::fprintf(stderr, "%s: error: %s\n", kProg, e.c_str());
      return 1;
    }
  }
  for (const auto& f : failed)
    std::fprintf(stderr, "%s: goal check failed: %s\n", kProg, f.c_str());
  return failed.empty() || opt.fail_above <= 0.0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  // Every path out of run() goes through here: the report is on stdout.
  return tt::finish_stdout(kProg, run(argc, argv));
}
