// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: random colour-dot pattern generation, analytic evaluation and texture baking.
#include "tacse3/sim/pattern.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "tacse3/sim/rng.hpp"

namespace tacse3::sim {
namespace {

// Printed dot inks (linear RGB reflectance), loosely those of dense colour-pattern gels.
constexpr float kPalette[][3] = {
    {0.85f, 0.14f, 0.12f},  // red
    {0.14f, 0.68f, 0.20f},  // green
    {0.14f, 0.24f, 0.86f},  // blue
    {0.90f, 0.84f, 0.14f},  // yellow
    {0.80f, 0.20f, 0.74f},  // magenta
    {0.14f, 0.74f, 0.80f},  // cyan
    {0.07f, 0.07f, 0.08f},  // black
    {0.95f, 0.95f, 0.93f},  // white
};
constexpr int kPaletteSize = sizeof(kPalette) / sizeof(kPalette[0]);

bool finite_in(double v, double lo, double hi) {
  return std::isfinite(v) && v >= lo && v <= hi;
}

}  // namespace

std::string validate(const PatternSpec& s) {
  if (!finite_in(s.dot_spacing_mm, 0.01, 10.0))
    return "pattern dot_spacing_mm must be in [0.01, 10]";
  if (!finite_in(s.dot_radius_min_mm, 0.001, s.dot_spacing_mm) ||
      !finite_in(s.dot_radius_max_mm, s.dot_radius_min_mm, s.dot_spacing_mm)) {
    return "pattern dot radii must satisfy 0 < min <= max <= spacing";
  }
  if (!finite_in(s.dot_jitter, 0.0, 0.5)) return "pattern dot_jitter must be in [0, 0.5]";
  if (!finite_in(s.dot_fill, 0.0, 1.0)) return "pattern dot_fill must be in [0, 1]";
  if (!finite_in(s.edge_px, 0.3, 5.0)) return "pattern edge_px must be in [0.3, 5]";
  if (!finite_in(s.background, 0.0, 1.0)) return "pattern background must be in [0, 1]";
  if (s.supersample < 1 || s.supersample > 8) return "pattern supersample must be in [1, 8]";
  if (s.margin_px < 8 || s.margin_px > 512) return "pattern margin_px must be in [8, 512]";
  return {};
}

void Pattern::build(const PatternSpec& spec, double pixel_pitch_mm, int width, int height,
                    std::uint64_t seed) {
  spec_ = spec;
  margin_ = spec.margin_px;
  spacing_px_ = spec.dot_spacing_mm / pixel_pitch_mm;
  const double lo = -margin_ - 2.0 * spacing_px_;
  origin_ = lo;
  cells_x_ = static_cast<int>(std::ceil((width + 2.0 * margin_ + 4.0 * spacing_px_) / spacing_px_));
  cells_y_ =
      static_cast<int>(std::ceil((height + 2.0 * margin_ + 4.0 * spacing_px_) / spacing_px_));
  const double reach_px =
      spec.dot_jitter * spacing_px_ + spec.dot_radius_max_mm / pixel_pitch_mm + spec.edge_px;
  reach_ = static_cast<int>(std::ceil(reach_px / spacing_px_ + 0.5));

  Rng rng(hash_combine(seed, 0xD07D07));
  dots_.assign(static_cast<std::size_t>(cells_x_) * static_cast<std::size_t>(cells_y_), Dot{});
  for (int j = 0; j < cells_y_; ++j) {
    for (int i = 0; i < cells_x_; ++i) {
      Dot& d = dots_[static_cast<std::size_t>(j) * static_cast<std::size_t>(cells_x_) +
                     static_cast<std::size_t>(i)];
      const double jx = rng.uniform(-spec.dot_jitter, spec.dot_jitter);
      const double jy = rng.uniform(-spec.dot_jitter, spec.dot_jitter);
      const double r_mm = rng.uniform(spec.dot_radius_min_mm, spec.dot_radius_max_mm);
      const int colour = static_cast<int>(rng.uniform() * kPaletteSize) % kPaletteSize;
      const double shade = rng.uniform(0.8, 1.1);
      d.present = rng.uniform() < spec.dot_fill;
      d.x = origin_ + (i + 0.5 + jx) * spacing_px_;
      d.y = origin_ + (j + 0.5 + jy) * spacing_px_;
      d.r = r_mm / pixel_pitch_mm;
      for (int c = 0; c < 3; ++c) {
        d.rgb[c] =
            std::min(1.0f, static_cast<float>(static_cast<double>(kPalette[colour][c]) * shade));
      }
      if (spec.grey_dots) {
        const float luma = 0.299f * d.rgb[0] + 0.587f * d.rgb[1] + 0.114f * d.rgb[2];
        d.rgb[0] = d.rgb[1] = d.rgb[2] = luma;
      }
    }
  }

  // Bake the texture: the same compositing as eval(), dot by dot over its footprint.
  const int s = spec.supersample;
  scale_ = static_cast<float>(s);
  tex_w_ = (width + 2 * margin_) * s;
  tex_h_ = (height + 2 * margin_) * s;
  max_x_ = static_cast<float>(tex_w_ - 1) - 1e-3f;
  max_y_ = static_cast<float>(tex_h_ - 1) - 1e-3f;
  texture_.assign(static_cast<std::size_t>(tex_w_) * static_cast<std::size_t>(tex_h_) * 3,
                  static_cast<float>(spec.background));
  const double inv_s = 1.0 / s;
  for (const Dot& d : dots_) {
    if (!d.present) continue;
    const double ext = d.r + spec.edge_px + 1.0;
    const int a0 = std::max(0, static_cast<int>(std::floor((d.x - ext + margin_) * s)));
    const int a1 = std::min(tex_w_ - 1, static_cast<int>(std::ceil((d.x + ext + margin_) * s)));
    const int b0 = std::max(0, static_cast<int>(std::floor((d.y - ext + margin_) * s)));
    const int b1 = std::min(tex_h_ - 1, static_cast<int>(std::ceil((d.y + ext + margin_) * s)));
    for (int b = b0; b <= b1; ++b) {
      const double y = b * inv_s - margin_;
      for (int a = a0; a <= a1; ++a) {
        const double x = a * inv_s - margin_;
        const auto alpha = static_cast<float>(coverage(d, x, y));
        if (alpha <= 0.0f) continue;
        float* t = &texture_[(static_cast<std::size_t>(b) * static_cast<std::size_t>(tex_w_) +
                              static_cast<std::size_t>(a)) *
                             3];
        for (int c = 0; c < 3; ++c) t[c] += alpha * (d.rgb[c] - t[c]);
      }
    }
  }
}

double Pattern::coverage(const Dot& d, double x, double y) const noexcept {
  const double dist = std::hypot(x - d.x, y - d.y) - d.r;
  const double e = spec_.edge_px;
  if (dist >= e) return 0.0;
  if (dist <= -e) return 1.0;
  const double u = 0.5 - 0.5 * dist / e;  // 1 inside .. 0 outside
  return u * u * (3.0 - 2.0 * u);
}

Eigen::Vector3d Pattern::eval(double x, double y) const noexcept {
  const double bg = spec_.background;
  Eigen::Vector3d out(bg, bg, bg);
  const int ci = static_cast<int>(std::floor((x - origin_) / spacing_px_));
  const int cj = static_cast<int>(std::floor((y - origin_) / spacing_px_));
  for (int j = std::max(0, cj - reach_); j <= std::min(cells_y_ - 1, cj + reach_); ++j) {
    for (int i = std::max(0, ci - reach_); i <= std::min(cells_x_ - 1, ci + reach_); ++i) {
      const Dot& d = dots_[static_cast<std::size_t>(j) * static_cast<std::size_t>(cells_x_) +
                           static_cast<std::size_t>(i)];
      if (!d.present) continue;
      const double alpha = coverage(d, x, y);
      if (alpha <= 0.0) continue;
      for (int c = 0; c < 3; ++c) out[c] += alpha * (static_cast<double>(d.rgb[c]) - out[c]);
    }
  }
  return out;
}

}  // namespace tacse3::sim
