// SPDX-License-Identifier: Apache-2.0
// tacse3_bench_vs_dis: tacse3's block flow and per-sensor pipeline against OpenCV's DIS optical
// flow, on the same simulated frames, each scored against the simulator's true displacement.
//
// Every benchmark runs one thread over the same frames: one grasp per sensor profile, rendered
// in memory (left pad, grey) and reduced to the 160x120 working image by the pipeline's own
// luma stage. One benchmark iteration is one frame; one repetition is exactly one pass over all
// grasps, each measured against its first (untouched) frame. The flow error of each method,
// from an untimed pass over the same frames, is the counter rms_px: the RMS end-point error in
// working px over the flow grid points whose material is in contact (tools/flow_truth.hpp).
// After the runs a summary gives the error per profile and the time ratio of the cheapest DIS
// preset that is at least as accurate as tacse3's per-sensor pipeline.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/video/tracking.hpp>
#include <string>
#include <vector>

#include "tacse3/dsp/block_flow.hpp"
#include "tacse3/dsp/luma.hpp"
#include "tacse3/dsp/pipeline.hpp"
#include "tacse3/sim/profile.hpp"
#include "tacse3/tools/bench.hpp"
#include "tacse3/tools/flow_truth.hpp"
#include "tacse3/tools/sim_source.hpp"

namespace {

using namespace tacse3;

// One grasp: its sensor frames, working images (U8.2 for tacse3, 8-bit for DIS) and the true
// displacement of every frame from frame 0.
struct Sequence {
  std::string profile;
  std::string sim_arguments;
  std::vector<std::vector<std::uint8_t>> frames;  // 320x240 grey
  std::vector<dsp::WorkImage> work;
  std::vector<cv::Mat> work8;
  std::vector<tools::GridTruth> truth;
};

std::vector<Sequence>& sequences() {
  static std::vector<Sequence> s;
  return s;
}

std::int64_t total_frames() {
  std::int64_t n = 0;
  for (const Sequence& s : sequences()) n += static_cast<std::int64_t>(s.frames.size());
  return n;
}

cv::Mat to_8bit(const dsp::WorkImage& w) {
  cv::Mat m(dsp::kWorkHeight, dsp::kWorkWidth, CV_8UC1);
  for (int y = 0; y < dsp::kWorkHeight; ++y) {
    auto* row = m.ptr<std::uint8_t>(y);
    for (int x = 0; x < dsp::kWorkWidth; ++x) {
      row[x] = static_cast<std::uint8_t>(std::min(255, (w.at(x, y) + 2) >> 2));
    }
  }
  return m;
}

// The case tacse3-sim renders with `c.sim_arguments()`, left pad only.
std::string render(const tools::SimCase& c, Sequence* out) {
  sim::SimConfig cfg;
  if (std::string e = tools::make_sim_config(c, &cfg); !e.empty()) return e;
  cfg.sensors = {true, false};
  std::string err;
  auto src = tools::SimSource::create(cfg, c.profile + " " + c.label(), 1, &err);
  if (!src) return err;
  out->profile = c.profile;
  out->sim_arguments = c.sim_arguments();
  sim::PadFields ref;
  for (std::size_t i = 0; i < src->info().frame_count(); ++i) {
    std::array<const dsp::FrameView*, 2> views{};
    if (std::string e = src->read(i, &views); !e.empty()) return e;
    const dsp::FrameView& v = *views[0];
    out->frames.emplace_back(v.data, v.data + v.size_bytes);
    out->work.emplace_back();
    if (dsp::frame_to_work_image(v, out->work.back()) != dsp::Status::kOk) return "bad frame";
    out->work8.push_back(to_8bit(out->work.back()));
    const sim::PadFields& f = src->simulator().fields(sim::Sensor::kLeft);
    if (i == 0) ref = f;
    out->truth.push_back(tools::grid_truth(ref, f));
  }
  if (out->truth.front().contact_count() != 0) return c.label() + ": frame 0 is in contact";
  return {};
}

// The flow error of a method: per profile and over all profiles.
struct Score {
  std::vector<tools::FlowError> per_sequence;
  tools::FlowError all;
};
std::map<std::string, Score>& scores() {
  static std::map<std::string, Score> s;
  return s;
}

// A method has frame(sequence, index), which does the frame's whole work (index 0: take the
// reference), and estimate(), the displacement from frame 0 on the grid.
template <typename Method>
const Score& score(const std::string& name, Method& m) {
  auto it = scores().find(name);
  if (it != scores().end()) return it->second;
  Score sc;
  for (const Sequence& s : sequences()) {
    tools::FlowError e;
    for (std::size_t i = 0; i < s.frames.size(); ++i) {
      m.frame(s, i);
      e.add(s.truth[i], m.estimate());
    }
    sc.all.merge(e);
    sc.per_sequence.push_back(e);
  }
  return scores().emplace(name, sc).first->second;
}

template <typename Method>
void run(benchmark::State& state, const std::string& name, Method& m) {
  const double rms = score(name, m).all.rms_px();
  const std::vector<Sequence>& seqs = sequences();
  std::size_t s = 0, i = 0;
  for (auto _ : state) {
    m.frame(seqs[s], i);
    if (++i == seqs[s].frames.size()) {
      i = 0;
      s = (s + 1) % seqs.size();
    }
  }
  state.counters["rms_px"] = rms;
}

// Stage 2 alone: the block flow on the working image.
class Tacse3Flow {
 public:
  void frame(const Sequence& s, std::size_t i) noexcept {
    if (i == 0) {
      flow_->tare(s.work[0]);
      d_ = {};
    } else {
      flow_->track(s.work[i], d_, valid_);
    }
    benchmark::DoNotOptimize(d_.x.v.data());
  }
  tools::GridFlow estimate() const noexcept { return tools::grid_flow(d_); }

