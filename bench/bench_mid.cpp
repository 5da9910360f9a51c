// SPDX-License-Identifier: Apache-2.0
// tacse3 bench: middle stages per sensor frame (smoothing, Gaussian density, NHHD) and both
// sensors.
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>

#include "tacse3/dsp/density.hpp"
#include "tacse3/dsp/fixed.hpp"
#include "tacse3/dsp/nhhd.hpp"
#include "tacse3/dsp/smoothing.hpp"

namespace {

using namespace tacse3::dsp;

constexpr int kFrames = 16;

// A plausible contact sequence: an indentation (radial source) that grows, twists (vortex) and
// slides (uniform shear) over kFrames frames, plus deterministic block-flow noise (~0.03 px).
// Displacements in working px, Q16.
struct Sequence {
  std::array<VectorField, kFrames> flow{};
  GridMask valid{};
  GridMask valid_with_holes{};
};

std::unique_ptr<Sequence> make_sequence() {
  auto s = std::make_unique<Sequence>();
  std::uint64_t state = 0x9E3779B97F4A7C15ULL;
  const auto noise = [&]() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (static_cast<double>(state >> 11) / 9007199254740992.0 - 0.5) * 0.1;
  };
  for (int t = 0; t < kFrames; ++t) {
    const double depth = 0.5 + 0.05 * t;
    const double twist = 0.02 * t;
    const double slide = 0.1 * t;
    for (int gy = 0; gy < kGridHeight; ++gy) {
      for (int gx = 0; gx < kGridWidth; ++gx) {
        const double x = gx - 19.5 - 2.0;
        const double y = gy - 14.5 + 1.0;
        const double r2 = x * x + y * y;
        const double prof = r2 < 1e-9 ? 0.5 : -std::expm1(-r2 / 32.0) * 16.0 / r2;
        const double u = depth * prof * x - twist * prof * y + slide + noise();
        const double v = depth * prof * y + twist * prof * x - 0.5 * slide + noise();
        s->flow[static_cast<std::size_t>(t)].x(gx, gy) = to_q32<kFieldFrac>(u);
        s->flow[static_cast<std::size_t>(t)].y(gx, gy) = to_q32<kFieldFrac>(v);
      }
    }
  }
  s->valid.fill(1);
  s->valid_with_holes.fill(1);
  for (std::size_t i = 0; i < kGridCount; i += 23) s->valid_with_holes.v[i] = 0;  // ~4 % invalid
  return s;
}

const Sequence& sequence() {
  static const std::unique_ptr<Sequence> s = make_sequence();
  return *s;
}

// Everything one sensor needs in the middle stage, allocated once.
struct MidStage {
  FlowSmoother smoother;
  GaussianDensity density;
  Nhhd nhhd;
  VectorField smooth{};
  GridMask smooth_valid{};
  ScalarField g{};
  VectorField d{};
  VectorField r{};
  VectorField k{};

  void run(const VectorField& flow, const GridMask& valid) {
    smoother.apply(flow, valid, smooth, smooth_valid);
    density.compute(smooth, smooth_valid, g);
    nhhd.decompose(smooth, smooth_valid, d, r, k);
  }
};

// scalar: FlowSmoother::apply_scalar, the reference for the SIMD path's speed-up.
void smoothing(benchmark::State& state, bool scalar) {
  const Sequence& seq = sequence();
  auto stage = std::make_unique<MidStage>();
  const GridMask& valid = state.range(0) != 0 ? seq.valid_with_holes : seq.valid;
  int t = 0;
  for (auto _ : state) {
    const VectorField& in = seq.flow[static_cast<std::size_t>(t)];
    if (scalar) {
      stage->smoother.apply_scalar(in, valid, stage->smooth, stage->smooth_valid);
    } else {
      stage->smoother.apply(in, valid, stage->smooth, stage->smooth_valid);
    }
    benchmark::DoNotOptimize(stage->smooth);
    t = (t + 1) % kFrames;
  }
}
void BM_Smoothing(benchmark::State& state) {
  smoothing(state, false);
}
void BM_SmoothingScalar(benchmark::State& state) {
  smoothing(state, true);
}
BENCHMARK(BM_Smoothing)->ArgName("holes")->Arg(0)->Arg(1);
BENCHMARK(BM_SmoothingScalar)->ArgName("holes")->Arg(0)->Arg(1);

