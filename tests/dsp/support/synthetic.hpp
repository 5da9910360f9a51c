// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: analytic random-dot texture rendered under known warps into sensor frames.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "tacse3/dsp/types.hpp"

namespace tacse3::test {

using Vec2 = std::array<double, 2>;
using Rgb = std::array<double, 3>;

// Texture parameters. Coordinates are sensor pixels in the MATERIAL (undeformed) frame: the
// material point m is seen at sensor pixel m when nothing moves. Pixel (i, j) samples the
// continuous image at its centre (i, j).
struct DotTextureOptions {
  int dot_count = 2200;    // dots over the frame plus margin (~1 per 64 px^2)
  double min_sigma = 2.0;  // Gaussian dot radius range, sensor px (log-uniform)
  double max_sigma = 6.0;
  double margin = 48.0;       // texture extends this far beyond the frame on every side
  double background = 120.0;  // grey level of every channel
  double amplitude = 70.0;    // per-channel dot amplitude, uniform in [-a, a]
};

// Sum of coloured Gaussian dots on a grey background: a fixed continuous function of the
// material coordinates. Deterministic from the seed (own splitmix64 generator, identical on
// every platform).
//  - rgb() evaluates the sum exactly.
//  - luma() (used for GREY/YUYV frames) reconstructs the luma of the same sum from a lattice of
//    4 samples per sensor px with Catmull-Rom bicubic interpolation: ~20x faster, and still a
//    fixed C1-continuous function, so every warp's ground truth is exact. It differs from
//    luma_exact() by far less than one grey level.
class DotTexture {
 public:
  explicit DotTexture(std::uint64_t seed, const DotTextureOptions& options = {});
  Rgb rgb(double x, double y) const;  // unclamped channel values
  // Luma with the pipeline's integer BT.601 weights (77, 150, 29) / 256, unclamped.
  double luma(double x, double y) const;
  double luma_exact(double x, double y) const;

 private:
  struct Dot {
    double x, y, inv_two_sigma2, cutoff2;
    Rgb a;
    double luma_a;
  };
  template <typename F>
  void for_dots_near(double x, double y, F&& f) const;

  DotTextureOptions opt_;
  double x0_, y0_;  // bucket grid origin
  int bw_, bh_;     // bucket grid size
  std::vector<std::vector<Dot>> buckets_;
  int lw_, lh_;                 // luma lattice size
  std::vector<float> lattice_;  // luma at (x0 + i / 4, y0 + j / 4)
};

// A warp maps material points to image positions (forward) and back (inverse), sensor px.
struct Warp {
  std::function<Vec2(double, double)> forward;
  std::function<Vec2(double, double)> inverse;

  static Warp identity();
  static Warp shift(double dx, double dy);  // sensor px
  // x = c + A (m - c) + t with c the pad centre (159.5, 119.5); A = [a11 a12; a21 a22].
  static Warp affine(double a11, double a12, double a21, double a22, double tx, double ty);
  // x = m + u(m) for an arbitrary smooth displacement u (sensor px); the inverse is found by
  // fixed-point iteration m <- x - u(m) (needs |du/dm| < 1).
  static Warp displacement(std::function<Vec2(double, double)> u);
  // Displacement of grid point (gx, gy) in WORKING px (the block flow's unit).
  Vec2 grid_displacement_work(int gx, int gy) const;
};

// Photometric disturbances applied to every channel before 8-bit quantisation:
//   out = clamp(round(gain * v * vignette(x, y) + offset + noise)), noise ~ N(0, noise_sigma^2),
//   vignette = 1 - vignetting * r^2 / r_corner^2 about the pad centre.
struct Photometric {
  double gain = 1.0;
  double offset = 0.0;
  double noise_sigma = 0.0;
  std::uint64_t noise_seed = 1;
  double vignetting = 0.0;
};

// 320x240 frames, tightly packed, in the given format. YUYV carries the luma in Y and neutral
// chroma (128); GREY carries the luma.
std::vector<std::uint8_t> render_frame(const DotTexture& tex, const Warp& warp,
                                       dsp::PixelFormat format, const Photometric& ph = {});
dsp::FrameView frame_view(const std::vector<std::uint8_t>& bytes, dsp::PixelFormat format);
// GREY render followed by the pipeline's own luma stage.
dsp::WorkImage render_work_image(const DotTexture& tex, const Warp& warp,
                                 const Photometric& ph = {});

// A constant frame (e.g. 0 = dark, 255 = saturated) in the given format.
std::vector<std::uint8_t> constant_frame(std::uint8_t value, dsp::PixelFormat format);

}  // namespace tacse3::test
