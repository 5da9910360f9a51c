// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: coarse-to-fine image pyramid used by the block flow.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// Level 0 is the 160x120 working image; level l has (160 >> l) x (120 >> l) pixels.
// Pixel centres follow the cell-centred convention: level-(l+1) pixel k covers level-l pixels
// 2k and 2k+1, so a level-0 coordinate x maps to (x + 0.5) / 2^l - 0.5 and a displacement
// scales by exactly 2^-l.
inline constexpr int kMaxPyramidLevels = 3;

constexpr int pyramid_width(int level) noexcept {
  return kWorkWidth >> level;
}
constexpr int pyramid_height(int level) noexcept {
  return kWorkHeight >> level;
}
// Each plane has one replicated padding column and row (x = width, y = height) so a bilinear
// read at the last valid position (weight 0 on the far neighbour) stays inside the buffer.
// Rows are padded to a multiple of 8 samples (16 bytes) for aligned row starts.
constexpr int pyramid_stride(int level) noexcept {
  return (pyramid_width(level) + 1 + 7) / 8 * 8;
}
constexpr std::size_t pyramid_plane_samples(int level) noexcept {
  return static_cast<std::size_t>(pyramid_stride(level)) *
         static_cast<std::size_t>(pyramid_height(level) + 1);
}
constexpr std::size_t pyramid_offset(int level) noexcept {
  std::size_t off = 0;
  for (int l = 0; l < level; ++l) off += pyramid_plane_samples(l);
  return off;
}
inline constexpr std::size_t kPyramidSamples = pyramid_offset(kMaxPyramidLevels);

template <typename T>
struct PyramidPlanes {
  alignas(16) std::array<T, kPyramidSamples> px{};

  T* level(int l) noexcept { return px.data() + pyramid_offset(l); }
  const T* level(int l) const noexcept { return px.data() + pyramid_offset(l); }
  T at(int l, int x, int y) const noexcept {
    return level(l)[static_cast<std::size_t>(y) * static_cast<std::size_t>(pyramid_stride(l)) +
                    static_cast<std::size_t>(x)];
  }
};

// Image planes, U8.2 (0..1020) at every level.
using ImagePyramid = PyramidPlanes<std::uint16_t>;

// Copies the working image into level 0 and builds levels 1..levels-1 by the separable
// [1 3 3 1]/8 binomial low-pass decimated by 2 (cell-centred; indices clamped at borders).
// `levels` is clamped to 1..kMaxPyramidLevels; higher planes are left as they are.
//
// Scaling and overflow: U8.2 in, U8.2 out. The vertical pass sums to at most 8 * 1020 = 8160,
// the 2D sum to at most 64 * 1020 = 65280 (uint32); out = (sum + 32) >> 6 (round half-up), so
// each level adds at most 0.5 LSB of rounding error to the one below; no saturation possible.
void build_pyramid(const WorkImage& in, int levels, ImagePyramid& out) noexcept;

// Builds levels 1..levels-1 of `pyr` from its level 0 (same kernel and scaling as above).
void extend_pyramid(ImagePyramid& pyr, int levels) noexcept;

}  // namespace tacse3::dsp
