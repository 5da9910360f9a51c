// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: image formation (warp, illumination, shading, flicker, shot and read noise).
#include "tacse3/sim/camera.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "tacse3/sim/rng.hpp"

namespace tacse3::sim {
namespace {

constexpr int kNormalTableBits = 16;
constexpr int kNormalTableSize = 1 << kNormalTableBits;

bool finite_in(double v, double lo, double hi) {
  return std::isfinite(v) && v >= lo && v <= hi;
}

// Inverse standard normal CDF (P. J. Acklam's rational approximation, |rel. err| < 1.2e-9).
double normal_quantile(double p) {
  static constexpr double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,
                                 -2.759285104469687e+02, 1.383577518672690e+02,
                                 -3.066479806614716e+01, 2.506628277459239e+00};
  static constexpr double b[] = {-5.447609879822406e+01, 1.615858368580409e+02,
                                 -1.556989798598866e+02, 6.680131188771972e+01,
                                 -1.328068155288572e+01};
  static constexpr double c[] = {-7.784894002430293e-03, -3.223964580411365e-01,
                                 -2.400758277161838e+00, -2.549732539343734e+00,
                                 4.374664141464968e+00,  2.938163982698783e+00};
  static constexpr double d[] = {7.784695709041462e-03, 3.224671290700398e-01,
                                 2.445134137142996e+00, 3.754408661907416e+00};
  constexpr double lo = 0.02425;
  if (p < lo) {
    const double q = std::sqrt(-2.0 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  }
  if (p > 1.0 - lo) {
    const double q = std::sqrt(-2.0 * std::log(1.0 - p));
    return -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  }
  const double q = p - 0.5;
  const double r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
}

inline std::uint8_t quantise(float v) noexcept {
  v = v < 0.0f ? 0.0f : (v > 255.0f ? 255.0f : v);
  return static_cast<std::uint8_t>(v + 0.5f);
}

}  // namespace

std::string validate(const CameraSpec& c) {
  if (!finite_in(c.exposure, 0.0, 10.0)) return "camera exposure must be in [0, 10]";
  if (!finite_in(c.vignetting_corner, 0.05, 1.0))
    return "camera vignetting_corner must be in [0.05, 1]";
  for (int k = 0; k < 3; ++k) {
    if (!finite_in(c.tint[k], 0.0, 4.0)) return "camera tint must be in [0, 4] per channel";
    if (!finite_in(c.tint_gradient[k], -1.0, 1.0)) {
      return "camera tint_gradient must be in [-1, 1] per channel";
    }
  }
  if (!finite_in(c.flicker, 0.0, 0.5)) return "camera flicker must be in [0, 0.5]";
  if (!finite_in(c.flicker_hz, 0.0, 1000.0)) return "camera flicker_hz must be in [0, 1000]";
  if (!finite_in(c.noise, 0.0, 100.0)) return "camera noise must be in [0, 100]";
  if (!finite_in(c.electrons_per_dn, 0.01, 1e6)) return "camera electrons_per_dn must be > 0";
  if (!finite_in(c.read_noise_dn, 0.0, 100.0)) return "camera read_noise_dn must be in [0, 100]";
  if (c.mjpeg_quality < 0 || c.mjpeg_quality > 100)
    return "camera mjpeg_quality must be in [0, 100]";
  if (c.mjpeg_quality > 0 && !mjpeg_available()) {
    return "camera mjpeg_quality needs libturbojpeg, which this build lacks "
           "(apt-get install libturbojpeg0-dev)";
  }
  return validate(c.shading);
}

void Camera::build(const RigSpec& rig, const CameraSpec& spec, std::uint64_t seed, Sensor sensor) {
  rig_ = rig;
  spec_ = spec;
  seed_ = seed;
  sensor_ = sensor;
  const int w = rig.width, h = rig.height;
  const double cx = 0.5 * (w - 1), cy = 0.5 * (h - 1);
  const double r_corner = std::hypot(cx, cy);
  // V(r) = (1 + (r/rv)^2)^-2 (cos^4 law of a lens at focal length rv), V(corner) as given.
  const double rv =
      r_corner / std::sqrt(std::max(1e-9, 1.0 / std::sqrt(spec.vignetting_corner) - 1.0));
  gain_.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double rr = std::hypot(x - cx, y - cy) / rv;
      const double vig =
          spec.vignetting_corner >= 1.0 ? 1.0 : 1.0 / ((1.0 + rr * rr) * (1.0 + rr * rr));
      const double across = (x - cx) / (w - 1);  // -0.5 .. 0.5
      for (int c = 0; c < 3; ++c) {
        const double g =
            255.0 * spec.exposure * vig * spec.tint[c] * (1.0 + spec.tint_gradient[c] * across);
        gain_[(static_cast<std::size_t>(y) * static_cast<std::size_t>(w) +
               static_cast<std::size_t>(x)) *
                  3 +
              static_cast<std::size_t>(c)] = static_cast<float>(g);
      }
    }
  }
  const int gw = w / kCellPx;
  xi0_.resize(static_cast<std::size_t>(w));
  xi1_.resize(static_cast<std::size_t>(w));
  xw_.resize(static_cast<std::size_t>(w));
  for (int x = 0; x < w; ++x) {
    const double g = std::clamp((x - 0.5 * (kCellPx - 1)) / kCellPx, 0.0, gw - 1.0);
    const int i0 = std::min(static_cast<int>(g), gw - 1);
    xi0_[static_cast<std::size_t>(x)] = i0;
    xi1_[static_cast<std::size_t>(x)] = std::min(i0 + 1, gw - 1);
    xw_[static_cast<std::size_t>(x)] = static_cast<float>(g - i0);
  }
  row_x_.resize(static_cast<std::size_t>(gw));
  row_y_.resize(static_cast<std::size_t>(gw));
  row_s_.resize(static_cast<std::size_t>(gw));
  line_.resize(static_cast<std::size_t>(w) * 3);
  noise_line_.resize(static_cast<std::size_t>(w) * 3 + 4);
  sigma_.resize(257);
  for (int v = 0; v <= 256; ++v) {
    sigma_[static_cast<std::size_t>(v)] =
        static_cast<float>(spec.noise * std::sqrt(v / spec.electrons_per_dn +
                                                  spec.read_noise_dn * spec.read_noise_dn));
  }
  normal_.resize(kNormalTableSize);
  for (int k = 0; k < kNormalTableSize; ++k) {
    normal_[static_cast<std::size_t>(k)] =
        static_cast<float>(normal_quantile((k + 0.5) / kNormalTableSize));
  }
  if (spec.mjpeg_quality > 0) (void)mjpeg_.build(w, h, spec.mjpeg_quality);
}

