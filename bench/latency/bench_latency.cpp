// SPDX-License-Identifier: Apache-2.0
// tacse3_bench_latency: runs the daemon's loop on the sim board (paced at 120 Hz, CAN log to
// /dev/null) several times and reports the medians over the runs of the latency p50 / p99 (frame
// timestamp -> last frame of the cycle handed to the CAN channel) and of the DSP time per sample.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "tacse3/firmware/daemon.hpp"

using namespace tacse3;
using namespace tacse3::firmware;

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return -1.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 ? std::atoi(argv[1]) : 5;
  const double seconds = argc > 2 ? std::atof(argv[2]) : 3.0;
  if (runs < 1 || seconds <= 0.0) {
    std::fprintf(stderr, "usage: tacse3_bench_latency [RUNS=5] [SECONDS=3]\n");
    return 2;
  }
  config::BoardConfig board;
  std::string e;
  if (!config::load_board(std::filesystem::path(TACSE3_SOURCE_BOARDS_DIR) / "sim/board.toml",
                          &board, &e)) {
    std::fprintf(stderr, "tacse3_bench_latency: %s\n", e.c_str());
    return 1;
  }
  board.can.backend = config::CanBackend::kLog;
  board.can.log = "/dev/null";
  CalibrationSource cal;
  if (!load_calibration_source(TACSE3_SIM_CALIBRATION, &cal, &e)) {
    std::fprintf(stderr, "tacse3_bench_latency: %s\n", e.c_str());
    return 1;
  }
  Options opt;
  opt.verbosity = 0;
  opt.seconds = seconds;
  std::vector<double> p50, p99, dsp, pair_fraction;
  for (int r = 0; r < runs; ++r) {
    auto d = Daemon::create(board, opt, cal, stderr, &e);
    if (!d) {
      std::fprintf(stderr, "tacse3_bench_latency: %s\n", e.c_str());
      return 1;
    }
    d->run(false);
    const DaemonSummary& s = d->summary();
    std::printf(
        "run %d: %llu samples (%llu pairs), latency p50 %lld us, p99 %lld us, dsp p50 %lld us\n",
        r + 1, static_cast<unsigned long long>(s.engine.samples),
        static_cast<unsigned long long>(s.engine.pairs), static_cast<long long>(s.latency_p50_us),
        static_cast<long long>(s.latency_p99_us), static_cast<long long>(s.dsp_p50_us));
    p50.push_back(static_cast<double>(s.latency_p50_us));
    p99.push_back(static_cast<double>(s.latency_p99_us));
    dsp.push_back(static_cast<double>(s.dsp_p50_us));
    pair_fraction.push_back(
        s.engine.samples ? static_cast<double>(s.engine.pairs) / s.engine.samples : 0.0);
  }
  std::printf(
      "median over %d runs of %.1f s: latency p50 %.0f us, p99 %.0f us; dsp time p50 %.0f us; "
      "pairs %.0f %% of samples\n",
      runs, seconds, median(p50), median(p99), median(dsp), 100.0 * median(pair_fraction));
  return 0;
}
