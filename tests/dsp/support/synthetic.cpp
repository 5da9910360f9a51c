// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: analytic random-dot texture rendered under known warps into sensor frames.
#include "support/synthetic.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "tacse3/dsp/luma.hpp"

namespace tacse3::test {
namespace {

constexpr double kBucket = 16.0;
constexpr double kCutoffSigmas = 3.5;
constexpr int kLatticePerPx = 4;

// Catmull-Rom weights for the fraction t of a cell.
std::array<double, 4> catmull_rom(double t) {
  const double t2 = t * t, t3 = t2 * t;
  return {0.5 * (-t3 + 2 * t2 - t), 0.5 * (3 * t3 - 5 * t2 + 2), 0.5 * (-3 * t3 + 4 * t2 + t),
          0.5 * (t3 - t2)};
}

// splitmix64: tiny, well mixed and bit-identical on every platform.
struct Rng {
  std::uint64_t s;
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
  double normal() {  // Box-Muller
    const double u1 = std::max(uniform(), 1e-300);
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }
};

std::uint8_t to_u8(double v) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0l, 255l));
}

}  // namespace

DotTexture::DotTexture(std::uint64_t seed, const DotTextureOptions& options) : opt_(options) {
  x0_ = -opt_.margin;
  y0_ = -opt_.margin;
  const double w = dsp::kSensorWidth + 2 * opt_.margin;
  const double h = dsp::kSensorHeight + 2 * opt_.margin;
  bw_ = static_cast<int>(std::ceil(w / kBucket));
  bh_ = static_cast<int>(std::ceil(h / kBucket));
  buckets_.assign(static_cast<std::size_t>(bw_ * bh_), {});
  Rng rng{seed};
  const double log_lo = std::log(opt_.min_sigma);
  const double log_hi = std::log(opt_.max_sigma);
  for (int k = 0; k < opt_.dot_count; ++k) {
    Dot d{};
    d.x = x0_ + rng.uniform() * w;
    d.y = y0_ + rng.uniform() * h;
    const double sigma = std::exp(log_lo + rng.uniform() * (log_hi - log_lo));
    d.inv_two_sigma2 = 1.0 / (2.0 * sigma * sigma);
    d.cutoff2 = kCutoffSigmas * kCutoffSigmas * sigma * sigma;
    for (double& a : d.a) a = (2.0 * rng.uniform() - 1.0) * opt_.amplitude;
    d.luma_a = (77.0 * d.a[0] + 150.0 * d.a[1] + 29.0 * d.a[2]) / 256.0;
    const int bx = std::clamp(static_cast<int>((d.x - x0_) / kBucket), 0, bw_ - 1);
    const int by = std::clamp(static_cast<int>((d.y - y0_) / kBucket), 0, bh_ - 1);
    buckets_[static_cast<std::size_t>(by * bw_ + bx)].push_back(d);
  }
  // Luma lattice: splat every dot with separable Gaussian factors.
  lw_ = static_cast<int>(w * kLatticePerPx) + 1;
  lh_ = static_cast<int>(h * kLatticePerPx) + 1;
  lattice_.assign(static_cast<std::size_t>(lw_) * static_cast<std::size_t>(lh_),
                  static_cast<float>(opt_.background));
  std::vector<double> fx, fy;
  for (const auto& bucket : buckets_) {
    for (const Dot& d : bucket) {
      const double cut = std::sqrt(d.cutoff2);
      const int i0 = std::max(0, static_cast<int>(std::ceil((d.x - cut - x0_) * kLatticePerPx)));
      const int i1 =
          std::min(lw_ - 1, static_cast<int>(std::floor((d.x + cut - x0_) * kLatticePerPx)));
      const int j0 = std::max(0, static_cast<int>(std::ceil((d.y - cut - y0_) * kLatticePerPx)));
      const int j1 =
          std::min(lh_ - 1, static_cast<int>(std::floor((d.y + cut - y0_) * kLatticePerPx)));
      if (i1 < i0 || j1 < j0) continue;
      fx.resize(static_cast<std::size_t>(i1 - i0 + 1));
      fy.resize(static_cast<std::size_t>(j1 - j0 + 1));
      for (int i = i0; i <= i1; ++i) {
        const double dx = x0_ + static_cast<double>(i) / kLatticePerPx - d.x;
        fx[static_cast<std::size_t>(i - i0)] = std::exp(-dx * dx * d.inv_two_sigma2);
      }
      for (int j = j0; j <= j1; ++j) {
        const double dy = y0_ + static_cast<double>(j) / kLatticePerPx - d.y;
        fy[static_cast<std::size_t>(j - j0)] = d.luma_a * std::exp(-dy * dy * d.inv_two_sigma2);
      }
      for (int j = j0; j <= j1; ++j) {
        float* row = lattice_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(lw_);
        const double a = fy[static_cast<std::size_t>(j - j0)];
        const double dy = y0_ + static_cast<double>(j) / kLatticePerPx - d.y;
        for (int i = i0; i <= i1; ++i) {
          const double dx = x0_ + static_cast<double>(i) / kLatticePerPx - d.x;
          if (dx * dx + dy * dy < d.cutoff2) {
            row[i] += static_cast<float>(a * fx[static_cast<std::size_t>(i - i0)]);
          }
        }
      }
    }
  }
}

