// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: calibrated force maps against the double reference, analytic divergence,
// saturation at MAXPOS/MAXNEG.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

#include "tacse3/dsp/fixed.hpp"
#include "tacse3/dsp/force_map.hpp"
#include "tacse3/dsp_ref/force_map_ref.hpp"

namespace tacse3::dsp {
namespace {

constexpr double kLsb = 1.0 / 65536.0;

struct Inputs {
  ScalarField density;
  VectorField d, r, k;
  GridMask valid;
};

std::unique_ptr<Inputs> random_inputs(std::uint32_t seed, double invalid_fraction) {
  auto in = std::make_unique<Inputs>();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> g(-0.3, 0.3), px(-5.0, 5.0), u(0.0, 1.0);
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    in->density.v[i] = to_q32<16>(g(rng));
    in->d.x.v[i] = to_q32<16>(px(rng));
    in->d.y.v[i] = to_q32<16>(px(rng));
    in->r.x.v[i] = to_q32<16>(px(rng));
    in->r.y.v[i] = to_q32<16>(px(rng));
    in->k.x.v[i] = to_q32<16>(px(rng));
    in->k.y.v[i] = to_q32<16>(px(rng));
    in->valid.v[i] = u(rng) < invalid_fraction ? 0 : 1;
  }
  return in;
}

struct Stats {
  double snr_db;
  double max_err_lsb;
};
Stats compare(const GridArray<std::int32_t>& fixed, const std::vector<double>& ref) {
  double sig = 0.0, noise = 0.0, worst = 0.0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const double e = from_q<16>(fixed.v[i]) - ref[i];
    sig += ref[i] * ref[i];
    noise += e * e;
    worst = std::max(worst, std::abs(e) / kLsb);
  }
  return {noise > 0.0 ? 10.0 * std::log10(sig / noise) : 400.0, worst};
}

TEST(ForceMap, MatchesReferenceWithinHalfLsbForRepresentableGains) {
  Calibration cal;
  cal.normal_gain_density = 1.0;
  cal.normal_gain_divergence = 0.5;
  cal.shear_gain_d = 0.25;
  cal.shear_gain_r = 1.0;
  cal.shear_gain_k = 2.0;
  ForceMap fm;
  ASSERT_EQ(fm.configure(cal), Status::kOk);
  for (std::uint32_t seed = 1; seed <= 5; ++seed) {
    const auto in = random_inputs(seed, 0.1);
    ScalarField fz;
    VectorField shear;
    fm.compute(in->density, in->d, in->r, in->k, in->valid, fz, shear);
    const auto ref = dsp_ref::force_map_ref(cal, in->density, in->d, in->r, in->k, in->valid);
    // Gains are exact in Q16, so the only error is the final rounding shift (≤ 0.5 LSB), plus
    // the Q16 rounding of div(d) before its gain (≤ 0.5 LSB · 0.5) for f^z.
    const Stats sz = compare(fz, ref.fz), sx = compare(shear.x, ref.fx),
                sy = compare(shear.y, ref.fy);
    EXPECT_LE(sz.max_err_lsb, 0.75 + 1e-9);
    EXPECT_LE(sx.max_err_lsb, 0.5 + 1e-9);
    EXPECT_LE(sy.max_err_lsb, 0.5 + 1e-9);
    // Signals of ~0.3 (f^z) and ~5 px (shear) against ≤ 0.5 LSB = 7.6e-6: ≥ 90 dB.
    EXPECT_GT(sz.snr_db, 90.0);
    EXPECT_GT(sx.snr_db, 110.0);
    EXPECT_GT(sy.snr_db, 110.0);
  }
}

TEST(ForceMap, ArbitraryGainsStayWithinGainQuantisationBound) {
  Calibration cal;
  cal.normal_gain_density = 1.2345;
  cal.normal_gain_divergence = 0.3333;
  cal.shear_gain_d = 0.1111;
  cal.shear_gain_r = 0.9876;
  cal.shear_gain_k = 1.4142;
  ForceMap fm;
  ASSERT_EQ(fm.configure(cal), Status::kOk);
  const auto in = random_inputs(7, 0.0);
  ScalarField fz;
  VectorField shear;
  fm.compute(in->density, in->d, in->r, in->k, in->valid, fz, shear);
  const auto ref = dsp_ref::force_map_ref(cal, in->density, in->d, in->r, in->k, in->valid);
  // Each gain is off by ≤ 2^-17; with |inputs| ≤ 5 px and three terms that adds
  // ≤ 3 · 5 · 2^-17 = 7.5 LSB to the 0.5 LSB rounding. f^z: |𝒢| ≤ 0.3, |div| ≤ ~2.5.
  EXPECT_LE(compare(shear.x, ref.fx).max_err_lsb, 8.0);
  EXPECT_LE(compare(shear.y, ref.fy).max_err_lsb, 8.0);
  EXPECT_LE(compare(fz, ref.fz).max_err_lsb, 2.5);
  EXPECT_GT(compare(shear.x, ref.fx).snr_db, 100.0);
  EXPECT_GT(compare(fz, ref.fz).snr_db, 90.0);
}

