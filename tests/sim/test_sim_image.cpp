// SPDX-License-Identifier: Apache-2.0
// Tests of the simulator's image formation: warp, mirror convention, noise, flicker, determinism.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "tacse3/sim/simulator.hpp"

namespace tacse3::sim {
namespace {

constexpr int kW = 320, kH = 240;

CameraSpec flat_camera() {
  CameraSpec c;
  c.exposure = 1.0;
  c.vignetting_corner = 1.0;
  c.tint = {1.0, 1.0, 1.0};
  c.tint_gradient = {0.0, 0.0, 0.0};
  c.flicker = 0.0;
  c.noise = 0.0;
  return c;
}

struct WarpError {
  double mean = 0.0;
  double max = 0.0;
};

// Renders the pattern under a uniform displacement (dx, dy) px and compares every pixel with
// the analytic pattern at the shifted coordinates.
WarpError warp_error(double dx_px, double dy_px, double compare_dx, double compare_dy) {
  RigSpec rig;
  Pattern pattern;
  pattern.build(PatternSpec{}, rig.pixel_pitch_mm, kW, kH, 7);
  Camera cam;
  cam.build(rig, flat_camera(), 7, Sensor::kLeft);
  PadFields f;
  f.allocate(rig);
  std::fill(f.total_x.begin(), f.total_x.end(), static_cast<float>(dx_px * rig.pixel_pitch_mm));
  std::fill(f.total_y.begin(), f.total_y.end(), static_cast<float>(dy_px * rig.pixel_pitch_mm));
  std::vector<std::uint8_t> img(kW * kH * 3);
  cam.render(pattern, f, 0, img.data(), 3);
  WarpError e;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const Eigen::Vector3d ref = pattern.eval(x - compare_dx, y - compare_dy);
      for (int c = 0; c < 3; ++c) {
        const double d =
            std::abs(img[(static_cast<std::size_t>(y) * kW + x) * 3 + c] - 255.0 * ref[c]);
        e.mean += d;
        e.max = std::max(e.max, d);
      }
    }
  }
  e.mean /= kW * kH * 3.0;
  return e;
}

TEST(SimImage, UniformTranslationRendersThePatternAtShiftedCoordinates) {
  // Whole-pixel shifts land on texels: exact up to rounding.
  const WarpError whole = warp_error(2.0, -1.0, 2.0, -1.0);
  EXPECT_LE(whole.max, 0.51);
  // Sub-pixel shifts: bilinear interpolation of the 2x texture of the band-limited pattern.
  const WarpError sub = warp_error(2.3, -1.7, 2.3, -1.7);
  EXPECT_LT(sub.mean, 1.0);
  EXPECT_LT(sub.max, 12.0);
  // The comparison is sensitive: a 0.5 px error in the shift is clearly visible.
  const WarpError wrong = warp_error(2.3, -1.7, 2.8, -1.7);
  EXPECT_GT(wrong.mean, 5.0 * sub.mean);
}

std::vector<std::uint8_t> render(Simulator& sim, Sensor s, double t, int channels = 3) {
  std::vector<std::uint8_t> img(sim.frame_bytes(channels));
  EXPECT_EQ(sim.render(s, std::llround(t * 1e9), img, channels), SimStatus::kOk);
  return img;
}

// Best integer shift (dx, dy) such that cur(x, y) ~ ref(x - dx, y - dy) in a central window.
std::pair<int, int> best_shift(const std::vector<std::uint8_t>& ref,
                               const std::vector<std::uint8_t>& cur) {
  double best = 1e30;
  std::pair<int, int> arg{0, 0};
  for (int dy = -8; dy <= 8; ++dy) {
    for (int dx = -8; dx <= 8; ++dx) {
      double cost = 0.0;
      for (int y = 100; y < 140; ++y) {
        for (int x = 140; x < 180; ++x) {
          for (int c = 0; c < 3; ++c) {
            cost += std::abs(cur[(static_cast<std::size_t>(y) * kW + x) * 3 + c] -
                             ref[(static_cast<std::size_t>(y - dy) * kW + (x - dx)) * 3 + c]);
          }
        }
      }
      if (cost < best) {
        best = cost;
        arg = {dx, dy};
      }
    }
  }
  return arg;
}

