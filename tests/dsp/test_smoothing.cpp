// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: separable Gaussian smoothing of the flow (normalised convolution, Q15 taps).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <numbers>
#include <string>

#include "support/fields.hpp"
#include "tacse3/dsp/fixed.hpp"
#include "tacse3/dsp/smoothing.hpp"
#include "tacse3/dsp_ref/smoothing_ref.hpp"

namespace tacse3::dsp {
namespace {

namespace f = test::fields;
using dsp_ref::GridMaskD;
using dsp_ref::GridVectorD;

std::unique_ptr<FlowSmoother> make_smoother(const SmoothingConfig& config = {}) {
  auto s = std::make_unique<FlowSmoother>();
  EXPECT_EQ(s->configure(config), Status::kOk);
  return s;
}

GridMask all_valid() {
  GridMask m;
  m.fill(1);
  return m;
}

TEST(Smoothing, TapsAreQ15SymmetricAndSumToOne) {
  auto s = make_smoother();
  EXPECT_EQ(s->radius(), 3);  // ceil(3 sigma) at sigma = 1
  std::int32_t sum = 0;
  for (int i = -s->radius(); i <= s->radius(); ++i) {
    EXPECT_EQ(s->tap(i), s->tap(-i));
    EXPECT_GE(s->tap(i), 1);
    sum += s->tap(i);
  }
  EXPECT_EQ(sum, 1 << 15);
  // Against the continuous Gaussian normalised over [-3, 3]: within 1 LSB of Q15.
  double norm = 0.0;
  for (int i = -3; i <= 3; ++i) norm += std::exp(-0.5 * i * i);
  for (int i = 0; i <= 3; ++i) {
    EXPECT_NEAR(s->tap(i), 32768.0 * std::exp(-0.5 * i * i) / norm, 1.0) << i;
  }
  EXPECT_EQ(s->tap(4), 0);
}

TEST(Smoothing, ConstantFieldIsReproducedExactly) {
  // Normalised convolution of a constant is the constant, at the edges and around holes too.
  auto s = make_smoother();
  f::Rng rng(1);
  const GridMask holes = dsp_ref::grid_mask_to(f::random_mask(rng, 0.2));
  for (const GridMask& m : {all_valid(), holes}) {
    VectorField w;
    w.x.fill(123456789);
    w.y.fill(-98765);
    VectorField out;
    GridMask ov;
    s->apply(w, m, out, ov);
    for (std::size_t i = 0; i < kGridCount; ++i) {
      if (ov.v[i] == 0) continue;
      ASSERT_EQ(out.x.v[i], 123456789);
      ASSERT_EQ(out.y.v[i], -98765);
    }
  }
}

TEST(Smoothing, AffineFieldIsReproducedExactlyInTheInterior) {
  // A symmetric kernel leaves an affine field unchanged where the whole support is inside the
  // grid: sum g_i (a + b i) = a. Bit-exact with integer slopes (in LSB per cell).
  auto s = make_smoother();
  VectorField w;
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      w.x(gx, gy) = 1000 * gx - 3000 * gy + 77;
      w.y(gx, gy) = -12345 * gx + 501 * gy;
    }
  }
  VectorField out;
  GridMask ov;
  s->apply(w, all_valid(), out, ov);
  for (int gy = 3; gy < kGridHeight - 3; ++gy) {
    for (int gx = 3; gx < kGridWidth - 3; ++gx) {
      ASSERT_EQ(out.x(gx, gy), w.x(gx, gy));
      ASSERT_EQ(out.y(gx, gy), w.y(gx, gy));
    }
  }
  // At the edges the truncated kernel is renormalised: a one-sided mean, biased by the slope
  // times the centroid offset of the half kernel (0.52 cells at sigma 1), never pulled to 0.
  const double offset = (s->tap(1) + 2.0 * s->tap(2) + 3.0 * s->tap(3)) /
                        (s->tap(0) + s->tap(1) + s->tap(2) + s->tap(3));
  EXPECT_NEAR(out.x(0, 15) - w.x(0, 15), 1000.0 * offset, 1.0);
  EXPECT_NEAR(offset, 0.52, 0.01);
}