// scalar: GaussianDensity::compute_scalar.
void density(benchmark::State& state, bool scalar) {
  const Sequence& seq = sequence();
  auto stage = std::make_unique<MidStage>();
  const GridMask& valid = state.range(0) != 0 ? seq.valid_with_holes : seq.valid;
  int t = 0;
  for (auto _ : state) {
    const VectorField& u = seq.flow[static_cast<std::size_t>(t)];
    if (scalar) {
      stage->density.compute_scalar(u, valid, stage->g);
    } else {
      stage->density.compute(u, valid, stage->g);
    }
    benchmark::DoNotOptimize(stage->g);
    t = (t + 1) % kFrames;
  }
}
void BM_Density(benchmark::State& state) {
  density(state, false);
}
void BM_DensityScalar(benchmark::State& state) {
  density(state, true);
}
BENCHMARK(BM_Density)->ArgName("holes")->Arg(0)->Arg(1);
BENCHMARK(BM_DensityScalar)->ArgName("holes")->Arg(0)->Arg(1);

// Arg: V-cycles per call (default config = 1).
void BM_Nhhd(benchmark::State& state) {
  const Sequence& seq = sequence();
  auto stage = std::make_unique<MidStage>();
  NhhdConfig config;
  config.cycles = static_cast<int>(state.range(0));
  if (stage->nhhd.configure(config) != Status::kOk) state.SkipWithError("bad config");
  int t = 0;
  for (auto _ : state) {
    stage->nhhd.decompose(seq.flow[static_cast<std::size_t>(t)], seq.valid, stage->d, stage->r,
                          stage->k);
    benchmark::DoNotOptimize(stage->k);
    t = (t + 1) % kFrames;
  }
}
BENCHMARK(BM_Nhhd)->ArgName("cycles")->Arg(1)->Arg(2)->Arg(4);

// Plain warm-started Jacobi (levels = 1) at the same sweep count as one default V-cycle on the
// fine grid (4 sweeps): the cost of the textbook scheme, for comparison.
void BM_NhhdPlainJacobi4Sweeps(benchmark::State& state) {
  const Sequence& seq = sequence();
  auto stage = std::make_unique<MidStage>();
  NhhdConfig config;
  config.levels = 1;
  config.coarsest_sweeps = 4;
  if (stage->nhhd.configure(config) != Status::kOk) state.SkipWithError("bad config");
  int t = 0;
  for (auto _ : state) {
    stage->nhhd.decompose(seq.flow[static_cast<std::size_t>(t)], seq.valid, stage->d, stage->r,
                          stage->k);
    benchmark::DoNotOptimize(stage->k);
    t = (t + 1) % kFrames;
  }
}
BENCHMARK(BM_NhhdPlainJacobi4Sweeps);

// The whole middle stage for one sensor frame: smoothing -> density -> NHHD (default configs).
void BM_MidStageOneSensor(benchmark::State& state) {
  const Sequence& seq = sequence();
  auto stage = std::make_unique<MidStage>();
  int t = 0;
  for (auto _ : state) {
    stage->run(seq.flow[static_cast<std::size_t>(t)], seq.valid);
    benchmark::DoNotOptimize(stage->k);
    t = (t + 1) % kFrames;
  }
}
BENCHMARK(BM_MidStageOneSensor);

// Both sensors of a frame pair (two independent stage objects, as in the dual pipeline).
void BM_MidStageBothSensors(benchmark::State& state) {
  const Sequence& seq = sequence();
  auto left = std::make_unique<MidStage>();
  auto right = std::make_unique<MidStage>();
  int t = 0;
  for (auto _ : state) {
    left->run(seq.flow[static_cast<std::size_t>(t)], seq.valid);
    right->run(seq.flow[static_cast<std::size_t>((t + 5) % kFrames)], seq.valid_with_holes);
    benchmark::DoNotOptimize(left->k);
    benchmark::DoNotOptimize(right->k);
    t = (t + 1) % kFrames;
  }
}
BENCHMARK(BM_MidStageBothSensors);

}  // namespace

BENCHMARK_MAIN();
