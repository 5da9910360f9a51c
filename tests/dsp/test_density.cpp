// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: Gaussian density map G (shift-invariant local-expansion proxy, paper Sec. IV-B).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>

#include "support/fields.hpp"
#include "tacse3/dsp/density.hpp"
#include "tacse3/dsp/fixed.hpp"
#include "tacse3/dsp_ref/density_ref.hpp"

namespace tacse3::dsp {
namespace {

namespace f = test::fields;
using dsp_ref::GridMaskD;
using dsp_ref::GridScalarD;
using dsp_ref::GridVectorD;

std::unique_ptr<GaussianDensity> make_density(const DensityConfig& config = {}) {
  auto d = std::make_unique<GaussianDensity>();
  EXPECT_EQ(d->configure(config), Status::kOk);
  return d;
}

GridMask all_valid() {
  GridMask m;
  m.fill(1);
  return m;
}

// Interior: points whose whole neighbourhood (3 sigma + margin = 3.5 cells) lies inside the grid.
bool interior(int gx, int gy) {
  return gx >= 4 && gx < kGridWidth - 4 && gy >= 4 && gy < kGridHeight - 4;
}

TEST(Density, KernelLutMatchesTheTruncatedGaussian) {
  // Q15 LUT with linear interpolation vs the exact kernel: within 1 LSB everywhere, 0 from the
  // cut-off (3 sigma = 12 px at sigma = 1 cell) on.
  auto d = make_density();
  const double sigma_px = 4.0;
  for (double r = 0.0; r <= 14.0; r += 0.01) {
    const double exact =
        32768.0 * dsp_ref::density_kernel_ref(std::round(r * 1024.0) / 1024.0, sigma_px);
    ASSERT_NEAR(d->kernel_q15(r), exact, 1.0) << r;
  }
  EXPECT_EQ(d->kernel_q15(0.0), 32768);
  EXPECT_EQ(d->kernel_q15(12.0), 0);
  EXPECT_EQ(d->kernel_q15(30.0), 0);
}

TEST(Density, UniformShiftGivesExactlyZero) {
  // Shift invariance: only differences of displacements enter, so any uniform shift (sub-pixel,
  // large, negative) gives G = 0 bit-exactly, with or without invalid points.
  auto d = make_density();
  f::Rng rng(2);
  const GridMask holes = dsp_ref::grid_mask_to(f::random_mask(rng, 0.2));
  const double shifts[][2] = {{0.0, 0.0}, {0.37, -0.81}, {10.37, 3.5}, {-25.0, 17.125}};
  for (const auto& s : shifts) {
    const VectorField u = dsp_ref::grid_vector_to_q16(f::sample(f::uniform(s[0], s[1])));
    for (const GridMask& m : {all_valid(), holes}) {
      ScalarField g;
      g.fill(12345);
      d->compute(u, m, g);
      for (std::size_t i = 0; i < kGridCount; ++i) ASSERT_EQ(g.v[i], 0) << s[0] << "," << s[1];
    }
  }
}

TEST(Density, RotationIsSecondOrder) {
  // A (linearised) rotation by theta stretches distances by sqrt(1 + theta^2): G ~ -theta^2, far
  // below the first-order response to expansion (-2 eps).
  auto d = make_density();
  const double theta = 0.03;
  const VectorField u =
      dsp_ref::grid_vector_to_q16(f::sample(f::rigid_rotation(theta * kGridStride)));
  ScalarField g;
  d->compute(u, all_valid(), g);
  const double expected = dsp_ref::density_uniform_scaling_ref(std::sqrt(1.0 + theta * theta), {});
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      if (!interior(gx, gy)) continue;
      ASSERT_NEAR(from_q<kFieldFrac>(g(gx, gy)), expected, 2e-4);
      ASSERT_LT(std::abs(from_q<kFieldFrac>(g(gx, gy))), 2.0 * theta * theta);
    }
  }
}