template <typename F>
void DotTexture::for_dots_near(double x, double y, F&& f) const {
  const int reach = static_cast<int>(std::ceil(kCutoffSigmas * opt_.max_sigma / kBucket));
  const int cx = static_cast<int>(std::floor((x - x0_) / kBucket));
  const int cy = static_cast<int>(std::floor((y - y0_) / kBucket));
  for (int by = std::max(cy - reach, 0); by <= std::min(cy + reach, bh_ - 1); ++by) {
    for (int bx = std::max(cx - reach, 0); bx <= std::min(cx + reach, bw_ - 1); ++bx) {
      for (const Dot& d : buckets_[static_cast<std::size_t>(by * bw_ + bx)]) {
        const double dx = x - d.x;
        const double dy = y - d.y;
        const double r2 = dx * dx + dy * dy;
        if (r2 < d.cutoff2) f(d, std::exp(-r2 * d.inv_two_sigma2));
      }
    }
  }
}

Rgb DotTexture::rgb(double x, double y) const {
  Rgb c{opt_.background, opt_.background, opt_.background};
  for_dots_near(x, y, [&](const Dot& d, double g) {
    for (int k = 0; k < 3; ++k)
      c[static_cast<std::size_t>(k)] += g * d.a[static_cast<std::size_t>(k)];
  });
  return c;
}

double DotTexture::luma(double x, double y) const {
  const double u = (x - x0_) * kLatticePerPx;
  const double v = (y - y0_) * kLatticePerPx;
  const int iu = static_cast<int>(std::floor(u));
  const int iv = static_cast<int>(std::floor(v));
  if (iu < 1 || iv < 1 || iu + 2 >= lw_ || iv + 2 >= lh_) return luma_exact(x, y);
  const auto wu = catmull_rom(u - iu);
  const auto wv = catmull_rom(v - iv);
  double acc = 0.0;
  for (int b = 0; b < 4; ++b) {
    const float* row = lattice_.data() +
                       static_cast<std::size_t>(iv - 1 + b) * static_cast<std::size_t>(lw_) +
                       static_cast<std::size_t>(iu - 1);
    const double r = wu[0] * static_cast<double>(row[0]) + wu[1] * static_cast<double>(row[1]) +
                     wu[2] * static_cast<double>(row[2]) + wu[3] * static_cast<double>(row[3]);
    acc += wv[static_cast<std::size_t>(b)] * r;
  }
  return acc;
}

double DotTexture::luma_exact(double x, double y) const {
  double v = opt_.background;
  for_dots_near(x, y, [&](const Dot& d, double g) { v += g * d.luma_a; });
  return v;
}

Warp Warp::identity() {
  return shift(0.0, 0.0);
}

Warp Warp::shift(double dx, double dy) {
  return {[=](double x, double y) {
            return Vec2{x + dx, y + dy};
          },
          [=](double x, double y) {
            return Vec2{x - dx, y - dy};
          }};
}

Warp Warp::affine(double a11, double a12, double a21, double a22, double tx, double ty) {
  const double cx = dsp::kPadCentreX;
  const double cy = dsp::kPadCentreY;
  const double det = a11 * a22 - a12 * a21;
  const double i11 = a22 / det, i12 = -a12 / det, i21 = -a21 / det, i22 = a11 / det;
  return {[=](double x, double y) {
            const double mx = x - cx, my = y - cy;
            return Vec2{cx + a11 * mx + a12 * my + tx, cy + a21 * mx + a22 * my + ty};
          },
          [=](double x, double y) {
            const double px = x - cx - tx, py = y - cy - ty;
            return Vec2{cx + i11 * px + i12 * py, cy + i21 * px + i22 * py};
          }};
}