 private:
  std::unique_ptr<dsp::BlockFlow> flow_ = std::make_unique<dsp::BlockFlow>();
  dsp::VectorField d_{};
  dsp::GridMask valid_{};
};

// Stages 1-8 on the sensor frame; its flow is the smoothed field the later stages use.
class Tacse3Sensor {
 public:
  Tacse3Sensor() { (void)p_->configure(dsp::PipelineConfig{}, dsp::Calibration{}); }
  void frame(const Sequence& s, std::size_t i) noexcept {
    const std::vector<std::uint8_t>& f = s.frames[i];
    p_->process(tools::frame_view(f.data(), dsp::kSensorWidth, dsp::kSensorHeight, 1), 1.0 / 120.0,
                out_);
    if (i == 0) p_->tare();
    benchmark::DoNotOptimize(out_.motion.omega.data());
  }
  tools::GridFlow estimate() const noexcept { return tools::grid_flow(p_->fields().smoothed); }

 private:
  std::unique_ptr<dsp::SensorPipeline> p_ = std::make_unique<dsp::SensorPipeline>();
  dsp::SensorResult out_{};
};

// OpenCV's DIS flow from frame 0 to frame i on the 8-bit working image.
class Dis {
 public:
  explicit Dis(int preset) : dis_(cv::DISOpticalFlow::create(preset)) {}
  void frame(const Sequence& s, std::size_t i) {
    dis_->calc(s.work8[0], s.work8[i], flow_);
    benchmark::DoNotOptimize(flow_.data);
  }
  tools::GridFlow estimate() const noexcept {
    return tools::grid_flow(flow_.ptr<float>(), flow_.cols, flow_.rows);
  }

 private:
  cv::Ptr<cv::DISOpticalFlow> dis_;
  cv::Mat flow_;
};

// A flow that reports no motion: its score is the RMS of the true displacement itself, the scale
// every other score is read against.
struct ZeroFlow {
  void frame(const Sequence&, std::size_t) noexcept {}
  tools::GridFlow estimate() const noexcept { return {}; }
};

void BM_Tacse3Flow(benchmark::State& state) {
  Tacse3Flow m;
  run(state, "BM_Tacse3Flow", m);
}
void BM_Tacse3Sensor(benchmark::State& state) {
  Tacse3Sensor m;
  run(state, "BM_Tacse3Sensor", m);
}
void BM_DIS(benchmark::State& state, int preset, const char* name) {
  Dis m(preset);
  run(state, name, m);
}

// The console output plus the runs' median CPU times (µs) for the summary.
class SummaryReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      const std::string name = r.run_name.function_name;
      if (r.run_type == Run::RT_Aggregate && r.aggregate_name == "median") {
        median_[name] = r.GetAdjustedCPUTime();
      } else if (r.run_type == Run::RT_Iteration && !r.error_occurred) {
        times_[name].push_back(r.GetAdjustedCPUTime());
      }
    }
    ConsoleReporter::ReportRuns(runs);
  }
  // Median CPU time per iteration, µs; negative if the benchmark did not run.
  double median_us(const std::string& name) const {
    if (auto it = median_.find(name); it != median_.end()) return it->second;
    auto it = times_.find(name);
    if (it == times_.end() || it->second.empty()) return -1.0;
    std::vector<double> v = it->second;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  }

 private:
  std::map<std::string, double> median_;
  std::map<std::string, std::vector<double>> times_;
};

const char* const kDisNames[] = {"BM_DIS/ultrafast", "BM_DIS/fast", "BM_DIS/medium"};

