// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: every vectorised fixed-point stage equals its scalar path bit for bit, on every
// SIMD target compiled in and supported by this CPU (x86: AVX2, SSE4, the single-lane fallback;
// Arm under qemu: NEON), on random input and saturating edge cases.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "tacse3/dsp/density.hpp"
#include "tacse3/dsp/luma.hpp"
#include "tacse3/dsp/simd.hpp"
#include "tacse3/dsp/smoothing.hpp"

namespace tacse3::dsp {
namespace {

// Runs body(name) once per SIMD target, restoring the best target afterwards.
template <class Body>
void for_each_target(Body body) {
  const int n = simd_target_count();
  ASSERT_GE(n, 1);
  for (int i = 0; i < n; ++i) {
    SCOPED_TRACE(std::string("SIMD target ") + simd_target_name(i));
    simd_select_target(i);
    body();
  }
  simd_select_target(-1);
}

TEST(SimdTargets, TheBoardsGetNeonAndX86GetsAVector) {
  const std::string best = simd_target_name(0);
#if defined(__aarch64__) || defined(__arm__)
  EXPECT_EQ(best, "NEON");
  EXPECT_EQ(simd_target_count(), 1);
#elif defined(__x86_64__)
  if (__builtin_cpu_supports("avx2")) {
    EXPECT_EQ(best, "AVX2");
  } else if (__builtin_cpu_supports("sse4.2")) {
    EXPECT_EQ(best, "SSE4");
  }
  // The single-lane fallback is always last, so the tests below cover the scalar tails too.
  EXPECT_EQ(std::string(simd_target_name(simd_target_count() - 1)), "SCALAR");
#endif
  EXPECT_STREQ(simd_target_name(simd_target_count()), "");
  EXPECT_STREQ(simd_target_name(-1), "");
}

// --- luma + 2x2 box ------------------------------------------------------------------------

int row_bytes(PixelFormat f) {
  return packed_row_bytes(f);
}

// A frame of `format` with `pad` extra bytes per row, filled by gen(i).
template <class Gen>
std::vector<std::uint8_t> make_frame(PixelFormat format, int pad, Gen gen) {
  const std::size_t stride = static_cast<std::size_t>(row_bytes(format) + pad);
  std::vector<std::uint8_t> f(stride * kSensorHeight);
  for (std::size_t i = 0; i < f.size(); ++i) f[i] = gen(i);
  return f;
}

void expect_luma_equal(const std::vector<std::uint8_t>& bytes, PixelFormat format, int pad) {
  FrameView v;
  v.data = bytes.data();
  v.size_bytes = bytes.size();
  v.width = kSensorWidth;
  v.height = kSensorHeight;
  v.stride_bytes = pad == 0 ? 0 : row_bytes(format) + pad;
  v.format = format;
  for (const WorkImageFilter filter : {WorkImageFilter::kBox, WorkImageFilter::kBinomial}) {
    SCOPED_TRACE(filter == WorkImageFilter::kBox ? "box" : "binomial");
    WorkImage scalar;
    WorkImage simd;
    scalar.px.fill(0xBEEF);
    simd.px.fill(0x1234);
    ASSERT_EQ(frame_to_work_image_scalar(v, scalar, filter), Status::kOk);
    ASSERT_EQ(frame_to_work_image(v, simd, filter), Status::kOk);
    int mismatches = 0;
    for (std::size_t p = 0; p < scalar.px.size(); ++p) {
      if (scalar.px[p] != simd.px[p] && ++mismatches <= 5) {
        ADD_FAILURE() << "pixel " << p << ": scalar " << scalar.px[p] << ", SIMD " << simd.px[p];
      }
    }
    EXPECT_EQ(mismatches, 0);
  }
}

const PixelFormat kFormats[] = {PixelFormat::kRgb888, PixelFormat::kYuyv, PixelFormat::kGrey};

TEST(SimdLuma, RandomFramesEqualScalar) {
  for_each_target([] {
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> byte(0, 255);
    for (PixelFormat f : kFormats) {
      // Packed, and an odd padding so rows start at unaligned addresses.
      for (int pad : {0, 7}) {
        SCOPED_TRACE("format " + std::to_string(static_cast<int>(f)) + " pad " +
                     std::to_string(pad));
        expect_luma_equal(
            make_frame(f, pad, [&](std::size_t) { return static_cast<std::uint8_t>(byte(rng)); }),
            f, pad);
      }
    }
  });
}

TEST(SimdLuma, SaturatedAndAlternatingFramesEqualScalar) {
  for_each_target([] {
    for (PixelFormat f : kFormats) {
      SCOPED_TRACE("format " + std::to_string(static_cast<int>(f)));
      // All 255: every block sum at its 1020 maximum, the RGB weighted sum at 261120 (the
      // binomial's at 4177920).
      expect_luma_equal(make_frame(f, 0, [](std::size_t) { return std::uint8_t{255}; }), f, 0);
      expect_luma_equal(make_frame(f, 0, [](std::size_t) { return std::uint8_t{0}; }), f, 0);
      // 0/255 in every byte phase: a lane mix-up between pairs, channels or rows shows.
      for (std::size_t period : {2u, 3u, 4u, 6u}) {
        expect_luma_equal(make_frame(f, 0,
                                     [&](std::size_t i) {
                                       return static_cast<std::uint8_t>(i % period == 0 ? 255 : 0);
                                     }),
                          f, 0);
      }
      // Values at the half-up rounding boundary of the RGB weights: a ramp over all bytes.
      expect_luma_equal(
          make_frame(f, 3, [](std::size_t i) { return static_cast<std::uint8_t>(i * 37 % 256); }),
          f, 3);
    }
  });
}

// --- Gaussian smoothing ----------------------------------------------------------------------

void expect_smoothing_equal(const SmoothingConfig& config, const VectorField& in,
                            const GridMask& valid) {
  FlowSmoother scalar;
  FlowSmoother simd;
  ASSERT_EQ(scalar.configure(config), Status::kOk);
  ASSERT_EQ(simd.configure(config), Status::kOk);
  VectorField out_scalar;
  VectorField out_simd;
  GridMask valid_scalar;
  GridMask valid_simd;
  scalar.apply_scalar(in, valid, out_scalar, valid_scalar);
  simd.apply(in, valid, out_simd, valid_simd);
  int mismatches = 0;
  for (std::size_t p = 0; p < kGridCount; ++p) {
    if ((out_scalar.x.v[p] != out_simd.x.v[p] || out_scalar.y.v[p] != out_simd.y.v[p] ||
         valid_scalar.v[p] != valid_simd.v[p]) &&
        ++mismatches <= 5) {
      ADD_FAILURE() << "point " << p << ": scalar (" << out_scalar.x.v[p] << ", "
                    << out_scalar.y.v[p] << ", " << int{valid_scalar.v[p]} << "), SIMD ("
                    << out_simd.x.v[p] << ", " << out_simd.y.v[p] << ", " << int{valid_simd.v[p]}
                    << ")";
    }
  }
  EXPECT_EQ(mismatches, 0);
  // In place (out aliases in, out_valid aliases valid), as the pipeline may call it.
  VectorField inout = in;
  GridMask mask = valid;
  simd.apply(inout, mask, inout, mask);
  EXPECT_EQ(inout.x.v, out_scalar.x.v);
  EXPECT_EQ(inout.y.v, out_scalar.y.v);
  EXPECT_EQ(mask.v, valid_scalar.v);
}

// Every radius from 1 to kMaxRadius, both support thresholds' extremes.
const SmoothingConfig kSmoothingConfigs[] = {{0.3, 0.25}, {0.7, 0.5},  {1.0, 0.25},
                                             {1.5, 1.0},  {2.0, 0.01}, {3.0, 0.25}};

TEST(SimdSmoothing, RandomFieldsAndMasksEqualScalar) {
  for_each_target([] {
    std::mt19937 rng(11);
    std::uniform_int_distribution<std::int32_t> any(INT32_MIN, INT32_MAX);
    std::uniform_int_distribution<std::int32_t> flow(-(1 << 22), 1 << 22);  // +-64 px in Q16
    for (const SmoothingConfig& c : kSmoothingConfigs) {
      SCOPED_TRACE("sigma " + std::to_string(c.sigma_cells));
      for (int hole_pct : {0, 10, 60}) {
        VectorField in;
        GridMask valid;
        std::uniform_int_distribution<int> pct(0, 99);
        for (std::size_t p = 0; p < kGridCount; ++p) {
          const bool wide = hole_pct == 10;  // one case over the whole int32 range
          in.x.v[p] = wide ? any(rng) : flow(rng);
          in.y.v[p] = wide ? any(rng) : flow(rng);
          valid.v[p] = pct(rng) >= hole_pct ? 1 : 0;
        }
        expect_smoothing_equal(c, in, valid);
      }
    }
  });
}

TEST(SimdSmoothing, SaturatedFieldsAndEdgeMasksEqualScalar) {
  for_each_target([] {
    for (const SmoothingConfig& c : kSmoothingConfigs) {
      SCOPED_TRACE("sigma " + std::to_string(c.sigma_cells));
      VectorField in;
      GridMask valid;
      // Extremes: the row sums reach +-2^46, the column numerators +-2^61.
      in.x.fill(INT32_MAX);
      in.y.fill(INT32_MIN);
      valid.fill(1);
      expect_smoothing_equal(c, in, valid);
      // Alternating extremes (every low 16-bit pattern of the row sums), a checkerboard mask.
      for (std::size_t p = 0; p < kGridCount; ++p) {
        in.x.v[p] = (p % 3 == 0) ? INT32_MIN : INT32_MAX - static_cast<std::int32_t>(p);
        in.y.v[p] = (p % 2 == 0) ? -static_cast<std::int32_t>(p * 4099) : INT32_MIN + 1;
        valid.v[p] = static_cast<std::uint8_t>(((p / kGridWidth) + p) % 2);
      }
      expect_smoothing_equal(c, in, valid);
      valid.fill(0);  // nothing valid: every output 0 and invalid
      expect_smoothing_equal(c, in, valid);
      valid.fill(0);  // one valid point in a corner and one in the middle
      valid.v[0] = 1;
      valid.v[kGridCount / 2 + 7] = 1;
      expect_smoothing_equal(c, in, valid);
    }
  });
}

// --- Gaussian density ------------------------------------------------------------------------

// Both paths over the same calls (the undeformed density is cached per mask, so the second call
// with an unchanged mask takes the cached path).
void expect_density_equal(double sigma, const VectorField& u, const GridMask& valid) {
  GaussianDensity scalar;
  GaussianDensity simd;
  ASSERT_EQ(scalar.configure(DensityConfig{sigma}), Status::kOk);
  ASSERT_EQ(simd.configure(DensityConfig{sigma}), Status::kOk);
  for (int call = 0; call < 2; ++call) {
    ScalarField g_scalar;
    ScalarField g_simd;
    g_scalar.fill(12345);
    g_simd.fill(-1);
    scalar.compute_scalar(u, valid, g_scalar);
    simd.compute(u, valid, g_simd);
    EXPECT_EQ(scalar.density().v, simd.density().v) << "call " << call;
    EXPECT_EQ(g_scalar.v, g_simd.v) << "call " << call;
  }
}

const double kDensitySigmas[] = {0.5, 0.8, 1.0, 1.37, 2.0};

TEST(SimdDensity, RandomDisplacementsAndMasksEqualScalar) {
  for_each_target([] {
    std::mt19937 rng(5);
    std::uniform_int_distribution<std::int32_t> any(INT32_MIN, INT32_MAX);
    std::uniform_int_distribution<std::int32_t> flow(-(6 << 16), 6 << 16);  // +-6 px in Q16
    std::uniform_int_distribution<int> pct(0, 99);
    for (double sigma : kDensitySigmas) {
      SCOPED_TRACE("sigma " + std::to_string(sigma));
      for (int hole_pct : {0, 15, 70}) {
        VectorField u;
        GridMask valid;
        for (std::size_t p = 0; p < kGridCount; ++p) {
          const bool wide = hole_pct == 15;  // one case over the whole int32 range (clamped)
          u.x.v[p] = wide ? any(rng) : flow(rng);
          u.y.v[p] = wide ? any(rng) : flow(rng);
          valid.v[p] = pct(rng) >= hole_pct ? 1 : 0;
        }
        expect_density_equal(sigma, u, valid);
      }
    }
  });
}

TEST(SimdDensity, ClampedAndDegenerateInputsEqualScalar) {
  for_each_target([] {
    for (double sigma : kDensitySigmas) {
      SCOPED_TRACE("sigma " + std::to_string(sigma));
      VectorField u;
      GridMask valid;
      valid.fill(1);
      expect_density_equal(sigma, u, valid);  // no motion: G == 0 everywhere
      // Alternating extremes: every pair distance at the component clamp.
      for (std::size_t p = 0; p < kGridCount; ++p) {
        u.x.v[p] = p % 2 == 0 ? INT32_MAX : INT32_MIN;
        u.y.v[p] = (p / kGridWidth) % 2 == 0 ? INT32_MIN : INT32_MAX;
      }
      expect_density_equal(sigma, u, valid);
      // Compression by 0.3 cells per cell (distances through the LUT's whole range).
      for (int y = 0; y < kGridHeight; ++y) {
        for (int x = 0; x < kGridWidth; ++x) {
          u.x(x, y) = -x * (kGridStride << 16) * 3 / 10;
          u.y(x, y) = y * (kGridStride << 16) / 7;
        }
      }
      expect_density_equal(sigma, u, valid);
      // Only the first and last columns valid (row tails), then nothing valid.
      for (int y = 0; y < kGridHeight; ++y) {
        for (int x = 0; x < kGridWidth; ++x) valid(x, y) = x < 3 || x >= kGridWidth - 3 ? 1 : 0;
      }
      expect_density_equal(sigma, u, valid);
      valid.fill(0);
      expect_density_equal(sigma, u, valid);
    }
  });
}

}  // namespace
}  // namespace tacse3::dsp
