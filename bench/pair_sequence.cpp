// SPDX-License-Identifier: Apache-2.0
// tacse3 bench: simulated grasps for BM_DualFramePairSequence, and the per-pair timing.
#include "pair_sequence.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "tacse3/dsp/pipeline.hpp"
#include "tacse3/tools/bench.hpp"
#include "tacse3/tools/sim_source.hpp"

namespace tacse3::bench {

namespace {

constexpr std::int64_t kPeriodNs = 8'333'333;  // 120 Hz
constexpr int kLostCycles = 6;                 // left pad missing for this many pairs

// Appends one grasp; `lose_left` drops the left frames of kLostCycles pairs at 60 % of it.
std::string append_grasp(const char* motion, double magnitude, bool lose_left, PairSequence* seq) {
  tools::SimCase c = tools::make_sim_case("sphere", motion, magnitude);
  c.release_s = 0.2;
  sim::SimConfig cfg;
  if (std::string e = tools::make_sim_config(c, &cfg); !e.empty()) return e;
  std::string err;
  auto src = tools::SimSource::create(cfg, c.label(), 1, &err);
  if (!src) return err;
  const std::size_t n = src->info().frame_count();
  const std::size_t lost_from = lose_left ? n * 6 / 10 : n;
  std::array<bool, 2> was_in_contact{false, false};
  for (std::size_t i = 0; i < n; ++i) {
    std::array<const dsp::FrameView*, 2> views{};
    if (std::string e = src->read(i, &views); !e.empty()) return e;
    PairFrames p;
    p.events = i == 0 ? kTare : 0u;
    for (std::size_t k = 0; k < 2; ++k) {
      const bool in = src->simulator().labels(static_cast<sim::Sensor>(k)).in_contact;
      if (in && !was_in_contact[k]) p.events |= kOnset;
      if (!in && was_in_contact[k]) p.events |= kRelease;
      was_in_contact[k] = in;
      const bool lost = k == 0 && i >= lost_from && i < lost_from + kLostCycles;
      if (!lost) p.pad[k].assign(views[k]->data, views[k]->data + views[k]->size_bytes);
    }
    if (i >= lost_from && i <= lost_from + kLostCycles) p.events |= kLostPad;
    seq->pairs.push_back(std::move(p));
  }
  return {};
}

double thread_cpu_us() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e6 + static_cast<double>(ts.tv_nsec) * 1e-3;
}

// Nearest-rank percentile of sorted values.
double percentile(const std::vector<double>& sorted, double p) {
  const auto rank = static_cast<std::size_t>(std::ceil(p / 100.0 * sorted.size()));
  return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

}  // namespace

const char* event_name(unsigned event) noexcept {
  switch (event) {
    case kKeyframeSwitch:
      return "keyframe switch";
    case kOnset:
      return "onset";
    case kRelease:
      return "release";
    case kTare:
      return "tare";
    case kLostPad:
      return "lost pad";
    case kCoarseFallback:
      return "coarse fallback";
    default:
      return "?";
  }
}

std::string event_names(unsigned events) {
  std::string s;
  for (int b = 0; b < kPairEventCount; ++b) {
    if (!(events & (1u << b))) continue;
    if (!s.empty()) s += "+";
    s += event_name(1u << b);
  }
  return s.empty() ? "none" : s;
}

const PairSequence& pair_sequence() {
  static const PairSequence seq = [] {
    PairSequence s;
    const struct {
      const char* motion;
      double magnitude;
      bool lose_left;
    } grasps[] = {{"rz", 30.0, false}, {"rx", 20.0, true},  {"ry", -20.0, false},
                  {"tx", 2.0, false},  {"ty", -2.0, false}, {"rz", -30.0, false}};
    for (const auto& g : grasps) {
      s.error = append_grasp(g.motion, g.magnitude, g.lose_left, &s);
      if (!s.error.empty()) return s;
    }
    if (s.pairs.size() < 1000) {
      s.error = std::to_string(s.pairs.size()) + " pairs rendered, fewer than 1000";
    }
    return s;
  }();
  return seq;
}

PairTimes run_pair_sequence(const PairSequence& seq) {
  auto p = std::make_unique<dsp::DualPipeline>();
  (void)p->configure(dsp::DualConfig{}, {dsp::Calibration{}, dsp::Calibration{}});
  dsp::DualResult out;
  auto stages = std::make_unique<std::array<dsp::PadStages, 2>>();
  PairTimes t;
  t.us.reserve(seq.pairs.size());
  t.deferred_us.reserve(seq.pairs.size());
  t.events.reserve(seq.pairs.size());
  std::int64_t t_ns = 0;
  bool tare_taken = false;  // this pair's stages took a tare request (firmware::PadStager)
  bool tared = false;       // the previous pair became the reference: its successor restarts
  for (const PairFrames& pair : seq.pairs) {
    std::array<dsp::FrameView, 2> v{};
    for (std::size_t k = 0; k < 2; ++k) {
      if (!pair.pad[k].empty()) {
        v[k] = tools::frame_view(pair.pad[k].data(), dsp::kSensorWidth, dsp::kSensorHeight, 1);
      }
    }
    // DualPipeline::process() in its parts, as the daemon runs them. A tare: the pair's filters
    // and pose restart at once, the pads take it with this pair's stages and make these frames
    // the reference in their deferred work, and their motion restarts with the next pair.
    const double start = thread_cpu_us();
    if (pair.events & kTare) {
      p->restart_filters();
      p->reset_pose();
      tare_taken = true;
    }
    if (tared) {
      for (std::size_t k = 0; k < 2; ++k)
        p->sensor_mut(static_cast<dsp::SensorSlot>(k)).reset_motion();
    }
    std::array<const dsp::PadStages*, 2> staged{};
    for (std::size_t k = 0; k < 2; ++k) {
      if (pair.pad[k].empty()) continue;
      p->process_pad(static_cast<dsp::SensorSlot>(k), v[k], (*stages)[k]);
      staged[k] = &(*stages)[k];
    }
    p->finish(staged[0], staged[1], t_ns, out);
    const double result = thread_cpu_us();
    for (std::size_t k = 0; k < 2; ++k) {
      dsp::SensorPipeline& sp = p->sensor_mut(static_cast<dsp::SensorSlot>(k));
      sp.run_deferred();
      if (tare_taken) sp.tare_image();
    }
    t.deferred_us.push_back(thread_cpu_us() - result);
    t.us.push_back(result - start);
    benchmark::DoNotOptimize(out.twist.data());
    unsigned events = pair.events | (tared ? kTare : 0u);
    tared = tare_taken;
    tare_taken = false;
    if (out.sensors[0].keyframe_switched || out.sensors[1].keyframe_switched) {
      events |= kKeyframeSwitch;
    }
    for (std::size_t k = 0; k < 2; ++k) {
      if (pair.pad[k].empty()) continue;
      const auto& c = p->sensor(static_cast<dsp::SensorSlot>(k)).flow().last_coarse_fallback();
      ++t.pad_frames;
      if (!c.ran) continue;
      events |= kCoarseFallback;
      ++t.coarse_runs;
      t.coarse_failed += c.failed;
      t.coarse_failed_fresh += c.failed_fresh;
      t.coarse_recovered += c.recovered;
      t.coarse_windows += c.coarse_windows;
    }
    t.events.push_back(events);
    t_ns += kPeriodNs;
  }
  return t;
}

void report_pair_times(const PairTimes& times, benchmark::State& state) {
  std::vector<double> sorted = times.us;
  std::sort(sorted.begin(), sorted.end());
  state.counters["pairs"] = static_cast<double>(sorted.size());
  state.counters["p50_us"] = percentile(sorted, 50.0);
  state.counters["p99_us"] = percentile(sorted, 99.0);
  state.counters["max_us"] = sorted.back();
  std::vector<double> cycle(times.us.size());
  for (std::size_t i = 0; i < cycle.size(); ++i) cycle[i] = times.us[i] + times.deferred_us[i];
  std::sort(cycle.begin(), cycle.end());
  state.counters["cycle_p50_us"] = percentile(cycle, 50.0);
  state.counters["cycle_max_us"] = cycle.back();
  state.counters["deferred_max_us"] =
      *std::max_element(times.deferred_us.begin(), times.deferred_us.end());
  std::array<double, kPairEventCount> event_max{};
  std::size_t slowest = 0;
  for (std::size_t i = 0; i < times.us.size(); ++i) {
    if (times.us[i] > times.us[slowest]) slowest = i;
    for (int b = 0; b < kPairEventCount; ++b) {
      if (times.events[i] & (1u << b)) {
        event_max[static_cast<std::size_t>(b)] =
            std::max(event_max[static_cast<std::size_t>(b)], times.us[i]);
      }
    }
  }
  for (int b = 0; b < kPairEventCount; ++b) {
    std::string key = event_name(1u << b);
    std::replace(key.begin(), key.end(), ' ', '_');
    state.counters[key + "_max_us"] = event_max[static_cast<std::size_t>(b)];
  }
  state.counters["coarse_share"] = static_cast<double>(times.coarse_runs) /
                                   static_cast<double>(std::max<std::size_t>(times.pad_frames, 1));
  state.counters["coarse_fresh_failures"] =
      static_cast<double>(times.coarse_failed_fresh) /
      static_cast<double>(std::max<long>(times.coarse_failed, 1));
  state.counters["coarse_recovered_per_run"] =
      static_cast<double>(times.coarse_recovered) /
      static_cast<double>(std::max<std::size_t>(times.coarse_runs, 1));
  state.counters["coarse_windows_per_run"] =
      static_cast<double>(times.coarse_windows) /
      static_cast<double>(std::max<std::size_t>(times.coarse_runs, 1));
  state.SetLabel("max: pair " + std::to_string(slowest) + " (" +
                 event_names(times.events[slowest]) + ")");
}

}  // namespace tacse3::bench
