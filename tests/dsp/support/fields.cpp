// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: analytic grid vector fields, discrete operators and error metrics (mid stages).
#include "support/fields.hpp"

#include <cmath>
#include <cstddef>
#include <limits>

#include "tacse3/dsp/fixed.hpp"

namespace tacse3::test::fields {

using dsp::kGridCount;
using dsp::kGridHeight;
using dsp::kGridWidth;
using dsp_ref::GridMaskD;
using dsp_ref::GridScalarD;
using dsp_ref::GridVectorD;

namespace {
constexpr double kCx = 0.5 * (kGridWidth - 1);
constexpr double kCy = 0.5 * (kGridHeight - 1);

// (1 - exp(-r^2 / 2 s^2)) s^2 / r^2, with its limit 1/2 at r = 0.
double gaussian_profile(double r2, double s) {
  const double a = r2 / (2.0 * s * s);
  if (a < 1e-8) return 0.5;
  return -std::expm1(-a) / (2.0 * a);
}
}  // namespace

GridVectorD sample(const FieldFn& f) {
  GridVectorD w;
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const std::size_t p = static_cast<std::size_t>(gy * kGridWidth + gx);
      f(gx - kCx, gy - kCy, w.x[p], w.y[p]);
    }
  }
  return w;
}

GridVectorD add(const GridVectorD& a, const GridVectorD& b) {
  GridVectorD c;
  for (std::size_t i = 0; i < kGridCount; ++i) {
    c.x[i] = a.x[i] + b.x[i];
    c.y[i] = a.y[i] + b.y[i];
  }
  return c;
}

GridVectorD scale(const GridVectorD& a, double s) {
  GridVectorD c;
  for (std::size_t i = 0; i < kGridCount; ++i) {
    c.x[i] = s * a.x[i];
    c.y[i] = s * a.y[i];
  }
  return c;
}

FieldFn uniform(double ux, double uy) {
  return [=](double, double, double& u, double& v) {
    u = ux;
    v = uy;
  };
}
FieldFn rigid_rotation(double omega, double cx, double cy) {
  return [=](double x, double y, double& u, double& v) {
    u = -omega * (y - cy);
    v = omega * (x - cx);
  };
}
FieldFn rigid_expansion(double eps, double cx, double cy) {
  return [=](double x, double y, double& u, double& v) {
    u = eps * (x - cx);
    v = eps * (y - cy);
  };
}
FieldFn pure_shear(double a) {
  return [=](double x, double y, double& u, double& v) {
    u = a * x;
    v = -a * y;
  };
}
FieldFn gaussian_vortex(double amp, double s, double cx, double cy) {
  return [=](double x, double y, double& u, double& v) {
    const double dx = x - cx;
    const double dy = y - cy;
    const double g = amp * gaussian_profile(dx * dx + dy * dy, s);
    u = -g * dy;
    v = g * dx;
  };
}
FieldFn gaussian_source(double amp, double s, double cx, double cy) {
  return [=](double x, double y, double& u, double& v) {
    const double dx = x - cx;
    const double dy = y - cy;
    const double g = amp * gaussian_profile(dx * dx + dy * dy, s);
    u = g * dx;
    v = g * dy;
  };
}

double Rng::uniform() {
  state_ ^= state_ >> 12;
  state_ ^= state_ << 25;
  state_ ^= state_ >> 27;
  const std::uint64_t r = state_ * 2685821657736338717ULL;
  return static_cast<double>(r >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

GridVectorD random_smooth(Rng& rng, double amp, double noise) {
  GridVectorD w = sample(uniform(0.3 * amp * rng.uniform(), 0.3 * amp * rng.uniform()));
  for (int n = 0; n < 4; ++n) {
    const double cx = 12.0 * rng.uniform();
    const double cy = 8.0 * rng.uniform();
    const double s = 2.5 + 1.5 * rng.uniform();
    w = add(w, sample(gaussian_vortex(0.5 * amp * rng.uniform(), s, cx, cy)));
    w = add(w, sample(gaussian_source(0.5 * amp * rng.uniform(), s, cx, cy)));
  }
  for (std::size_t i = 0; i < kGridCount && noise > 0.0; ++i) {
    w.x[i] += noise * std::sqrt(3.0) * rng.uniform();
    w.y[i] += noise * std::sqrt(3.0) * rng.uniform();
  }
  return w;
}

GridMaskD random_mask(Rng& rng, double invalid_fraction) {
  GridMaskD m(kGridCount, 1);
  for (std::size_t i = 0; i < kGridCount; ++i) {
    if (0.5 * (rng.uniform() + 1.0) < invalid_fraction) m[i] = 0;
  }
  return m;
}

double rms(const GridVectorD& a, const GridMaskD* mask) {
  double s = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < kGridCount; ++i) {
    if (mask != nullptr && (*mask)[i] == 0) continue;
    s += a.x[i] * a.x[i] + a.y[i] * a.y[i];
    ++n;
  }
  return n == 0 ? 0.0 : std::sqrt(s / static_cast<double>(n));
}

double rms_diff(const GridVectorD& a, const GridVectorD& b, const GridMaskD* mask) {
  double s = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < kGridCount; ++i) {
    if (mask != nullptr && (*mask)[i] == 0) continue;
    const double ex = a.x[i] - b.x[i];
    const double ey = a.y[i] - b.y[i];
    s += ex * ex + ey * ey;
    ++n;
  }
  return n == 0 ? 0.0 : std::sqrt(s / static_cast<double>(n));
}