TEST(Density, UniformScalingMatchesTheAnalyticLatticeValue) {
  // x -> s x about any centre: in the interior every point sees the same neighbourhood scaled by
  // s, so G = sum K(s|o|) / sum K(|o|) - 1 exactly (the infinite-lattice value), ~ 1/s^2 - 1.
  // Expansion (s > 1) gives G < 0 (height -G > 0), compression G > 0.
  auto d = make_density();
  for (const double eps : {-0.1, -0.05, -0.02, 0.02, 0.05, 0.1}) {
    const double s = 1.0 + eps;
    const VectorField u = dsp_ref::grid_vector_to_q16(
        f::sample(f::rigid_expansion(eps * kGridStride, 2.5, -1.5)));  // px per cell
    ScalarField g;
    d->compute(u, all_valid(), g);
    const double expected = dsp_ref::density_uniform_scaling_ref(s, {});
    // The lattice value is within 3 % of the continuum 1/s^2 - 1 (the kernel is cut at 3 sigma,
    // which makes the lattice sum differ slightly from the integral).
    EXPECT_NEAR(expected, 1.0 / (s * s) - 1.0, 0.03 * std::abs(1.0 / (s * s) - 1.0)) << eps;
    for (int gy = 0; gy < kGridHeight; ++gy) {
      for (int gx = 0; gx < kGridWidth; ++gx) {
        if (!interior(gx, gy)) continue;
        const double gv = from_q<kFieldFrac>(g(gx, gy));
        ASSERT_NEAR(gv, expected, 2e-4) << eps << " at " << gx << "," << gy;
        ASSERT_EQ(gv<0.0, eps> 0.0);
      }
    }
  }
}

TEST(Density, LocalExpansionIsNegativeAtTheCentreAndZeroFarAway) {
  // The gel bulging around an indenter: a Gaussian source of displacement. G < 0 at the centre
  // (about -2 x the central strain 2 * amp / 2 = amp per cell), ~0 far from it; the sign flips
  // for compression.
  auto d = make_density();
  for (const double amp : {0.1, -0.1}) {  // px per cell of central strain (x 4 px cells below)
    const VectorField u = dsp_ref::grid_vector_to_q16(
        f::sample(f::gaussian_source(amp * kGridStride, 3.0, 0.5, 0.5)));
    ScalarField g;
    d->compute(u, all_valid(), g);
    const double centre = from_q<kFieldFrac>(g(20, 15));
    // Central strain of the source: eps = amp / 2 per axis (d/dx of amp*x/2 near 0), so
    // G ~ 1/(1 + eps)^2 - 1 ~ -2 eps, reduced by the kernel averaging over the bump.
    const double eps = amp / 2.0;
    EXPECT_LT(std::abs(centre), 2.0 * std::abs(eps));
    EXPECT_GT(std::abs(centre), 0.8 * std::abs(eps));
    EXPECT_EQ(centre<0.0, amp> 0.0);
    EXPECT_LT(std::abs(from_q<kFieldFrac>(g(2, 2))), 0.05 * std::abs(centre));
    EXPECT_LT(std::abs(from_q<kFieldFrac>(g(37, 27))), 0.05 * std::abs(centre));
  }
}