TEST(SimImage, RightImageIsMirroredInY) {
  // A 0.5 mm stick translation along +G y moves the left image content by +5 px in y and the
  // right image content by -5 px (image y = -G y); along +G x both move by +5 px in x.
  for (auto [axis, ex, ey] :
       {std::tuple{MotionAxis::kTy, 0, 5}, std::tuple{MotionAxis::kTx, 5, 0}}) {
    SimConfig c;
    c.camera = flat_camera();
    c.scenario.axis = axis;
    c.scenario.magnitude = 0.5;
    c.scenario.regime = Regime::kStick;
    std::string error;
    auto sim = Simulator::create(c, &error);
    ASSERT_TRUE(sim) << error;
    for (Sensor s : {Sensor::kLeft, Sensor::kRight}) {
      const auto ref = render(*sim, s, sim->scenario().motion_start_s());
      const auto cur = render(*sim, s, sim->scenario().motion_end_s());
      const int mirror = s == Sensor::kRight ? -1 : 1;
      EXPECT_EQ(best_shift(ref, cur), std::make_pair(ex, ey * mirror))
          << to_string(s) << " " << to_string(axis);
    }
  }
}

TEST(SimImage, RenderedFieldMatchesThePatternInsideTheContact) {
  // Noise-free, flat light, no shading: each pixel shows the pattern at x - U(x).
  SimConfig c;
  c.camera = flat_camera();
  c.camera.shading.slope_gain = 0.0;
  c.camera.shading.press_gain_per_mm = 0.0;
  c.scenario.axis = MotionAxis::kRz;
  c.scenario.magnitude = 30.0;
  std::string error;
  auto sim = Simulator::create(c, &error);
  ASSERT_TRUE(sim) << error;
  const double t = sim->scenario().motion_start_s() + 0.5 * sim->scenario().motion_duration_s();
  // Advance the slide state at the frame rate, then render.
  for (int i = 0; sim->scenario().frame_time_ns(i) < std::llround(t * 1e9); ++i) {
    ASSERT_EQ(sim->step(Sensor::kLeft, sim->scenario().frame_time_ns(i)), SimStatus::kOk);
  }
  const auto img = render(*sim, Sensor::kLeft, t);
  const PadFields& f = sim->fields(Sensor::kLeft);
  const Pattern& pattern = sim->pattern(Sensor::kLeft);
  double err = 0.0, moved = 0.0;
  int n = 0;
  for (int j = 0; j < f.gh; ++j) {
    for (int i = 0; i < f.gw; ++i) {
      const std::size_t k = f.index(i, j);
      if (!f.contact[k]) continue;
      // Cell centres sit between pixels; check the four pixels around each centre.
      for (int q = 0; q < 4; ++q) {
        const int x = 4 * i + 1 + (q & 1), y = 4 * j + 1 + (q >> 1);
        // Field at the pixel: bilinear between cell centres, ~ the cell value near the centre.
        const double ux = f.total_x[k] / f.pitch_mm, uy = f.total_y[k] / f.pitch_mm;
        const Eigen::Vector3d p = pattern.eval(x - ux, y - uy);
        const Eigen::Vector3d p0 = pattern.eval(x, y);
        for (int ch = 0; ch < 3; ++ch) {
          err += std::abs(img[(static_cast<std::size_t>(y) * kW + x) * 3 + ch] - 255.0 * p[ch]);
          moved += std::abs(img[(static_cast<std::size_t>(y) * kW + x) * 3 + ch] - 255.0 * p0[ch]);
          ++n;
        }
      }
    }
  }
  ASSERT_GT(n, 1000);
  EXPECT_LT(err / n, 3.0);
  EXPECT_GT(moved / n, 4.0 * err / n);
}