double rms(const GridScalarD& a, const GridMaskD* mask) {
  double s = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < kGridCount; ++i) {
    if (mask != nullptr && (*mask)[i] == 0) continue;
    s += a[i] * a[i];
    ++n;
  }
  return n == 0 ? 0.0 : std::sqrt(s / static_cast<double>(n));
}

double rms_diff(const GridScalarD& a, const GridScalarD& b, const GridMaskD* mask) {
  double s = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < kGridCount; ++i) {
    if (mask != nullptr && (*mask)[i] == 0) continue;
    s += (a[i] - b[i]) * (a[i] - b[i]);
    ++n;
  }
  return n == 0 ? 0.0 : std::sqrt(s / static_cast<double>(n));
}

double snr_db(const GridVectorD& ref, const GridVectorD& test, const GridMaskD* mask) {
  const double e = rms_diff(ref, test, mask);
  if (e == 0.0) return std::numeric_limits<double>::infinity();
  return 20.0 * std::log10(rms(ref, mask) / e);
}

double snr_db(const GridScalarD& ref, const GridScalarD& test, const GridMaskD* mask) {
  const double e = rms_diff(ref, test, mask);
  if (e == 0.0) return std::numeric_limits<double>::infinity();
  return 20.0 * std::log10(rms(ref, mask) / e);
}

double max_lsb(const GridVectorD& ref, const dsp::VectorField& test, const GridMaskD* mask) {
  double m = 0.0;
  const double lsb = 1.0 / 65536.0;
  for (std::size_t i = 0; i < kGridCount; ++i) {
    if (mask != nullptr && (*mask)[i] == 0) continue;
    m = std::fmax(m, std::fabs(test.x.v[i] * lsb - ref.x[i]) / lsb);
    m = std::fmax(m, std::fabs(test.y.v[i] * lsb - ref.y[i]) / lsb);
  }
  return m;
}

double max_lsb(const GridScalarD& ref, const dsp::ScalarField& test, const GridMaskD* mask) {
  double m = 0.0;
  const double lsb = 1.0 / 65536.0;
  for (std::size_t i = 0; i < kGridCount; ++i) {
    if (mask != nullptr && (*mask)[i] == 0) continue;
    m = std::fmax(m, std::fabs(test.v[i] * lsb - ref[i]) / lsb);
  }
  return m;
}

std::int64_t twice_div(const dsp::VectorField& f, int gx, int gy) {
  return (static_cast<std::int64_t>(f.x(gx + 1, gy)) - f.x(gx - 1, gy)) +
         (static_cast<std::int64_t>(f.y(gx, gy + 1)) - f.y(gx, gy - 1));
}

std::int64_t twice_curl(const dsp::VectorField& f, int gx, int gy) {
  return (static_cast<std::int64_t>(f.y(gx + 1, gy)) - f.y(gx - 1, gy)) -
         (static_cast<std::int64_t>(f.x(gx, gy + 1)) - f.x(gx, gy - 1));
}

double central_div(const GridVectorD& f, int gx, int gy) {
  const auto at = [](int x, int y) { return static_cast<std::size_t>(y * kGridWidth + x); };
  return 0.5 *
         (f.x[at(gx + 1, gy)] - f.x[at(gx - 1, gy)] + f.y[at(gx, gy + 1)] - f.y[at(gx, gy - 1)]);
}

double central_curl(const GridVectorD& f, int gx, int gy) {
  const auto at = [](int x, int y) { return static_cast<std::size_t>(y * kGridWidth + x); };
  return 0.5 *
         (f.y[at(gx + 1, gy)] - f.y[at(gx - 1, gy)] - f.x[at(gx, gy + 1)] + f.x[at(gx, gy - 1)]);
}

}  // namespace tacse3::test::fields