TEST(Smoothing, SinusoidIsAttenuatedLikeTheGaussian) {
  // Transfer function of a Gaussian of sigma cells at wavelength L cells: exp(-2 pi^2 sigma^2/L^2).
  // The sampled, 3-sigma-truncated Q15 kernel must match to 0.5 % of the amplitude.
  for (const double sigma : {0.7, 1.0, 1.5}) {
    SmoothingConfig c;
    c.sigma_cells = sigma;
    auto s = make_smoother(c);
    const double wavelength = 10.0;
    const double amp = 4.0;  // px
    const GridVectorD wd = f::sample([&](double x, double y, double& u, double& v) {
      u = amp * std::cos(2.0 * std::numbers::pi * x / wavelength);
      v = amp * std::sin(2.0 * std::numbers::pi * y / wavelength);
    });
    VectorField out;
    GridMask ov;
    s->apply(dsp_ref::grid_vector_to_q16(wd), all_valid(), out, ov);
    const double h = std::exp(-2.0 * std::numbers::pi * std::numbers::pi * sigma * sigma /
                              (wavelength * wavelength));
    const int r = s->radius();
    for (int gy = r; gy < kGridHeight - r; ++gy) {
      for (int gx = r; gx < kGridWidth - r; ++gx) {
        const std::size_t p = static_cast<std::size_t>(gy * kGridWidth + gx);
        ASSERT_NEAR(from_q<kFieldFrac>(out.x.v[p]), h * wd.x[p], 0.005 * amp) << sigma;
        ASSERT_NEAR(from_q<kFieldFrac>(out.y.v[p]), h * wd.y[p], 0.005 * amp) << sigma;
      }
    }
  }
}

TEST(Smoothing, MatchesDoubleReference) {
  // Same normalised convolution in double with exact taps. Error sources: Q15 tap rounding
  // (<= 0.5 LSB per tap, i.e. a relative weight error <= 2^-16 / g_min) and the final rounding
  // (0.5 LSB). Worst case: |tap error| summed over the 2-D kernel ~ 4e-4 times the field variation
  // under the kernel (~1 px here) ~ 24 LSB; the errors average out. Thresholds 90 dB SNR and
  // 8 LSB.
  for (int seed = 1; seed <= 4; ++seed) {
    f::Rng rng(static_cast<std::uint64_t>(seed));
    const GridVectorD wd0 = f::random_smooth(rng, 3.0, 0.2);
    const GridMaskD md = seed == 1 ? GridMaskD(kGridCount, 1) : f::random_mask(rng, 0.15);
    const VectorField w = dsp_ref::grid_vector_to_q16(wd0);
    const GridVectorD wd = dsp_ref::grid_vector_from_q16(w);
    auto s = make_smoother();
    VectorField out;
    GridMask ov;
    s->apply(w, dsp_ref::grid_mask_to(md), out, ov);
    GridVectorD ref;
    GridMaskD ref_valid;
    dsp_ref::smooth_ref(wd, md, SmoothingConfig{}, ref, ref_valid);
    GridMaskD both(kGridCount, 0);
    int differing = 0;
    for (std::size_t i = 0; i < kGridCount; ++i) {
      both[i] = (ov.v[i] != 0 && ref_valid[i] != 0) ? 1 : 0;
      differing += (ov.v[i] != 0) != (ref_valid[i] != 0) ? 1 : 0;
    }
    EXPECT_EQ(differing, 0) << seed;  // support decisions agree (no sample sits on the threshold)
    const double snr = f::snr_db(ref, dsp_ref::grid_vector_from_q16(out), &both);
    const double lsb = f::max_lsb(ref, out, &both);
    RecordProperty("snr_db_seed" + std::to_string(seed), std::to_string(snr));
    RecordProperty("max_lsb_seed" + std::to_string(seed), std::to_string(lsb));
    EXPECT_GT(snr, 90.0) << seed;
    EXPECT_LT(lsb, 8.0) << seed;
  }
}

TEST(Smoothing, InvalidPointsAreIgnoredAndFilled) {
  auto s = make_smoother();
  f::Rng rng(5);
  const GridMaskD md = f::random_mask(rng, 0.2);
  const GridMask m = dsp_ref::grid_mask_to(md);
  VectorField a = dsp_ref::grid_vector_to_q16(f::random_smooth(rng, 2.0));
  VectorField b = a;
  for (std::size_t i = 0; i < kGridCount; ++i) {
    if (md[i] != 0) continue;
    a.x.v[i] = 0;
    a.y.v[i] = 0;
    b.x.v[i] = (i % 3 == 0) ? kQ32MaxPos : kQ32MaxNeg;  // garbage where the flow failed
    b.y.v[i] = static_cast<std::int32_t>(i * 2654435761u);
  }
  VectorField oa;
  VectorField ob;
  GridMask va;
  GridMask vb;
  s->apply(a, m, oa, va);
  s->apply(b, m, ob, vb);
  for (std::size_t i = 0; i < kGridCount; ++i) {
    ASSERT_EQ(oa.x.v[i], ob.x.v[i]);
    ASSERT_EQ(oa.y.v[i], ob.y.v[i]);
    ASSERT_EQ(va.v[i], vb.v[i]);
  }

  // A hole in a constant field is filled with the constant and becomes valid.
  VectorField c;
  c.x.fill(5 << 16);
  c.y.fill(-(3 << 16));
  GridMask hole = all_valid();
  hole(20, 15) = 0;
  VectorField oc;
  GridMask vc;
  s->apply(c, hole, oc, vc);
  EXPECT_EQ(vc(20, 15), 1);
  EXPECT_EQ(oc.x(20, 15), 5 << 16);
  EXPECT_EQ(oc.y(20, 15), -(3 << 16));

  // An isolated valid point carries 0.16 of the kernel mass (< min_support 0.25): dropped. Points
  // far from any valid sample are 0 and invalid.
  GridMask lonely;
  lonely.fill(0);
  lonely(10, 10) = 1;
  s->apply(c, lonely, oc, vc);
  EXPECT_EQ(vc(10, 10), 0);
  EXPECT_EQ(oc.x(10, 10), 0);
  EXPECT_EQ(vc(30, 20), 0);
  EXPECT_EQ(oc.y(30, 20), 0);
}