Warp Warp::displacement(std::function<Vec2(double, double)> u) {
  auto fwd = [u](double x, double y) {
    const Vec2 d = u(x, y);
    return Vec2{x + d[0], y + d[1]};
  };
  auto inv = [u](double x, double y) {
    Vec2 m{x, y};
    for (int it = 0; it < 60; ++it) {
      const Vec2 d = u(m[0], m[1]);
      const Vec2 next{x - d[0], y - d[1]};
      const double change = std::abs(next[0] - m[0]) + std::abs(next[1] - m[1]);
      m = next;
      if (change < 1e-10) break;  // far below any tolerance of the tests (1e-3 px)
    }
    return m;
  };
  return {fwd, inv};
}

Vec2 Warp::grid_displacement_work(int gx, int gy) const {
  const double mx = dsp::grid_sensor_x(gx);
  const double my = dsp::grid_sensor_y(gy);
  const Vec2 p = forward(mx, my);
  return {(p[0] - mx) / dsp::kWorkScale, (p[1] - my) / dsp::kWorkScale};
}

std::vector<std::uint8_t> render_frame(const DotTexture& tex, const Warp& warp,
                                       dsp::PixelFormat format, const Photometric& ph) {
  const int w = dsp::kSensorWidth;
  const int h = dsp::kSensorHeight;
  const int row_bytes = dsp::packed_row_bytes(format);
  std::vector<std::uint8_t> out(static_cast<std::size_t>(row_bytes * h));
  Rng noise{ph.noise_seed};
  const double corner2 = dsp::kPadCentreX * dsp::kPadCentreX + dsp::kPadCentreY * dsp::kPadCentreY;
  auto finish = [&](double v, int i, int j) {
    const double dx = i - dsp::kPadCentreX;
    const double dy = j - dsp::kPadCentreY;
    const double vig = 1.0 - ph.vignetting * (dx * dx + dy * dy) / corner2;
    double o = ph.gain * v * vig + ph.offset;
    if (ph.noise_sigma > 0.0) o += ph.noise_sigma * noise.normal();
    return to_u8(o);
  };
  for (int j = 0; j < h; ++j) {
    std::uint8_t* row = out.data() + static_cast<std::size_t>(j * row_bytes);
    for (int i = 0; i < w; ++i) {
      const Vec2 m = warp.inverse(i, j);
      switch (format) {
        case dsp::PixelFormat::kRgb888: {
          const Rgb c = tex.rgb(m[0], m[1]);
          for (int k = 0; k < 3; ++k) row[3 * i + k] = finish(c[static_cast<std::size_t>(k)], i, j);
          break;
        }
        case dsp::PixelFormat::kYuyv:
          row[2 * i] = finish(tex.luma(m[0], m[1]), i, j);
          row[2 * i + 1] = 128;
          break;
        case dsp::PixelFormat::kGrey:
          row[i] = finish(tex.luma(m[0], m[1]), i, j);
          break;
      }
    }
  }
  return out;
}

dsp::FrameView frame_view(const std::vector<std::uint8_t>& bytes, dsp::PixelFormat format) {
  dsp::FrameView v;
  v.data = bytes.data();
  v.size_bytes = bytes.size();
  v.width = dsp::kSensorWidth;
  v.height = dsp::kSensorHeight;
  v.stride_bytes = 0;
  v.format = format;
  return v;
}

dsp::WorkImage render_work_image(const DotTexture& tex, const Warp& warp, const Photometric& ph) {
  const auto bytes = render_frame(tex, warp, dsp::PixelFormat::kGrey, ph);
  dsp::WorkImage img;
  (void)dsp::frame_to_work_image(frame_view(bytes, dsp::PixelFormat::kGrey), img);
  return img;
}

std::vector<std::uint8_t> constant_frame(std::uint8_t value, dsp::PixelFormat format) {
  const int row_bytes = dsp::packed_row_bytes(format);
  std::vector<std::uint8_t> out(static_cast<std::size_t>(row_bytes * dsp::kSensorHeight), value);
  if (format == dsp::PixelFormat::kYuyv) {
    for (std::size_t i = 1; i < out.size(); i += 2) out[i] = 128;
  }
  return out;
}

}  // namespace tacse3::test
