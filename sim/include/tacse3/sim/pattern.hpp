// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: the gel's random colour-dot pattern, as an analytic function and a band-limited
// texture.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace tacse3::sim {

struct PatternSpec {
  double dot_spacing_mm = 0.42;  // jittered-grid spacing of the dots
  double dot_radius_min_mm = 0.11;
  double dot_radius_max_mm = 0.19;
  double dot_jitter = 0.35;  // dot centre jitter, fraction of the spacing
  double dot_fill = 0.92;    // probability that a grid cell carries a dot
  double edge_px = 0.9;      // half-width of the blurred dot edge (optics), pixels
  double background = 0.5;   // grey gel reflectance (linear, 0..1)
  int supersample = 3;       // texels per pixel of the precomputed texture
  int margin_px = 48;        // texture margin around the image (largest displacement)
  bool grey_dots = false;    // dots printed in grey levels (each ink's luma) instead of colours
};

// Empty string if usable, else a message naming the field.
std::string validate(const PatternSpec& spec);

// The pattern lives on the gel surface. Coordinates are the image's pixel coordinates of the
// undeformed gel (pixel (i, j) is centred at (i, j)). eval() is the exact analytic pattern (each
// dot a disc with a smooth edge of half-width edge_px, composited in a fixed order over the grey
// background); the texture samples that same function every 1/supersample pixel, and sample()
// interpolates it bilinearly. Linear RGB reflectance in [0, 1].
class Pattern {
 public:
  Pattern() = default;
  // Allocates the dot list and the texture; everything else is allocation-free.
  void build(const PatternSpec& spec, double pixel_pitch_mm, int width, int height,
             std::uint64_t seed);

  Eigen::Vector3d eval(double x, double y) const noexcept;

  // Bilinear texture sample; coordinates outside the texture are clamped to its border.
  void sample(float x, float y, float* rgb) const noexcept {
    float fx = (x + static_cast<float>(margin_)) * scale_;
    float fy = (y + static_cast<float>(margin_)) * scale_;
    fx = fx < 0.0f ? 0.0f : (fx > max_x_ ? max_x_ : fx);
    fy = fy < 0.0f ? 0.0f : (fy > max_y_ ? max_y_ : fy);
    const int ix = static_cast<int>(fx);
    const int iy = static_cast<int>(fy);
    const float ax = fx - static_cast<float>(ix);
    const float ay = fy - static_cast<float>(iy);
    const float* p0 = &texture_[(static_cast<std::size_t>(iy) * tex_w_ + ix) * 3];
    const float* p1 = p0 + static_cast<std::size_t>(tex_w_) * 3;
    for (int c = 0; c < 3; ++c) {
      const float top = p0[c] + ax * (p0[c + 3] - p0[c]);
      const float bot = p1[c] + ax * (p1[c + 3] - p1[c]);
      rgb[c] = top + ay * (bot - top);
    }
  }

  int texture_width() const noexcept { return tex_w_; }
  int texture_height() const noexcept { return tex_h_; }
  std::size_t dot_count() const noexcept { return dots_.size(); }

 private:
  struct Dot {
    double x, y, r;  // pixels
    float rgb[3];
    bool present;
  };
  double coverage(const Dot& d, double x, double y) const noexcept;

  PatternSpec spec_;
  double spacing_px_ = 5.0;
  double origin_ = 0.0;  // pixel coordinate of dot cell (0, 0)'s corner
  int cells_x_ = 0, cells_y_ = 0, reach_ = 1;
  std::vector<Dot> dots_;  // one per cell, row-major; composited in this order
  std::vector<float> texture_;
  int tex_w_ = 0, tex_h_ = 0, margin_ = 0;
  float scale_ = 1.0f, max_x_ = 0.0f, max_y_ = 0.0f;
};

}  // namespace tacse3::sim