TEST(Density, SimdPairLoopEqualsTheScalarDefinition) {
  // The pair loop runs 4 pairs per step (SSE2 pmaddwd on x86, generic vectors elsewhere) and
  // evaluates each unordered pair once. It must equal, bit for bit, the plain definition
  // D(p) = K(0) + sum over valid q within 3 sigma + 0.5 cells of kernel_of(dq) on every platform.
  auto d = make_density();
  f::Rng rng(6);
  const GridMaskD md = f::random_mask(rng, 0.1);
  const VectorField u = dsp_ref::grid_vector_to_q16(f::random_smooth(rng, 6.0, 0.5));
  ScalarField g;
  d->compute(u, dsp_ref::grid_mask_to(md), g);
  const auto q10 = [](std::int32_t v) {
    const std::int64_t r = rshift_round(v, kFieldFrac - GaussianDensity::kWorkFrac);
    return static_cast<std::int32_t>(r > (1 << 20) ? (1 << 20) : (r < -(1 << 20) ? -(1 << 20) : r));
  };
  const double reach = 3.0 * DensityConfig{}.sigma_cells + 0.5;
  const int cell = kGridStride << GaussianDensity::kWorkFrac;
  for (int py = 0; py < kGridHeight; ++py) {
    for (int px = 0; px < kGridWidth; ++px) {
      const std::size_t p = static_cast<std::size_t>(py * kGridWidth + px);
      std::int64_t dens = md[p] != 0 ? 32768 : 0;
      for (int oy = -3; oy <= 3 && md[p] != 0; ++oy) {
        for (int ox = -3; ox <= 3; ++ox) {
          if ((ox == 0 && oy == 0) || ox * ox + oy * oy > reach * reach) continue;
          const int qx = px + ox;
          const int qy = py + oy;
          if (qx < 0 || qy < 0 || qx >= kGridWidth || qy >= kGridHeight) continue;
          const std::size_t q = static_cast<std::size_t>(qy * kGridWidth + qx);
          if (md[q] == 0) continue;
          // Pairs are evaluated from the upper-half-plane end: (p, q) with q after p.
          const bool p_first = oy > 0 || (oy == 0 && ox > 0);
          const std::size_t a = p_first ? p : q;
          const std::size_t b = p_first ? q : p;
          const int sx = p_first ? ox : -ox;
          const int sy = p_first ? oy : -oy;
          dens += d->kernel_of(sx * cell + q10(u.x.v[b]) - q10(u.x.v[a]),
                               sy * cell + q10(u.y.v[b]) - q10(u.y.v[a]));
        }
      }
      ASSERT_EQ(d->density().v[p], dens) << px << "," << py;
    }
  }
}

TEST(Density, MatchesDoubleReference) {
  // Same definition in double (exact kernel, unquantised displacements). Error sources: Q10
  // displacements (<= 2^-11 px each, so <= 2^-10 px per distance component), Q15 LUT entries
  // (0.5 LSB), interpolation (< 1e-6) and the Q16 output. The distance rounding dominates:
  // |dK/dr| <= e^-1/2 / sigma = 0.15 / px gives <= 2e-4 per kernel term; 36 terms of one sign over
  // D0 ~ 6.3 would be ~70 LSB of G, random signs give a few LSB. Thresholds: 55 dB and 16 LSB.
  for (int seed = 1; seed <= 4; ++seed) {
    f::Rng rng(static_cast<std::uint64_t>(seed));
    const GridVectorD ud0 = f::random_smooth(rng, 2.5, 0.05);
    const GridMaskD md = seed == 1 ? GridMaskD(kGridCount, 1) : f::random_mask(rng, 0.15);
    const VectorField u = dsp_ref::grid_vector_to_q16(ud0);
    const GridVectorD ud = dsp_ref::grid_vector_from_q16(u);
    auto d = make_density();
    ScalarField g;
    d->compute(u, dsp_ref::grid_mask_to(md), g);
    const GridScalarD ref = dsp_ref::gaussian_density_ref(ud, md, DensityConfig{});
    const double snr = f::snr_db(ref, dsp_ref::grid_scalar_from_q16(g), &md);
    const double lsb = f::max_lsb(ref, g, &md);
    RecordProperty("snr_db_seed" + std::to_string(seed), std::to_string(snr));
    RecordProperty("max_lsb_seed" + std::to_string(seed), std::to_string(lsb));
    RecordProperty("rms_g_seed" + std::to_string(seed), std::to_string(f::rms(ref, &md)));
    EXPECT_GT(snr, 55.0) << seed;
    EXPECT_LT(lsb, 16.0) << seed;
  }
}

