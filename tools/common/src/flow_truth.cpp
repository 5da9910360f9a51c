// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the simulator's true displacement on the flow grid and a flow's RMS error.
#include "tacse3/tools/flow_truth.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "tacse3/dsp/geometry.hpp"

namespace tacse3::tools {

namespace {

constexpr double kQ16 = 1.0 / 65536.0;

// Bilinear interpolation of one channel of a row-major w x h image at (x, y), clamped at the
// edges like the simulator's renderer.
template <typename Sample>
double bilinear(Sample sample, int w, int h, double x, double y) noexcept {
  const double cx = std::clamp(x, 0.0, w - 1.0), cy = std::clamp(y, 0.0, h - 1.0);
  const int i0 = std::min(static_cast<int>(cx), w - 1), j0 = std::min(static_cast<int>(cy), h - 1);
  const int i1 = std::min(i0 + 1, w - 1), j1 = std::min(j0 + 1, h - 1);
  const double wx = cx - i0, wy = cy - j0;
  const double top = sample(i0, j0) + wx * (sample(i1, j0) - sample(i0, j0));
  const double bottom = sample(i0, j1) + wx * (sample(i1, j1) - sample(i0, j1));
  return top + wy * (bottom - top);
}

// Cell coordinate of a sensor-pixel coordinate: cell i is centred on pixel kCellPx i + 1.5.
double cell_coordinate(double sensor_px) noexcept {
  return (sensor_px - 0.5 * (sim::kCellPx - 1)) / sim::kCellPx;
}

struct Vec {
  double x = 0.0, y = 0.0;
};

// The Eulerian displacement U at sensor pixel p, in sensor px.
Vec field_at(const sim::PadFields& f, Vec p) noexcept {
  const double cx = cell_coordinate(p.x), cy = cell_coordinate(p.y);
  auto ux = [&f](int i, int j) { return f.total_x[f.index(i, j)]; };
  auto uy = [&f](int i, int j) { return f.total_y[f.index(i, j)]; };
  return {bilinear(ux, f.gw, f.gh, cx, cy) / f.pitch_mm,
          bilinear(uy, f.gw, f.gh, cx, cy) / f.pitch_mm};
}

bool contact_at(const sim::PadFields& f, Vec p) noexcept {
  const int i = std::clamp(static_cast<int>(std::lround(cell_coordinate(p.x))), 0, f.gw - 1);
  const int j = std::clamp(static_cast<int>(std::lround(cell_coordinate(p.y))), 0, f.gh - 1);
  return f.contact[f.index(i, j)] != 0;
}

}  // namespace

GridFlow grid_flow(const dsp::VectorField& q16) noexcept {
  GridFlow g;
  for (std::size_t k = 0; k < g.x.size(); ++k) {
    g.x[k] = q16.x.v[k] * kQ16;
    g.y[k] = q16.y.v[k] * kQ16;
  }
  return g;
}

GridFlow grid_flow(const float* xy, int width, int height) noexcept {
  GridFlow g;
  const auto w = static_cast<std::size_t>(width);
  auto fx = [xy, w](int i, int j) {
    return static_cast<double>(xy[2 * (static_cast<std::size_t>(j) * w + i)]);
  };
  auto fy = [xy, w](int i, int j) {
    return static_cast<double>(xy[2 * (static_cast<std::size_t>(j) * w + i) + 1]);
  };
  for (int gy = 0; gy < dsp::kGridHeight; ++gy) {
    for (int gx = 0; gx < dsp::kGridWidth; ++gx) {
      const auto k = static_cast<std::size_t>(gy * dsp::kGridWidth + gx);
      g.x[k] = bilinear(fx, width, height, dsp::grid_work_x(gx), dsp::grid_work_y(gy));
      g.y[k] = bilinear(fy, width, height, dsp::grid_work_x(gx), dsp::grid_work_y(gy));
    }
  }
  return g;
}

GridTruth grid_truth(const sim::PadFields& ref, const sim::PadFields& cur) noexcept {
  GridTruth t;
  for (int gy = 0; gy < dsp::kGridHeight; ++gy) {
    for (int gx = 0; gx < dsp::kGridWidth; ++gx) {
      const Vec p{dsp::grid_sensor_x(gx), dsp::grid_sensor_y(gy)};
      const Vec u0 = field_at(ref, p);
      const Vec m{p.x - u0.x, p.y - u0.y};
      // x = m + U_cur(x): a contraction wherever the gel is not folded (|dU/dx| < 1).
      Vec x = p;
      for (int it = 0; it < 50; ++it) {
        const Vec u = field_at(cur, x);
        const Vec next{m.x + u.x, m.y + u.y};
        const double step = std::hypot(next.x - x.x, next.y - x.y);
        x = next;
        if (step < 1e-9) break;
      }
      const auto k = static_cast<std::size_t>(gy * dsp::kGridWidth + gx);
      t.flow.x[k] = (x.x - p.x) / dsp::kWorkScale;
      t.flow.y[k] = (x.y - p.y) / dsp::kWorkScale;
      t.contact[k] = contact_at(cur, x) ? 1 : 0;
    }
  }
  return t;
}

int GridTruth::contact_count() const noexcept {
  return static_cast<int>(std::count(contact.begin(), contact.end(), std::uint8_t{1}));
}

void FlowError::add(const GridTruth& truth, const GridFlow& estimate) noexcept {
  for (std::size_t k = 0; k < truth.contact.size(); ++k) {
    if (!truth.contact[k]) continue;
    const double ex = estimate.x[k] - truth.flow.x[k], ey = estimate.y[k] - truth.flow.y[k];
    sum_sq_ += ex * ex + ey * ey;
    ++points_;
  }
}

void FlowError::merge(const FlowError& other) noexcept {
  sum_sq_ += other.sum_sq_;
  points_ += other.points_;
}

double FlowError::rms_px() const noexcept {
  return points_ > 0 ? std::sqrt(sum_sq_ / static_cast<double>(points_)) : 0.0;
}

}  // namespace tacse3::tools
