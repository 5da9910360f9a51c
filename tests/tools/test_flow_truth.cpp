// SPDX-License-Identifier: Apache-2.0
// tools tests: the simulator's true displacement on the flow grid and the RMS flow error that
// tacse3_bench_vs_dis reports, against analytic fields and a known sub-pixel shift.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <memory>
#include <vector>

#include "support/synthetic.hpp"
#include "tacse3/dsp/block_flow.hpp"
#include "tacse3/dsp/geometry.hpp"
#include "tacse3/tools/flow_truth.hpp"

namespace tt = tacse3::tools;
namespace dsp = tacse3::dsp;
namespace sim = tacse3::sim;

namespace {

constexpr double kPitch = 0.1;  // mm per sensor px

sim::PadFields uniform_fields(double ux_px, double uy_px) {
  sim::RigSpec rig;
  rig.pixel_pitch_mm = kPitch;
  sim::PadFields f;
  f.allocate(rig);
  std::fill(f.total_x.begin(), f.total_x.end(), ux_px * kPitch);
  std::fill(f.total_y.begin(), f.total_y.end(), uy_px * kPitch);
  return f;
}

// Contact on the cells of the central part of the pad, away from the image border where
// windows leave the frame.
void set_central_contact(sim::PadFields* f) {
  for (int j = f->gh / 4; j < 3 * f->gh / 4; ++j) {
    for (int i = f->gw / 4; i < 3 * f->gw / 4; ++i) f->contact[f->index(i, j)] = 1;
  }
}

}  // namespace

TEST(FlowTruth, UniformShiftIsTheShiftInWorkingPixels) {
  const sim::PadFields ref = uniform_fields(0.0, 0.0);
  sim::PadFields cur = uniform_fields(0.6, -0.9);  // sensor px
  set_central_contact(&cur);
  const tt::GridTruth t = tt::grid_truth(ref, cur);
  // The central half of the 80 x 60 cells: the grid points whose material sits on those cells.
  EXPECT_EQ(t.contact_count(), 20 * 15);
  for (std::size_t k = 0; k < t.flow.x.size(); ++k) {
    EXPECT_NEAR(t.flow.x[k], 0.3, 1e-9);
    EXPECT_NEAR(t.flow.y[k], -0.45, 1e-9);
  }
}

TEST(FlowTruth, DisplacementIsBetweenTheReferenceAndTheCurrentFrame) {
  // Both frames deformed: the material moved by the difference of the two uniform fields.
  sim::PadFields ref = uniform_fields(1.0, 2.0);
  sim::PadFields cur = uniform_fields(-0.4, 2.5);
  set_central_contact(&cur);
  const tt::GridTruth t = tt::grid_truth(ref, cur);
  EXPECT_NEAR(t.flow.x[600], -0.7, 1e-9);
  EXPECT_NEAR(t.flow.y[600], 0.25, 1e-9);
}

TEST(FlowTruth, FollowsTheMaterialThroughAnEulerianStretch) {
  // U(x) = a (x - c): the material at p ends at x with x - c = (p - c) / (1 - a), so it moved
  // by a (p - c) / (1 - a); U is sampled at x, not at p (a = 0.05 makes the difference 5 %).
  constexpr double a = 0.05, cx = 159.5, cy = 119.5;
  sim::PadFields ref = uniform_fields(0.0, 0.0);
  sim::PadFields cur = uniform_fields(0.0, 0.0);
  for (int j = 0; j < cur.gh; ++j) {
    for (int i = 0; i < cur.gw; ++i) {
      const double x = 4.0 * i + 1.5, y = 4.0 * j + 1.5;
      cur.total_x[cur.index(i, j)] = a * (x - cx) * kPitch;
      cur.total_y[cur.index(i, j)] = a * (y - cy) * kPitch;
    }
  }
  set_central_contact(&cur);
  const tt::GridTruth t = tt::grid_truth(ref, cur);
  for (int gy = 8; gy < 22; ++gy) {
    for (int gx = 10; gx < 30; ++gx) {
      const auto k = static_cast<std::size_t>(gy * dsp::kGridWidth + gx);
      const double px = dsp::grid_sensor_x(gx), py = dsp::grid_sensor_y(gy);
      EXPECT_NEAR(t.flow.x[k], a * (px - cx) / (1.0 - a) / 2.0, 1e-6) << gx << "," << gy;
      EXPECT_NEAR(t.flow.y[k], a * (py - cy) / (1.0 - a) / 2.0, 1e-6) << gx << "," << gy;
    }
  }
}

TEST(FlowTruth, DenseFlowIsSampledAtTheGridPoints) {
  // A linear field is reproduced exactly by bilinear sampling.
  std::vector<float> xy(2 * dsp::kWorkPixels);
  for (int y = 0; y < dsp::kWorkHeight; ++y) {
    for (int x = 0; x < dsp::kWorkWidth; ++x) {
      const auto k = static_cast<std::size_t>(y * dsp::kWorkWidth + x);
      xy[2 * k] = 0.01f * static_cast<float>(x);
      xy[2 * k + 1] = -0.02f * static_cast<float>(y);
    }
  }
  const tt::GridFlow g = tt::grid_flow(xy.data(), dsp::kWorkWidth, dsp::kWorkHeight);
  EXPECT_NEAR(g.x[0], 0.015, 1e-6);
  EXPECT_NEAR(g.y[0], -0.03, 1e-6);
  const std::size_t last = dsp::kGridCount - 1;
  EXPECT_NEAR(g.x[last], 0.01 * (4 * 39 + 1.5), 1e-5);
  EXPECT_NEAR(g.y[last], -0.02 * (4 * 29 + 1.5), 1e-5);
}

TEST(FlowError, ZeroFlowScoresTheShiftAndTheBlockFlowScoresNearZero) {
  // A smooth texture shifted by (0.6, -0.9) sensor px = (0.3, -0.45) working px.
  constexpr double dx = 0.6, dy = -0.9;
  const sim::PadFields ref = uniform_fields(0.0, 0.0);
  sim::PadFields cur = uniform_fields(dx, dy);
  set_central_contact(&cur);
  const tt::GridTruth truth = tt::grid_truth(ref, cur);

  tt::FlowError zero;
  zero.add(truth, tt::GridFlow{});
  EXPECT_EQ(zero.points(), 300);
  EXPECT_NEAR(zero.rms_px(), std::hypot(0.3, 0.45), 1e-9);

  const tacse3::test::DotTexture tex(7);
  const dsp::WorkImage a = tacse3::test::render_work_image(tex, tacse3::test::Warp::identity());
  const dsp::WorkImage b = tacse3::test::render_work_image(tex, tacse3::test::Warp::shift(dx, dy));
  auto flow = std::make_unique<dsp::BlockFlow>();
  dsp::VectorField d;
  dsp::GridMask valid;
  flow->track(a, d, valid);
  flow->track(b, d, valid);
  tt::FlowError good;
  good.add(truth, tt::grid_flow(d));
  EXPECT_LT(good.rms_px(), 0.02);

  // Merging two accumulators pools their points.
  tt::FlowError both = zero;
  both.merge(good);
  EXPECT_EQ(both.points(), 600);
  EXPECT_NEAR(both.rms_px(),
              std::sqrt(0.5 * (zero.rms_px() * zero.rms_px() + good.rms_px() * good.rms_px())),
              1e-12);
}
