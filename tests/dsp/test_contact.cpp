// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: contact mask hysteresis, minimum area, filter normalisation and 3D contact
// points against the double reference.
#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "tacse3/dsp/contact.hpp"
#include "tacse3/dsp/fixed.hpp"
#include "tacse3/dsp_ref/contact_ref.hpp"

namespace tacse3::dsp {
namespace {

struct Frame {
  ScalarField fz;
  VectorField w;
  GridMask valid;
  Frame() { valid.fill(1); }
};

// Paints a rectangle [x0, x1) x [y0, y1) of value v (f^z units).
void paint(ScalarField& f, int x0, int y0, int x1, int y1, double v) {
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) f(x, y) = to_q32<16>(v);
}

std::vector<double> to_double(const ScalarField& f) {
  std::vector<double> v(static_cast<std::size_t>(kGridCount));
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = from_q<16>(f.v[i]);
  return v;
}

int count(const GridMask& m) {
  int c = 0;
  for (auto x : m.v) c += x;
  return c;
}

class ContactTest : public ::testing::Test {
 protected:
  Calibration cal;  // τ_on = 0.02, τ_off = 0.01, min area 4
  std::unique_ptr<ContactDetector> det = std::make_unique<ContactDetector>();
  std::unique_ptr<ContactSet> cs = std::make_unique<ContactSet>();
  std::unique_ptr<Frame> fr = std::make_unique<Frame>();
  dsp_ref::ContactDetectorRef ref{cal};

  // Runs both implementations; the masks must be identical (values are far from ties).
  void step() {
    det->detect(fr->fz, fr->w, fr->valid, *cs);
    const dsp_ref::ContactSetRef r = ref.detect(to_double(fr->fz), fr->w, fr->valid);
    int diff = 0;
    for (std::size_t i = 0; i < r.mask.size(); ++i) diff += r.mask[i] != cs->mask.v[i];
    EXPECT_EQ(diff, 0);
    EXPECT_EQ(cs->count, r.count);
    EXPECT_EQ(cs->components, r.components);
  }
};

TEST_F(ContactTest, HysteresisKeepsOldCellsAboveTauOffOnly) {
  // 1. Between τ_off and τ_on with no history: no contact.
  paint(fr->fz, 10, 10, 18, 18, 0.015);
  step();
  EXPECT_FALSE(cs->contact);
  EXPECT_EQ(cs->count, 0);
  // 2. Above τ_on: the block interior (filter = value) is in contact. Edge cells see part of the
  //    zero surroundings (filter 0.75·v on edges, 0.5625·v on corners): 0.0225 and 0.0169.
  paint(fr->fz, 10, 10, 18, 18, 0.03);
  step();
  EXPECT_TRUE(cs->contact);
  EXPECT_EQ(cs->count, 64 - 4);  // 8x8 block minus the four corners (0.0169 < τ_on)
  EXPECT_EQ(cs->mask(14, 14), 1);
  EXPECT_EQ(cs->mask(10, 10), 0);
  // 3. Drop to 0.015 (< τ_on, > τ_off): cells already in Ω stay where filter > τ_off. Edges
  //    filter to 0.01125 > τ_off and stay; corners were not in Ω and do not enter.
  paint(fr->fz, 10, 10, 18, 18, 0.015);
  step();
  EXPECT_EQ(cs->count, 60);
  EXPECT_EQ(cs->mask(10, 10), 0);
  // 4. Grow the 0.015 region: new cells above τ_off but never above τ_on stay out.
  paint(fr->fz, 6, 10, 18, 18, 0.015);
  step();
  EXPECT_EQ(cs->mask(7, 14), 0);
  EXPECT_EQ(cs->mask(12, 14), 1);
  // 5. Below τ_off: released.
  paint(fr->fz, 6, 10, 18, 18, 0.005);
  step();
  EXPECT_FALSE(cs->contact);
  // 6. reset() forgets the history: 0.015 alone does not re-enter.
  paint(fr->fz, 10, 10, 18, 18, 0.03);
  step();
  EXPECT_EQ(cs->count, 60);
  det->reset();
  ref.reset();
  paint(fr->fz, 10, 10, 18, 18, 0.015);
  step();
  EXPECT_EQ(cs->count, 0);
}

TEST_F(ContactTest, MinimumAreaPerComponent) {
  // A 1-cell-wide horizontal line of value 0.05: on the line the filter gives 0.5·v = 0.025 >
  // τ_on, its end cells 0.375·v = 0.019 < τ_on, the rows beside it 0.25·v. A line of L cells
  // therefore yields a component of L − 2 cells.
  paint(fr->fz, 2, 2, 8, 3, 0.05);    // L = 6 → 4 cells = min area: kept
  paint(fr->fz, 2, 20, 7, 21, 0.05);  // L = 5 → 3 cells: dropped
  step();
  EXPECT_EQ(cs->components, 1);
  EXPECT_EQ(cs->count, 4);
  EXPECT_EQ(cs->cells_dropped, 3);
  EXPECT_EQ(cs->mask(4, 2), 1);
  EXPECT_EQ(cs->mask(4, 20), 0);
  // An isolated single-cell spike is spread by the filter over 3x3 = 9 cells; a minimum area of
  // 10 removes it while a real contact patch elsewhere survives.
  cal.contact_min_area_cells = 10;
  ASSERT_EQ(det->configure(cal), Status::kOk);
  ref = dsp_ref::ContactDetectorRef(cal);
  det->reset();
  fr->fz.fill(0);
  fr->fz(30, 5) = to_q32<16>(1.0);
  paint(fr->fz, 10, 10, 16, 16, 0.05);
  step();
  EXPECT_EQ(cs->components, 1);
  EXPECT_EQ(cs->mask(30, 5), 0);
  EXPECT_EQ(cs->cells_dropped, 9);
  EXPECT_GE(cs->count, 10);
}

TEST_F(ContactTest, FilterIsNormalisedOverValidPoints) {
  // A uniform field stays uniform after the filter, at the grid border and next to invalid
  // points (normalised convolution), so contact does not shrink there.
  fr->fz.fill(to_q32<16>(0.05));
  for (int y = 0; y < kGridHeight; ++y) fr->valid(20, y) = 0;
  step();
  for (int y = 0; y < kGridHeight; ++y) {
    for (int x = 0; x < kGridWidth; ++x) {
      if (x == 20) {
        EXPECT_EQ(cs->fz_filtered(x, y), 0);
        EXPECT_EQ(cs->mask(x, y), 0);
      } else {
        EXPECT_EQ(cs->fz_filtered(x, y), to_q32<16>(0.05)) << x << "," << y;
      }
    }
  }
  EXPECT_EQ(cs->count, kGridCount - kGridHeight);
  EXPECT_EQ(cs->components, 2);
}

TEST_F(ContactTest, PointsAtCurrentPositionsMatchReference) {
  cal.height_gain_m = 4e-3;
  cal.height_max_m = 1e-3;
  ASSERT_EQ(det->configure(cal), Status::kOk);
  ref = dsp_ref::ContactDetectorRef(cal);
  std::mt19937 rng(30);
  std::uniform_real_distribution<double> u(-3.0, 3.0), f(0.0, 0.4);
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    fr->fz.v[i] = to_q32<16>(f(rng));
    fr->w.x.v[i] = to_q32<16>(u(rng));
    fr->w.y.v[i] = to_q32<16>(u(rng));
  }
  det->detect(fr->fz, fr->w, fr->valid, *cs);
  const dsp_ref::ContactSetRef r = ref.detect(to_double(fr->fz), fr->w, fr->valid);
  ASSERT_GT(cs->count, 100);
  double worst_xy = 0.0, worst_z = 0.0;
  bool saw_clamp = false;
  for (std::size_t i = 0; i < r.mask.size(); ++i) {
    ASSERT_EQ(cs->mask.v[i], r.mask[i]);
    if (r.mask[i] == 0) continue;
    worst_xy = std::max(worst_xy, std::abs(cs->x_nm.v[i] - r.q[i].x() * 1e9));
    worst_xy = std::max(worst_xy, std::abs(cs->y_nm.v[i] - r.q[i].y() * 1e9));
    worst_z = std::max(worst_z, std::abs(cs->z_nm.v[i] - r.q[i].z() * 1e9));
    saw_clamp = saw_clamp || cs->z_nm.v[i] == 1000000;
  }
  // x, y: exact Q16 positions times an exact Q16 pitch (75000 nm · 2^16), one rounding: ≤ 0.5 nm.
  EXPECT_LE(worst_xy, 0.5 + 1e-6);
  // z: filter(f^z) rounded to Q16 (≤ 0.5 LSB · 4e6 nm = 30.5 nm), then rounded to 1 nm.
  EXPECT_LE(worst_z, 0.5 * 4e6 / 65536.0 + 0.5 + 1e-6);
  EXPECT_TRUE(saw_clamp);  // f^z up to 0.4 · 4 mm > 1 mm clamp
}