TEST(Density, InvalidPointsAreExcluded) {
  auto d = make_density();
  f::Rng rng(4);
  const GridMaskD md = f::random_mask(rng, 0.25);
  const GridMask m = dsp_ref::grid_mask_to(md);
  VectorField a = dsp_ref::grid_vector_to_q16(f::random_smooth(rng, 2.0));
  VectorField b = a;
  for (std::size_t i = 0; i < kGridCount; ++i) {
    if (md[i] != 0) continue;
    b.x.v[i] = (i % 2 == 0) ? kQ32MaxPos : kQ32MaxNeg;
    b.y.v[i] = static_cast<std::int32_t>(i * 40503u);
  }
  ScalarField ga;
  ScalarField gb;
  d->compute(a, m, ga);
  d->compute(b, m, gb);
  for (std::size_t i = 0; i < kGridCount; ++i) {
    ASSERT_EQ(ga.v[i], gb.v[i]);
    if (md[i] == 0) {
      ASSERT_EQ(ga.v[i], 0);
    }
  }
  // A valid point with no valid neighbour: D = D0 = K(0), G = 0 whatever its displacement.
  GridMask lonely;
  lonely.fill(0);
  lonely(5, 5) = 1;
  d->compute(b, lonely, gb);
  EXPECT_EQ(gb(5, 5), 0);
}

TEST(Density, ExtremeDisplacementsStayBounded) {
  // Full-scale displacements: the Q10 clamp, the +-c component clamp and int64 normalisation keep
  // every intermediate in range (UBSan). Points torn apart lose all neighbours: G -> K(0)/D0 - 1.
  auto d = make_density();
  VectorField u;
  ScalarField g;
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const bool hi = (gx + gy) % 2 == 0;
      u.x(gx, gy) = hi ? kQ32MaxPos : kQ32MaxNeg;
      u.y(gx, gy) = hi ? kQ32MaxNeg : kQ32MaxPos;
    }
  }
  d->compute(u, all_valid(), g);
  const double isolated = 32768.0 / d->density_undeformed()(20, 15) - 1.0;
  for (std::size_t i = 0; i < kGridCount; ++i) {
    ASSERT_GE(g.v[i], -(1 << kFieldFrac));
    ASSERT_LE(g.v[i], 0);
  }
  // The checkerboard keeps the diagonal neighbours together (same displacement): D counts them.
  EXPECT_GT(from_q<kFieldFrac>(g(20, 15)), isolated);
  // Everything collapsed onto one point: maximal compression, G = (#valid neighbours) - ... > 0.
  u.x.fill(0);
  u.y.fill(0);
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      u.x(gx, gy) = -(gx * kGridStride) << kFieldFrac;
      u.y(gx, gy) = -(gy * kGridStride) << kFieldFrac;
    }
  }
  d->compute(u, all_valid(), g);
  const double n_neighbours = d->density()(20, 15) / 32768.0;
  EXPECT_GT(from_q<kFieldFrac>(g(20, 15)), 2.0);
  EXPECT_NEAR(n_neighbours, 1.0 + 2.0 * d->pair_offsets(), 1e-9);
}

TEST(Density, ConfigurationIsValidated) {
  auto d = make_density();
  const int pairs = d->pair_offsets();
  EXPECT_EQ(pairs, 18);  // |o| <= 3.5 cells, upper half plane
  DensityConfig bad;
  bad.sigma_cells = 0.2;
  EXPECT_EQ(d->configure(bad), Status::kBadArgument);
  bad.sigma_cells = std::nan("");
  EXPECT_EQ(d->configure(bad), Status::kBadArgument);
  EXPECT_EQ(d->pair_offsets(), pairs);
  DensityConfig wide;
  wide.sigma_cells = kMaxDensitySigmaCells;
  EXPECT_EQ(d->configure(wide), Status::kOk);
  EXPECT_LE(2 * d->pair_offsets(), GaussianDensity::kMaxOffsets);
  // Shift invariance holds for every sigma.
  const VectorField u = dsp_ref::grid_vector_to_q16(f::sample(f::uniform(3.3, -1.1)));
  ScalarField g;
  d->compute(u, all_valid(), g);
  for (std::size_t i = 0; i < kGridCount; ++i) ASSERT_EQ(g.v[i], 0);
}

}  // namespace
}  // namespace tacse3::dsp
