// SPDX-License-Identifier: Apache-2.0
// tacse3 bench: a long dual-pad sequence of simulated grasps with the pipeline's rare events
// (keyframe switches, contact onset and release, tares, a lost pad), timed pair by pair.
#pragma once

#include <benchmark/benchmark.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace tacse3::bench {

// What a frame pair carries, as bit flags; a pair may carry several.
enum PairEvent : unsigned {
  kKeyframeSwitch = 1u << 0,  // either pad's block flow took a new keyframe
  kOnset = 1u << 1,           // either pad's true contact began
  kRelease = 1u << 2,         // either pad's true contact ended
  kTare = 1u << 3,            // a tare was requested just before the pair, or it is the next
  kLostPad = 1u << 4,         // one pad's frame is missing, or is back after missing
  kCoarseFallback = 1u << 5,  // either pad's block flow ran its coarse levels
};
inline constexpr int kPairEventCount = 6;
const char* event_name(unsigned event) noexcept;
std::string event_names(unsigned events);  // "keyframe switch+onset", or "none"

struct PairFrames {
  std::array<std::vector<std::uint8_t>, 2> pad;  // GREY 320x240; empty: no frame this cycle
  unsigned events = 0;                           // all but kKeyframeSwitch, known in advance
};

struct PairSequence {
  std::vector<PairFrames> pairs;
  std::string error;  // rendering failed
};

// Rendered once, on first use: six grasps with release (tacse3-sim --release-s 0.2), each
// preceded by a tare, one of them with a left pad lost for a few cycles mid-motion.
const PairSequence& pair_sequence();

struct PairTimes {
  // Thread CPU time of each pair from its frames to its result (tare included on its pair):
  // both pads' image stages and the pair's finish, what a cycle's latency waits for.
  std::vector<double> us;
  // The pads' deferred image work after the result (a keyframe switch), which the daemon runs on
  // each pad's thread once the frame is handed on: off the latency, not off the CPU budget.
  std::vector<double> deferred_us;
  std::vector<unsigned> events;
  // Pad frames tracked, those whose block flow ran its coarse levels, the level-0 failures that
  // triggered those runs (and of them, the windows the frame before had tracked), and the
  // windows the runs recovered and the coarse windows they tracked
  // (dsp::BlockFlow::last_coarse_fallback()).
  std::size_t pad_frames = 0;
  std::size_t coarse_runs = 0;
  long coarse_failed = 0;
  long coarse_failed_fresh = 0;
  long coarse_recovered = 0;
  long coarse_windows = 0;
};

PairTimes run_pair_sequence(const PairSequence& seq);

// Counters p50_us, p99_us, max_us and the largest pair of each event (<event>_max_us), of the
// frames-to-result time; deferred_max_us, and cycle_p50_us / cycle_max_us of the whole cycle's
// CPU time (result + deferred); coarse_share, the share of pad frames whose block flow ran its
// coarse levels, coarse_fresh_failures, the share of the failures behind those runs that the
// frame before had tracked, coarse_recovered_per_run, the windows a run recovered on average, and
// coarse_windows_per_run, the coarse windows it tracked on average (of 370). The label names the
// slowest pair and its events.
void report_pair_times(const PairTimes& times, benchmark::State& state);

}  // namespace tacse3::bench