double Camera::flicker_gain(std::int64_t t_ns) const noexcept {
  if (spec_.flicker <= 0.0) return 1.0;
  const std::uint64_t base = hash_combine(seed_, 0xF11C + static_cast<std::uint64_t>(sensor_));
  const double phase =
      static_cast<double>(base >> 11) * (2.0 * std::numbers::pi / 9007199254740992.0);
  const double t = static_cast<double>(t_ns) * 1e-9;
  const double slow = std::sin(2.0 * std::numbers::pi * spec_.flicker_hz * t + phase);
  Rng rng(hash_combine(base, static_cast<std::uint64_t>(t_ns)));
  const double fast = rng.uniform(-1.0, 1.0);
  return 1.0 + spec_.flicker * (0.6 * slow + 0.4 * fast);
}

bool Camera::render(const Pattern& pattern, const PadFields& f, std::int64_t t_ns,
                    std::uint8_t* out, int channels) noexcept {
  const int w = rig_.width, h = rig_.height, gw = f.gw, gh = f.gh;
  const auto uw = static_cast<std::size_t>(w);
  const auto flick = static_cast<float>(flicker_gain(t_ns));
  const bool noisy = spec_.noise > 0.0;
  Rng rng(hash_combine(hash_combine(seed_, 0x4015E + static_cast<std::uint64_t>(sensor_)),
                       static_cast<std::uint64_t>(t_ns)));
  const float* sigma = sigma_.data();
  const float* normal = normal_.data();
  float* line = line_.data();
  float* zline = noise_line_.data();
  const std::size_t nvals = uw * static_cast<std::size_t>(channels);
  for (int y = 0; y < h; ++y) {
    // Field rows interpolated along y, in pixels; shading times flicker.
    const double gyd = std::clamp((y - 0.5 * (kCellPx - 1)) / kCellPx, 0.0, gh - 1.0);
    const int j0 = std::min(static_cast<int>(gyd), gh - 1);
    const int j1 = std::min(j0 + 1, gh - 1);
    const double wy = gyd - j0;
    const double scale = 1.0 / f.pitch_mm;
    for (int i = 0; i < gw; ++i) {
      const std::size_t a = f.index(i, j0), b = f.index(i, j1);
      const auto ui = static_cast<std::size_t>(i);
      row_x_[ui] = static_cast<float>((f.total_x[a] + wy * (f.total_x[b] - f.total_x[a])) * scale);
      row_y_[ui] = static_cast<float>((f.total_y[a] + wy * (f.total_y[b] - f.total_y[a])) * scale);
      row_s_[ui] = static_cast<float>(f.shade[a] + wy * (f.shade[b] - f.shade[a])) * flick;
    }
    // Backward warp: the pattern at x - U(x), times illumination and shading.
    const float* g = &gain_[static_cast<std::size_t>(y) * uw * 3];
    const auto fy = static_cast<float>(y);
    for (std::size_t x = 0; x < uw; ++x) {
      const auto i0 = static_cast<std::size_t>(xi0_[x]), i1 = static_cast<std::size_t>(xi1_[x]);
      const float wx = xw_[x];
      const float bx = row_x_[i0] + wx * (row_x_[i1] - row_x_[i0]);
      const float by = row_y_[i0] + wx * (row_y_[i1] - row_y_[i0]);
      const float s = row_s_[i0] + wx * (row_s_[i1] - row_s_[i0]);
      float* v = line + 3 * x;
      pattern.sample(static_cast<float>(x) - bx, fy - by, v);
      v[0] *= g[3 * x] * s;
      v[1] *= g[3 * x + 1] * s;
      v[2] *= g[3 * x + 2] * s;
    }
    if (channels == 1) {
      for (std::size_t x = 0; x < uw; ++x) {
        line[x] = 0.299f * line[3 * x] + 0.587f * line[3 * x + 1] + 0.114f * line[3 * x + 2];
      }
    }
    std::uint8_t* o = out + static_cast<std::size_t>(y) * nvals;
    if (!noisy) {
      for (std::size_t k = 0; k < nvals; ++k) o[k] = quantise(line[k]);
      continue;
    }
    // Shot + read noise: sigma(level) * N(0, 1), four table draws per 64 random bits.
    for (std::size_t k = 0; k < nvals; k += 4) {
      std::uint64_t bits = rng.next();
      for (std::size_t q = 0; q < 4 && k + q < nvals; ++q) {
        zline[k + q] = normal[bits & (kNormalTableSize - 1)];
        bits >>= kNormalTableBits;
      }
    }
    for (std::size_t k = 0; k < nvals; ++k) {
      const float v = line[k];
      const int lvl = v <= 0.0f ? 0 : (v >= 256.0f ? 256 : static_cast<int>(v));
      o[k] = quantise(v + sigma[lvl] * zline[k]);
    }
  }
  return spec_.mjpeg_quality <= 0 || mjpeg_.roundtrip(out, channels);
}

}  // namespace tacse3::sim
