// SPDX-License-Identifier: Apache-2.0
// tacse3_bench_latency: runs the daemon's loop several times, paced at 120 Hz with the CAN log to
// /dev/null, and reports the medians over the runs of the latency p50 / p99 (SampleTime -> last
// frame of the cycle handed to the CAN channel; from the later frame's arrival at its capture
// thread; from the earlier frame's) and of the DSP time per sample.
//   default: the sim board (the simulator renders both pads on the capture threads);
//   --replay DIR: a tacse3-sim recording replayed by both pads (pre-rendered frames, looping),
//   the right pad --phase-us after the left;
//   --dsp-priority P: the DSP thread at SCHED_FIFO P, as on the board (needs CAP_SYS_NICE; the
//   daemon says so when it cannot).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "tacse3/firmware/daemon.hpp"

using namespace tacse3;
using namespace tacse3::firmware;

namespace {

// Free-running cameras pair within half a period (docs/firmware.md, Pairing; rpi4-uvc's 4200 us).
constexpr int kReplayPairToleranceUs = 4200;

struct Args {
  int runs = 5;
  double seconds = 3.0;
  std::string replay;  // empty: the sim board
  int phase_us = 1500;
  int dsp_priority = -1;  // -1: the board's (the sim board: 0, normal scheduling)
};

int usage() {
  std::fprintf(
      stderr,
      "usage: tacse3_bench_latency [--replay DIR [--phase-us N]] [--dsp-priority P] "
      "[RUNS=5] [SECONDS=3]\n"
      "  --replay DIR       a tacse3-sim recording, replayed paced by both pads (looping)\n"
      "  --phase-us N       the right pad's frames N us after the left's (0..%d, default "
      "1500)\n"
      "  --dsp-priority P   the DSP thread at SCHED_FIFO P (1..99), as on the board\n",
      kReplayPairToleranceUs);
  return 2;
}

bool parse(int argc, char** argv, Args* a) {
  std::vector<const char*> positional;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--replay") == 0 && i + 1 < argc) {
      a->replay = argv[++i];
    } else if (std::strcmp(argv[i], "--phase-us") == 0 && i + 1 < argc) {
      char* end = nullptr;
      const long v = std::strtol(argv[++i], &end, 10);
      if (*end != '\0' || v < 0 || v > kReplayPairToleranceUs) return false;
      a->phase_us = static_cast<int>(v);
    } else if (std::strcmp(argv[i], "--dsp-priority") == 0 && i + 1 < argc) {
      char* end = nullptr;
      const long v = std::strtol(argv[++i], &end, 10);
      if (*end != '\0' || v < 1 || v > 99) return false;
      a->dsp_priority = static_cast<int>(v);
    } else if (argv[i][0] == '-') {
      return false;
    } else {
      positional.push_back(argv[i]);
    }
  }
  if (positional.size() > 2) return false;
  if (!positional.empty()) a->runs = std::atoi(positional[0]);
  if (positional.size() > 1) a->seconds = std::atof(positional[1]);
  return a->runs >= 1 && a->seconds > 0.0;
}

double median(std::vector<double> v) {
  if (v.empty()) return -1.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The sim board; with --replay, both pads replay the recording, paced and looping.
bool make_board(const Args& a, config::BoardConfig* board, std::string* e) {
  if (!config::load_board(std::filesystem::path(TACSE3_SOURCE_BOARDS_DIR) / "sim/board.toml", board,
                          e)) {
    return false;
  }
  board->can.backend = config::CanBackend::kLog;
  board->can.log = "/dev/null";
  if (a.dsp_priority > 0) board->realtime.dsp_priority = a.dsp_priority;
  if (a.replay.empty()) return true;
  for (std::size_t s = 0; s < 2; ++s) {
    board->sensors[s].backend = config::CameraBackend::kReplay;
    board->sensors[s].device = a.replay;
    board->sensors[s].phase_us = s == 1 ? a.phase_us : 0;
  }
  board->sim.realtime = true;
  board->sim.repeat = true;
  board->pipeline.pair_tolerance_us = kReplayPairToleranceUs;
  return true;
}

struct Series {
  std::vector<double> p50, p99, later50, later99, earlier50, earlier99, dsp, pair_fraction;
  void add(const DaemonSummary& s) {
    p50.push_back(static_cast<double>(s.latency_p50_us));
    p99.push_back(static_cast<double>(s.latency_p99_us));
    later50.push_back(static_cast<double>(s.later_arrival_p50_us));
    later99.push_back(static_cast<double>(s.later_arrival_p99_us));
    earlier50.push_back(static_cast<double>(s.earlier_arrival_p50_us));
    earlier99.push_back(static_cast<double>(s.earlier_arrival_p99_us));
    dsp.push_back(static_cast<double>(s.dsp_p50_us));
    pair_fraction.push_back(
        s.engine.samples ? static_cast<double>(s.engine.pairs) / s.engine.samples : 0.0);
  }
};

void print_run(int r, const DaemonSummary& s) {
  std::printf(
      "run %d: %llu samples (%llu pairs), latency p50 %lld us, p99 %lld us; from the later "
      "arrival p50 %lld us, p99 %lld us; from the earlier p50 %lld us, p99 %lld us; dsp p50 "
      "%lld us\n",
      r, static_cast<unsigned long long>(s.engine.samples),
      static_cast<unsigned long long>(s.engine.pairs), static_cast<long long>(s.latency_p50_us),
      static_cast<long long>(s.latency_p99_us), static_cast<long long>(s.later_arrival_p50_us),
      static_cast<long long>(s.later_arrival_p99_us),
      static_cast<long long>(s.earlier_arrival_p50_us),
      static_cast<long long>(s.earlier_arrival_p99_us), static_cast<long long>(s.dsp_p50_us));
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  if (!parse(argc, argv, &a)) return usage();
  config::BoardConfig board;
  std::string e;
  CalibrationSource cal;
  if (!make_board(a, &board, &e) || !load_calibration_source(TACSE3_SIM_CALIBRATION, &cal, &e)) {
    std::fprintf(stderr, "tacse3_bench_latency: %s\n", e.c_str());
    return 1;
  }
  Options opt;
  opt.verbosity = 0;
  opt.seconds = a.seconds;
  Series series;
  for (int r = 0; r < a.runs; ++r) {
    auto d = Daemon::create(board, opt, cal, stderr, &e);
    if (!d) {
      std::fprintf(stderr, "tacse3_bench_latency: %s\n", e.c_str());
      return 1;
    }
    d->run(false);
    print_run(r + 1, d->summary());
    series.add(d->summary());
  }
  std::printf(
      "median over %d runs of %.1f s (%s): latency p50 %.0f us, p99 %.0f us; from the later "
      "arrival p50 %.0f us, p99 %.0f us; from the earlier p50 %.0f us, p99 %.0f us; dsp time p50 "
      "%.0f us; pairs %.0f %% of samples\n",
      a.runs, a.seconds, a.replay.empty() ? "sim board" : "replay board", median(series.p50),
      median(series.p99), median(series.later50), median(series.later99), median(series.earlier50),
      median(series.earlier99), median(series.dsp), 100.0 * median(series.pair_fraction));
  return 0;
}
