// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: binomial image pyramid ([1 3 3 1] / 8 low-pass, decimation by 2).
#include "tacse3/dsp/pyramid.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace tacse3::dsp {
namespace {

int clamp_levels(int levels) noexcept {
  return std::clamp(levels, 1, kMaxPyramidLevels);
}

// Replicates the last column into the padding column of every row and the last row into the
// padding row (including its padding column).
template <typename T>
void replicate_padding(T* plane, int level) noexcept {
  const int w = pyramid_width(level);
  const int h = pyramid_height(level);
  const std::size_t s = static_cast<std::size_t>(pyramid_stride(level));
  for (int y = 0; y < h; ++y) {
    T* row = plane + static_cast<std::size_t>(y) * s;
    row[w] = row[w - 1];
  }
  std::copy_n(plane + static_cast<std::size_t>(h - 1) * s, w + 1,
              plane + static_cast<std::size_t>(h) * s);
}

// Level l+1 from level l with the [1 3 3 1] / 8 kernel in each direction.
void downsample(const std::uint16_t* src, int src_level, std::uint16_t* dst) noexcept {
  const int sw = pyramid_width(src_level);
  const int sh = pyramid_height(src_level);
  const std::size_t ss = static_cast<std::size_t>(pyramid_stride(src_level));
  const int dw = pyramid_width(src_level + 1);
  const int dh = pyramid_height(src_level + 1);
  const std::size_t ds = static_cast<std::size_t>(pyramid_stride(src_level + 1));
  // Vertical sums with one clamped sample on each side: tmp[1 + x] = column x, x = -1..sw.
  std::array<std::uint16_t, kWorkWidth + 2> tmp{};
  for (int k = 0; k < dh; ++k) {
    const int y0 = std::max(2 * k - 1, 0);
    const int y3 = std::min(2 * k + 2, sh - 1);
    const std::uint16_t* r0 = src + static_cast<std::size_t>(y0) * ss;
    const std::uint16_t* r1 = src + static_cast<std::size_t>(2 * k) * ss;
    const std::uint16_t* r2 = src + static_cast<std::size_t>(2 * k + 1) * ss;
    const std::uint16_t* r3 = src + static_cast<std::size_t>(y3) * ss;
    for (int x = 0; x < sw; ++x) {
      tmp[static_cast<std::size_t>(x + 1)] =
          static_cast<std::uint16_t>(r0[x] + 3 * (r1[x] + r2[x]) + r3[x]);
    }
    tmp[0] = tmp[1];
    tmp[static_cast<std::size_t>(sw + 1)] = tmp[static_cast<std::size_t>(sw)];
    std::uint16_t* out = dst + static_cast<std::size_t>(k) * ds;
    for (int x = 0; x < dw; ++x) {
      const std::uint32_t sum = tmp[static_cast<std::size_t>(2 * x)] +
                                3u * (tmp[static_cast<std::size_t>(2 * x + 1)] +
                                      tmp[static_cast<std::size_t>(2 * x + 2)]) +
                                tmp[static_cast<std::size_t>(2 * x + 3)];
      out[x] = static_cast<std::uint16_t>((sum + 32u) >> 6);
    }
  }
}

}  // namespace

void build_pyramid(const WorkImage& in, int levels, ImagePyramid& out) noexcept {
  std::uint16_t* l0 = out.level(0);
  const std::size_t s0 = static_cast<std::size_t>(pyramid_stride(0));
  for (int y = 0; y < kWorkHeight; ++y) {
    std::copy_n(in.px.data() + static_cast<std::size_t>(y) * kWorkWidth, kWorkWidth,
                l0 + static_cast<std::size_t>(y) * s0);
  }
  replicate_padding(l0, 0);
  extend_pyramid(out, levels);
}

void extend_pyramid(ImagePyramid& pyr, int levels) noexcept {
  levels = clamp_levels(levels);
  for (int l = 1; l < levels; ++l) {
    downsample(pyr.level(l - 1), l - 1, pyr.level(l));
    replicate_padding(pyr.level(l), l);
  }
}

}  // namespace tacse3::dsp