TEST(Smoothing, ExtremeInputsDoNotOverflow) {
  // int64 accumulators: |numerator| <= 2^61 even for full-scale inputs. Runs under UBSan.
  auto s = make_smoother();
  VectorField w;
  VectorField out;
  GridMask ov;
  w.x.fill(kQ32MaxPos);
  w.y.fill(kQ32MaxNeg);
  s->apply(w, all_valid(), out, ov);
  for (std::size_t i = 0; i < kGridCount; ++i) {
    ASSERT_EQ(out.x.v[i], kQ32MaxPos);
    ASSERT_EQ(out.y.v[i], kQ32MaxNeg);
  }
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const bool hi = (gx + gy) % 2 == 0;
      w.x(gx, gy) = hi ? kQ32MaxPos : kQ32MaxNeg;
      w.y(gx, gy) = hi ? kQ32MaxNeg : kQ32MaxPos;
    }
  }
  // Full-scale checkerboard, with and without holes: the exact normalised means (double
  // reference) are reproduced within the tap-rounding bound, never wrapped. Bound: the Q15 taps
  // are off by <= 0.5 LSB each and the centre tap by <= R LSB, so the 2-D weights are off by
  // <= 2 * 6 / 2^15 in total, times the input range 2^16 px: 24 px.
  f::Rng rng(8);
  const GridMaskD holes = f::random_mask(rng, 0.3);
  const GridVectorD wd = dsp_ref::grid_vector_from_q16(w);
  for (const GridMaskD& md : {GridMaskD(kGridCount, 1), holes}) {
    s->apply(w, dsp_ref::grid_mask_to(md), out, ov);
    GridVectorD ref;
    GridMaskD ref_valid;
    dsp_ref::smooth_ref(wd, md, SmoothingConfig{}, ref, ref_valid);
    for (std::size_t i = 0; i < kGridCount; ++i) {
      ASSERT_EQ(ov.v[i], ref_valid[i]);
      ASSERT_NEAR(from_q<kFieldFrac>(out.x.v[i]), ref.x[i], 24.0) << i;
      ASSERT_NEAR(from_q<kFieldFrac>(out.y.v[i]), ref.y[i], 24.0) << i;
    }
  }
}

TEST(Smoothing, OutputMayAliasInput) {
  auto s = make_smoother();
  f::Rng rng(9);
  const GridMask m = dsp_ref::grid_mask_to(f::random_mask(rng, 0.1));
  VectorField w = dsp_ref::grid_vector_to_q16(f::random_smooth(rng, 2.0, 0.1));
  VectorField out;
  GridMask ov;
  s->apply(w, m, out, ov);
  GridMask m2 = m;
  s->apply(w, m2, w, m2);
  for (std::size_t i = 0; i < kGridCount; ++i) {
    ASSERT_EQ(w.x.v[i], out.x.v[i]);
    ASSERT_EQ(w.y.v[i], out.y.v[i]);
    ASSERT_EQ(m2.v[i], ov.v[i]);
  }
}

TEST(Smoothing, ConfigurationIsValidated) {
  auto s = make_smoother();
  SmoothingConfig bad;
  bad.sigma_cells = 0.1;
  EXPECT_EQ(s->configure(bad), Status::kBadArgument);
  bad.sigma_cells = std::nan("");
  EXPECT_EQ(s->configure(bad), Status::kBadArgument);
  bad.sigma_cells = 1.0;
  bad.min_support = 0.0;
  EXPECT_EQ(s->configure(bad), Status::kBadArgument);
  bad.min_support = 1.5;
  EXPECT_EQ(s->configure(bad), Status::kBadArgument);
  EXPECT_EQ(s->radius(), 3);  // unchanged
  SmoothingConfig wide;
  wide.sigma_cells = kMaxSigmaCells;
  EXPECT_EQ(s->configure(wide), Status::kOk);
  EXPECT_EQ(s->radius(), FlowSmoother::kMaxRadius);
}

}  // namespace
}  // namespace tacse3::dsp