TEST(SimImage, DeterministicFromTheSeed) {
  SimConfig c;
  c.scenario.axis = MotionAxis::kRy;
  c.scenario.magnitude = 30.0;
  c.seed = 42;
  std::string error;
  auto a = Simulator::create(c, &error);
  auto b = Simulator::create(c, &error);
  c.seed = 43;
  auto other = Simulator::create(c, &error);
  ASSERT_TRUE(a && b && other) << error;
  for (double t : {0.0, 0.7, 1.2}) {
    for (Sensor s : {Sensor::kLeft, Sensor::kRight}) {
      const auto ia = render(*a, s, t), ib = render(*b, s, t), io = render(*other, s, t);
      EXPECT_EQ(ia, ib);
      std::size_t diff = 0;
      for (std::size_t k = 0; k < ia.size(); ++k) diff += ia[k] != io[k] ? 1 : 0;
      EXPECT_GT(diff, ia.size() / 2);
    }
  }
  // Re-rendering the same time after a reset gives the same frame (noise keyed on time).
  a->reset(Sensor::kLeft);
  b->reset(Sensor::kLeft);
  EXPECT_EQ(render(*a, Sensor::kLeft, 0.3), render(*b, Sensor::kLeft, 0.3));
  // The two pads carry different gels (patterns).
  a->reset(Sensor::kLeft);
  a->reset(Sensor::kRight);
  EXPECT_NE(render(*a, Sensor::kLeft, 0.05), render(*a, Sensor::kRight, 0.05));
}

TEST(SimImage, ShotAndReadNoiseHaveTheModelledVariance) {
  SimConfig c;
  c.camera.flicker = 0.0;
  std::string error;
  auto sim = Simulator::create(c, &error);
  ASSERT_TRUE(sim) << error;
  // Approach phase: no contact, so two frames differ by noise only.
  const auto f1 = render(*sim, Sensor::kLeft, 0.01);
  const auto f2 = render(*sim, Sensor::kLeft, 0.02);
  double var_diff = 0.0, var_model = 0.0;
  for (std::size_t k = 0; k < f1.size(); ++k) {
    const double d = static_cast<double>(f1[k]) - f2[k];
    var_diff += d * d;
    const double level = 0.5 * (f1[k] + f2[k]);
    var_model += 2.0 * (level / c.camera.electrons_per_dn +
                        c.camera.read_noise_dn * c.camera.read_noise_dn + 1.0 / 12.0);
  }
  EXPECT_NEAR(var_diff / var_model, 1.0, 0.1);
}

TEST(SimImage, FlickerStaysWithinItsAmplitude) {
  Camera cam;
  cam.build(RigSpec{}, CameraSpec{}, 3, Sensor::kLeft);
  double lo = 2.0, hi = 0.0;
  for (int i = 0; i < 600; ++i) {
    const double g = cam.flicker_gain(static_cast<std::int64_t>(i) * 8333333);
    lo = std::min(lo, g);
    hi = std::max(hi, g);
  }
  EXPECT_GE(lo, 0.98);
  EXPECT_LE(hi, 1.02);
  EXPECT_GT(hi - lo, 0.02);
}

TEST(SimImage, GreyFramesAreTheLumaOfRgb) {
  SimConfig c;
  c.camera.noise = 0.0;
  std::string error;
  auto a = Simulator::create(c, &error);
  auto b = Simulator::create(c, &error);
  ASSERT_TRUE(a && b) << error;
  const auto rgb = render(*a, Sensor::kRight, 0.8, 3);
  const auto grey = render(*b, Sensor::kRight, 0.8, 1);
  int worst = 0;
  for (std::size_t k = 0; k < grey.size(); ++k) {
    const double y = 0.299 * rgb[3 * k] + 0.587 * rgb[3 * k + 1] + 0.114 * rgb[3 * k + 2];
    worst = std::max(worst, static_cast<int>(std::lround(std::abs(y - grey[k]) + 0.49)));
  }
  EXPECT_LE(worst, 1);
  std::vector<std::uint8_t> small(10);
  EXPECT_EQ(a->render(Sensor::kLeft, 0, small, 3), SimStatus::kBadBuffer);
  EXPECT_EQ(a->render(Sensor::kLeft, 0, std::span<std::uint8_t>(small.data(), small.size()), 2),
            SimStatus::kBadBuffer);
}

}  // namespace
}  // namespace tacse3::sim
