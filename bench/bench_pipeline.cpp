// SPDX-License-Identifier: Apache-2.0
// tacse3 bench: the whole dual-sensor frame pair through DualPipeline, steady state and per stage,
// and the per-pair cost distribution over simulated grasps with their rare events.
#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

#include "support/scenes.hpp"
#include "tacse3/dsp/pipeline.hpp"
#ifdef TACSE3_BENCH_HAVE_SIM
#include "pair_sequence.hpp"
#endif

namespace {

using namespace tacse3;

// A grasp with a small rotation, rendered once: the benchmark cycles through its frames so the
// pipeline works on real contact (mask, moments, solve) with warm-started flow and NHHD.
struct Frames {
  std::vector<std::vector<std::uint8_t>> pad[2];
  int count = 0;
};

const Frames& frames() {
  static const Frames f = [] {
    Frames out;
    test::GraspScene s;
    s.motion << 0.01, 0.0, 0.04, 0.0, 0.1e-3, 0.0;
    s.grasp_frames = 6;
    s.motion_frames = 10;
    s.hold_frames = 0;
    const test::DotTexture lt(21), rt(22);
    for (int i = 0; i < test::scene_frames(s); ++i) {
      out.pad[0].push_back(test::render_scene_frame(s, lt, 0, i));
      out.pad[1].push_back(test::render_scene_frame(s, rt, 1, i));
    }
    out.count = test::scene_frames(s);
    return out;
  }();
  return f;
}

// Full frame pair: both sensors' luma → flow → smoothing → 𝒢 → NHHD → forces → contact → motion,
// then fusion, moving average and SE(3). The frames go forwards then backwards so the motion
// never stops and keyframes keep switching now and then, as in a long grasp.
void BM_DualFramePair(benchmark::State& state) {
  const Frames& f = frames();
  auto p = std::make_unique<dsp::DualPipeline>();
  dsp::DualConfig cfg;
  if (state.range(0) == 1) cfg.fusion.method = dsp::FusionMethod::kPaper;
  (void)p->configure(cfg, {dsp::Calibration{}, dsp::Calibration{}});
  dsp::DualResult out;
  std::int64_t i = 0;
  for (auto _ : state) {
    const int cycle = static_cast<int>(i % (2 * f.count));
    const int k = cycle < f.count ? cycle : 2 * f.count - 1 - cycle;
    const auto l =
        test::frame_view(f.pad[0][static_cast<std::size_t>(k)], dsp::PixelFormat::kRgb888);
    const auto r =
        test::frame_view(f.pad[1][static_cast<std::size_t>(k)], dsp::PixelFormat::kRgb888);
    p->process(&l, &r, i * 8'333'333, out);
    benchmark::DoNotOptimize(out.twist.data());
    ++i;
  }
  state.SetLabel(state.range(0) == 1 ? "paper fusion" : "joint fusion");
}
BENCHMARK(BM_DualFramePair)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// One sensor's pipeline alone (half of the frame pair without fusion).
void BM_SensorPipeline(benchmark::State& state) {
  const Frames& f = frames();
  auto p = std::make_unique<dsp::SensorPipeline>();
  dsp::SensorResult out;
  std::int64_t i = 0;
  for (auto _ : state) {
    const int cycle = static_cast<int>(i % (2 * f.count));
    const int k = cycle < f.count ? cycle : 2 * f.count - 1 - cycle;
    p->process(test::frame_view(f.pad[0][static_cast<std::size_t>(k)], dsp::PixelFormat::kRgb888),
               1.0 / 120.0, out);
    benchmark::DoNotOptimize(out.motion.omega.data());
    ++i;
  }
}
BENCHMARK(BM_SensorPipeline)->Unit(benchmark::kMicrosecond);

#ifdef TACSE3_BENCH_HAVE_SIM
// Simulated grasps (pair_sequence.hpp) pair by pair: the distribution of the per-pair CPU time,
// and which event the slowest pair carried. One iteration is the whole sequence.
void BM_DualFramePairSequence(benchmark::State& state) {
  const bench::PairSequence& seq = bench::pair_sequence();
  if (!seq.error.empty()) {
    state.SkipWithError(seq.error.c_str());
    return;
  }
  bench::PairTimes times;
  for (auto _ : state) times = bench::run_pair_sequence(seq);
  bench::report_pair_times(times, state);
}
BENCHMARK(BM_DualFramePairSequence)->Iterations(1)->Unit(benchmark::kMillisecond);
#endif

}  // namespace

BENCHMARK_MAIN();