TEST(ForceMap, DivergenceOfLinearFieldIsExact) {
  // v = (a x, b y) in working px with x, y the working-image coordinates: div = a + b exactly,
  // for central and one-sided differences alike, also next to invalid points.
  auto in = random_inputs(3, 0.0);
  const double a = 0.03, b = -0.01;
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      in->d.x(gx, gy) = to_q32<16>(a * grid_work_x(gx));
      in->d.y(gx, gy) = to_q32<16>(b * grid_work_y(gy));
    }
  }
  in->valid(10, 10) = 0;
  in->valid(11, 10) = 0;
  ScalarField div;
  grid_divergence(in->d, in->valid, div);
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      if (in->valid(gx, gy) == 0) {
        EXPECT_EQ(div(gx, gy), 0);
        continue;
      }
      // Inputs carry ≤ 0.5 LSB each; a difference over 4 px divides that by 2.
      EXPECT_NEAR(from_q<16>(div(gx, gy)), a + b, 1.0 * kLsb) << gx << "," << gy;
    }
  }
  const std::vector<double> ref = dsp_ref::grid_divergence_ref(in->d, in->valid);
  EXPECT_LE(compare(div, ref).max_err_lsb, 0.5 + 1e-9);
}

TEST(ForceMap, SaturatesAtMaxPosAndMaxNeg) {
  Calibration cal;
  cal.normal_gain_density = 2.0;
  cal.shear_gain_d = 1.0;
  cal.shear_gain_r = 1.0;
  cal.shear_gain_k = 1.0;
  ForceMap fm;
  ASSERT_EQ(fm.configure(cal), Status::kOk);
  auto in = std::make_unique<Inputs>();
  in->valid.fill(1);
  in->density.fill(kQ32MaxNeg);  // −𝒢 · 2 = +2^32 in Q16: saturates to MAXPOS
  in->d.x.fill(kQ32MaxPos);
  in->r.x.fill(kQ32MaxPos);
  in->k.x.fill(kQ32MaxPos);
  in->d.y.fill(kQ32MaxNeg);
  in->r.y.fill(kQ32MaxNeg);
  in->k.y.fill(kQ32MaxNeg);
  ScalarField fz;
  VectorField shear;
  fm.compute(in->density, in->d, in->r, in->k, in->valid, fz, shear);
  EXPECT_EQ(fz(5, 5), kQ32MaxPos);
  EXPECT_EQ(shear.x(5, 5), kQ32MaxPos);
  EXPECT_EQ(shear.y(5, 5), kQ32MaxNeg);
  in->density.fill(kQ32MaxPos);
  fm.compute(in->density, in->d, in->r, in->k, in->valid, fz, shear);
  EXPECT_EQ(fz(5, 5), kQ32MaxNeg);
}

TEST(ForceMap, InvalidPointsAreZeroAndUndeformedIsZero) {
  ForceMap fm;  // defaults: f^z = −𝒢, shear = d + r + k
  auto in = std::make_unique<Inputs>();
  in->valid.fill(1);
  // Undeformed (𝒢 = 0) under a uniform shift: all of it is the harmonic part k.
  in->k.x.fill(to_q32<16>(0.75));
  in->k.y.fill(to_q32<16>(-0.25));
  in->d.x.fill(to_q32<16>(3.0));  // d enters with the default s_d = 1
  in->valid(3, 4) = 0;
  ScalarField fz;
  VectorField shear;
  fm.compute(in->density, in->d, in->r, in->k, in->valid, fz, shear);
  EXPECT_EQ(fz(0, 0), 0);
  EXPECT_EQ(shear.x(0, 0), to_q32<16>(3.75));
  EXPECT_EQ(shear.y(20, 20), to_q32<16>(-0.25));
  EXPECT_EQ(shear.x(3, 4), 0);
  EXPECT_EQ(shear.y(3, 4), 0);
  in->density.fill(to_q32<16>(-0.1));  // local expansion → positive normal response
  fm.compute(in->density, in->d, in->r, in->k, in->valid, fz, shear);
  EXPECT_EQ(fz(1, 1), to_q32<16>(0.1));
  EXPECT_EQ(fz(3, 4), 0);
}

}  // namespace
}  // namespace tacse3::dsp