void print_errors() {
  ZeroFlow zero;
  (void)score("(zero flow)", zero);
  std::printf("\nrms_px per sensor profile (working px, contact region of the flow grid):\n");
  std::printf("%-18s", "benchmark");
  for (const Sequence& s : sequences()) std::printf(" %16s", s.profile.c_str());
  std::printf(" %10s\n", "all");
  for (const auto& [name, sc] : scores()) {
    std::printf("%-18s", name.c_str());
    for (const tools::FlowError& e : sc.per_sequence) std::printf(" %16.3f", e.rms_px());
    std::printf(" %10.3f\n", sc.all.rms_px());
  }
  std::printf("%-18s", "(grid points)");
  for (const tools::FlowError& e : scores()["(zero flow)"].per_sequence) {
    std::printf(" %16lld", static_cast<long long>(e.points()));
  }
  std::printf(" %10lld\n", static_cast<long long>(scores()["(zero flow)"].all.points()));
}

// The goal's ratio: time of the cheapest DIS preset at least as accurate as BM_Tacse3Sensor,
// over BM_Tacse3Sensor's time.
void print_ratio(const SummaryReporter& rep) {
  const double t_sensor = rep.median_us("BM_Tacse3Sensor");
  const auto sensor = scores().find("BM_Tacse3Sensor");
  if (t_sensor <= 0.0 || sensor == scores().end()) {
    std::printf("\nratio: needs BM_Tacse3Sensor in the run\n");
    return;
  }
  const double rms = sensor->second.all.rms_px();
  std::printf("\nagainst BM_Tacse3Sensor (%.0f us, rms_px %.3f):\n", t_sensor, rms);
  const char* best = nullptr;
  double t_best = 0.0;
  for (const char* name : kDisNames) {
    const double t = rep.median_us(name);
    const auto sc = scores().find(name);
    if (t <= 0.0 || sc == scores().end()) continue;
    std::printf("  %-17s %6.2fx the time, %6.2fx the rms_px\n", name, t / t_sensor,
                sc->second.all.rms_px() / rms);
    if (sc->second.all.rms_px() <= rms && (best == nullptr || t < t_best)) {
      best = name;
      t_best = t;
    }
  }
  if (best == nullptr) {
    std::printf("ratio: no DIS preset in this run is as accurate as BM_Tacse3Sensor\n");
  } else {
    std::printf(
        "ratio: %s, the cheapest DIS preset as accurate as BM_Tacse3Sensor, takes %.2fx "
        "its time\n",
        best, t_best / t_sensor);
  }
}

// One grasp per named profile; `random` is left out (its draw depends on the seed).
std::string render_all() {
  for (const char* p :
       {"reference", "soft-thick", "stiff-thin", "coulomb-rim", "halfspace-mjpeg"}) {
    tools::SimCase c = tools::make_sim_case("sphere", "rz", 30.0);
    c.profile = p;
    Sequence s;
    if (std::string e = render(c, &s); !e.empty()) return std::string(p) + ": " + e;
    std::fprintf(stderr, "tacse3_bench_vs_dis: %s: %zu frames (tacse3-sim %s)\n", p,
                 s.frames.size(), s.sim_arguments.c_str());
    sequences().push_back(std::move(s));
  }
  return {};
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  cv::setNumThreads(0);  // one thread, like the pipeline
  if (std::string e = render_all(); !e.empty()) {
    std::fprintf(stderr, "tacse3_bench_vs_dis: %s\n", e.c_str());
    return 1;
  }
  // One iteration per frame and one pass per repetition: every method sees the same frames.
  const std::int64_t n = total_frames();
  std::vector<benchmark::internal::Benchmark*> benches;
  benches.push_back(benchmark::RegisterBenchmark("BM_Tacse3Flow", BM_Tacse3Flow));
  benches.push_back(benchmark::RegisterBenchmark("BM_Tacse3Sensor", BM_Tacse3Sensor));
  const int presets[] = {cv::DISOpticalFlow::PRESET_ULTRAFAST, cv::DISOpticalFlow::PRESET_FAST,
                         cv::DISOpticalFlow::PRESET_MEDIUM};
  for (int k = 0; k < 3; ++k) {
    benches.push_back(benchmark::RegisterBenchmark(kDisNames[k], BM_DIS, presets[k], kDisNames[k]));
  }
  for (benchmark::internal::Benchmark* b : benches) b->Iterations(n)->Unit(benchmark::kMicrosecond);
  SummaryReporter rep;
  benchmark::RunSpecifiedBenchmarks(&rep);
  print_errors();
  print_ratio(rep);
  benchmark::Shutdown();
  return 0;
}