TEST_F(ContactTest, UniformShiftMovesPointsByExactlyThePitch) {
  paint(fr->fz, 10, 10, 20, 20, 0.125);
  fr->w.x.fill(to_q32<16>(0.5));   // 0.5 working px = 1 sensor px = 75 µm
  fr->w.y.fill(to_q32<16>(-1.0));  // −2 sensor px
  step();
  for (int gy = 11; gy < 19; ++gy) {
    for (int gx = 11; gx < 19; ++gx) {
      EXPECT_EQ(cs->x_nm(gx, gy), (8 * gx + 3.5 + 1.0 - 159.5) * 75000.0);
      EXPECT_EQ(cs->y_nm(gx, gy), (8 * gy + 3.5 - 2.0 - 119.5) * 75000.0);
      EXPECT_EQ(cs->z_nm(gx, gy), 625000);  // 5 mm per unit · 0.125
    }
  }
}

TEST_F(ContactTest, ExtremeInputsClampWithoutOverflow) {
  fr->fz.fill(kQ32MaxPos);
  fr->w.x.fill(kQ32MaxPos);
  fr->w.y.fill(kQ32MaxNeg);
  det->detect(fr->fz, fr->w, fr->valid, *cs);
  EXPECT_EQ(cs->count, kGridCount);
  EXPECT_EQ(cs->x_nm(0, 0), kMaxPointNm);
  EXPECT_EQ(cs->y_nm(0, 0), -kMaxPointNm);
  EXPECT_EQ(cs->z_nm(0, 0), 2000000);  // height_max_m = 2 mm
  fr->fz.fill(kQ32MaxNeg);
  det->detect(fr->fz, fr->w, fr->valid, *cs);
  EXPECT_FALSE(cs->contact);
  fr->valid.fill(0);
  fr->fz.fill(kQ32MaxPos);
  det->detect(fr->fz, fr->w, fr->valid, *cs);
  EXPECT_FALSE(cs->contact);
  EXPECT_EQ(count(cs->mask), 0);
}

}  // namespace
}  // namespace tacse3::dsp
