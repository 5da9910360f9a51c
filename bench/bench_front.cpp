// SPDX-License-Identifier: Apache-2.0
// tacse3 bench: front end (luma conversion, pyramid, block flow steady state and keyframe switch).
#include <benchmark/benchmark.h>

#include <vector>

#include "support/synthetic.hpp"
#include "tacse3/dsp/block_flow.hpp"
#include "tacse3/dsp/luma.hpp"
#include "tacse3/dsp/pyramid.hpp"

namespace {

using tacse3::dsp::BlockFlow;
using tacse3::dsp::GridMask;
using tacse3::dsp::PixelFormat;
using tacse3::dsp::VectorField;
using tacse3::dsp::WorkImage;
namespace test = tacse3::test;

const test::DotTexture& texture() {
  static const test::DotTexture tex(2024);
  return tex;
}

// Realistic disturbances: sensor noise and a slight LED gain change between frames.
test::Photometric photometric(std::uint64_t seed, double gain) {
  test::Photometric ph;
  ph.noise_sigma = 1.0;
  ph.noise_seed = seed;
  ph.gain = gain;
  ph.vignetting = 0.15;
  return ph;
}

// scalar: frame_to_work_image_scalar, the reference for the SIMD path's speed-up
// (docs/performance.md).
void luma(benchmark::State& state, PixelFormat format, bool scalar = false,
          tacse3::dsp::WorkImageFilter filter = tacse3::dsp::WorkImageFilter::kBox) {
  const auto bytes = test::render_frame(texture(), test::Warp::identity(), format);
  const auto view = test::frame_view(bytes, format);
  WorkImage out;
  for (auto _ : state) {
    benchmark::DoNotOptimize(scalar ? tacse3::dsp::frame_to_work_image_scalar(view, out, filter)
                                    : tacse3::dsp::frame_to_work_image(view, out, filter));
    benchmark::ClobberMemory();
  }
}
void BM_LumaRgb888(benchmark::State& state) {
  luma(state, PixelFormat::kRgb888);
}
void BM_LumaYuyv(benchmark::State& state) {
  luma(state, PixelFormat::kYuyv);
}
void BM_LumaGrey(benchmark::State& state) {
  luma(state, PixelFormat::kGrey);
}
void BM_LumaRgb888Scalar(benchmark::State& state) {
  luma(state, PixelFormat::kRgb888, true);
}
void BM_LumaYuyvScalar(benchmark::State& state) {
  luma(state, PixelFormat::kYuyv, true);
}
void BM_LumaGreyScalar(benchmark::State& state) {
  luma(state, PixelFormat::kGrey, true);
}
// The binomial working image (antialias_filter = 1).
void BM_LumaBinomialRgb888(benchmark::State& state) {
  luma(state, PixelFormat::kRgb888, false, tacse3::dsp::WorkImageFilter::kBinomial);
}
void BM_LumaBinomialGrey(benchmark::State& state) {
  luma(state, PixelFormat::kGrey, false, tacse3::dsp::WorkImageFilter::kBinomial);
}
void BM_LumaBinomialRgb888Scalar(benchmark::State& state) {
  luma(state, PixelFormat::kRgb888, true, tacse3::dsp::WorkImageFilter::kBinomial);
}
BENCHMARK(BM_LumaRgb888);
BENCHMARK(BM_LumaYuyv);
BENCHMARK(BM_LumaGrey);
BENCHMARK(BM_LumaRgb888Scalar);
BENCHMARK(BM_LumaYuyvScalar);
BENCHMARK(BM_LumaGreyScalar);
BENCHMARK(BM_LumaBinomialRgb888);
BENCHMARK(BM_LumaBinomialGrey);
BENCHMARK(BM_LumaBinomialRgb888Scalar);

void BM_Pyramid3(benchmark::State& state) {
  const WorkImage img = test::render_work_image(texture(), test::Warp::identity());
  static tacse3::dsp::ImagePyramid pyr;
  for (auto _ : state) {
    tacse3::dsp::build_pyramid(img, 3, pyr);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_Pyramid3);

// Steady state: the tracker is warm and alternates between two frames 0.2 working px apart
// (a slowly moving contact, with sensor noise, vignetting and +-2 % LED gain), well below the
// keyframe threshold, so every iteration is a normal warm-started frame (level 0 converges from
// the warm start; the coarse levels are not needed).
void steady(benchmark::State& state, int coarse_trigger) {
  const WorkImage a =
      test::render_work_image(texture(), test::Warp::identity(), photometric(1, 1.0));
  const WorkImage b =
      test::render_work_image(texture(), test::Warp::shift(1.2, 0.6), photometric(2, 1.02));
  const WorkImage c =
      test::render_work_image(texture(), test::Warp::shift(1.6, 0.8), photometric(3, 0.98));
  static BlockFlow flow;
  tacse3::dsp::BlockFlowConfig cfg;
  cfg.coarse_trigger = coarse_trigger;
  (void)flow.configure(cfg);
  VectorField d;
  GridMask v;
  flow.tare(a);
  flow.track(b, d, v);
  bool odd = false;
  for (auto _ : state) {
    flow.track(odd ? b : c, d, v);
    odd = !odd;
    benchmark::DoNotOptimize(d);
  }
  state.counters["valid"] = flow.valid_count();
  state.counters["switches"] = flow.keyframe_switches();
}
void BM_BlockFlowSteady(benchmark::State& state) {
  steady(state, tacse3::dsp::BlockFlowConfig{}.coarse_trigger);
}
BENCHMARK(BM_BlockFlowSteady);
// The same with the coarse levels forced on every frame (coarse_trigger = 0).
void BM_BlockFlowSteadyCoarseEveryFrame(benchmark::State& state) {
  steady(state, 0);
}
BENCHMARK(BM_BlockFlowSteadyCoarseEveryFrame);

// A keyframe-switch frame: the same slowly moving scene as BM_BlockFlowSteady, but with the
// switch threshold lowered to 0.1 working px so that every frame switches. Each iteration is a
// normal warm-started frame plus the work of two switches: its own direct re-match against the
// tare frame (re-anchoring: one level-0 pass against the tare frame's kept models) and the
// level-0 window models of the keyframe the previous iteration took. The coarse levels are never
// built (no frame needs them, and every keyframe is replaced within a frame).
void BM_BlockFlowKeyframeSwitch(benchmark::State& state) {
  const WorkImage a =
      test::render_work_image(texture(), test::Warp::identity(), photometric(1, 1.0));
  const WorkImage b =
      test::render_work_image(texture(), test::Warp::shift(1.2, 0.6), photometric(2, 1.02));
  const WorkImage c =
      test::render_work_image(texture(), test::Warp::shift(1.6, 0.8), photometric(3, 0.98));
  tacse3::dsp::BlockFlowConfig cfg;
  cfg.keyframe_switch_px = 0.1;
  static BlockFlow flow;
  (void)flow.configure(cfg);
  VectorField d;
  GridMask v;
  flow.tare(a);
  flow.track(b, d, v);
  const std::uint32_t before = flow.keyframe_switches();
  bool odd = false;
  for (auto _ : state) {
    flow.track(odd ? b : c, d, v);
    odd = !odd;
    benchmark::DoNotOptimize(d);
  }
  state.counters["valid"] = flow.valid_count();
  state.counters["switch_ratio"] = static_cast<double>(flow.keyframe_switches() - before) /
                                   static_cast<double>(state.iterations());
}
BENCHMARK(BM_BlockFlowKeyframeSwitch);

// A frame after a sudden jump of (2.5, 0) working px with the warm start pointing the wrong
// way: level 0 fails, the coarse levels run and the failed windows are retried. The tracker is
// re-tared on the reference frame every iteration (outside the timed region).
void BM_BlockFlowJumpFrame(benchmark::State& state) {
  const WorkImage a =
      test::render_work_image(texture(), test::Warp::identity(), photometric(1, 1.0));
  const WorkImage b =
      test::render_work_image(texture(), test::Warp::shift(5.0, 0.0), photometric(2, 1.02));
  tacse3::dsp::BlockFlowConfig cfg;
  cfg.keyframe_switch_px = 0.0;  // measure the jump alone
  static BlockFlow flow;
  (void)flow.configure(cfg);
  VectorField d;
  GridMask v;
  for (auto _ : state) {
    state.PauseTiming();
    flow.tare(a);
    state.ResumeTiming();
    flow.track(b, d, v);
    benchmark::DoNotOptimize(d);
  }
  state.counters["valid"] = flow.valid_count();
}
BENCHMARK(BM_BlockFlowJumpFrame);

// Tare alone (pyramid + level-0 window models; the coarse levels follow in later frames).
void BM_BlockFlowTare(benchmark::State& state) {
  const WorkImage a = test::render_work_image(texture(), test::Warp::identity());
  static BlockFlow flow;
  for (auto _ : state) {
    flow.tare(a);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_BlockFlowTare);

}  // namespace

BENCHMARK_MAIN();
