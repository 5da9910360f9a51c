// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: pixel format codes, format negotiation choices and raw-buffer -> FrameView checks.
#include "tacse3/hal/camera/formats.hpp"

#include <algorithm>
#include <cstdio>

namespace tacse3::hal {

std::array<char, 12> fourcc_string(std::uint32_t fourcc) noexcept {
  std::array<char, 12> s{};
  bool printable = true;
  for (int i = 0; i < 4; ++i) {
    const auto c = static_cast<char>((fourcc >> (8 * i)) & 0xffu);
    if (c < 0x20 || c > 0x7e) printable = false;
    s[static_cast<std::size_t>(i)] = c;
  }
  if (!printable) std::snprintf(s.data(), s.size(), "0x%08x", fourcc);
  return s;
}

const char* to_string(dsp::PixelFormat format) noexcept {
  switch (format) {
    case dsp::PixelFormat::kRgb888:
      return "RGB888";
    case dsp::PixelFormat::kYuyv:
      return "YUYV";
    case dsp::PixelFormat::kGrey:
      return "GREY";
  }
  return "unknown";
}

bool interval_reaches_fps(FrameInterval interval, int fps) noexcept {
  if (!interval.known() || fps <= 0) return false;
  // num/den <= 1/fps * 1.005  <=>  num * fps * 1000 <= den * 1005
  const auto lhs =
      static_cast<std::uint64_t>(interval.num) * static_cast<std::uint64_t>(fps) * 1000u;
  const auto rhs = static_cast<std::uint64_t>(interval.den) * 1005u;
  return lhs <= rhs;
}

int v4l2_preference_rank(std::uint32_t fourcc, bool allow_mjpeg) noexcept {
  if (fourcc == v4l2_fourcc::kYuyv) return 0;
  if (fourcc == v4l2_fourcc::kRgb24) return 1;
  if (fourcc == v4l2_fourcc::kGrey) return 2;
  if (allow_mjpeg && fourcc == v4l2_fourcc::kMjpeg) return 3;
  if (allow_mjpeg && fourcc == v4l2_fourcc::kJpeg) return 4;
  return -1;
}

namespace {

// a is faster than b (shorter interval): a.num/a.den < b.num/b.den.
bool faster(FrameInterval a, FrameInterval b) noexcept {
  return static_cast<std::uint64_t>(a.num) * b.den < static_cast<std::uint64_t>(b.num) * a.den;
}

}  // namespace

V4l2FormatChoice choose_v4l2_format(const V4l2FormatOffer* offers, std::size_t count, int fps,
                                    bool allow_mjpeg, dsp::PixelFormat mjpeg_output) noexcept {
  // Tiers: 0 = reaches the rate, 1 = known but slower, 2 = rate unknown.
  int best_tier = 3;
  int best_rank = 0;
  std::size_t best = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const V4l2FormatOffer& o = offers[i];
    const int rank = v4l2_preference_rank(o.fourcc, allow_mjpeg);
    if (rank < 0 || !o.size_ok) continue;
    const int tier = interval_reaches_fps(o.fastest, fps) ? 0 : (o.fastest.known() ? 1 : 2);
    bool better = false;
    if (tier != best_tier) {
      better = tier < best_tier;
    } else if (tier == 1 && faster(o.fastest, offers[best].fastest)) {
      better = true;  // both too slow: the faster one wins
    } else if (tier == 1 && faster(offers[best].fastest, o.fastest)) {
      better = false;
    } else {
      better = rank < best_rank;
    }
    if (better) {
      best_tier = tier;
      best_rank = rank;
      best = i;
    }
  }
  V4l2FormatChoice c;
  if (best_tier == 3) return c;
  c.found = true;
  c.index = best;
  c.fourcc = offers[best].fourcc;
  c.meets_rate = best_tier == 0;
  c.mjpeg = c.fourcc == v4l2_fourcc::kMjpeg || c.fourcc == v4l2_fourcc::kJpeg;
  if (c.mjpeg) {
    c.output = mjpeg_output;
  } else if (c.fourcc == v4l2_fourcc::kYuyv) {
    c.output = dsp::PixelFormat::kYuyv;
  } else if (c.fourcc == v4l2_fourcc::kRgb24) {
    c.output = dsp::PixelFormat::kRgb888;
  } else {
    c.output = dsp::PixelFormat::kGrey;
  }
  return c;
}

LibcameraFormatChoice choose_libcamera_format(const std::uint32_t* fourccs,
                                              std::size_t count) noexcept {
  struct Pref {
    std::uint32_t fourcc;
    dsp::PixelFormat output;
    bool luma_only;
  };
  static constexpr Pref kPrefs[] = {
      {drm_fourcc::kYuyv, dsp::PixelFormat::kYuyv, false},
      {drm_fourcc::kBgr888, dsp::PixelFormat::kRgb888, false},
      {drm_fourcc::kR8, dsp::PixelFormat::kGrey, false},
      {drm_fourcc::kYuv420, dsp::PixelFormat::kGrey, true},
      {drm_fourcc::kNv12, dsp::PixelFormat::kGrey, true},
      {drm_fourcc::kYvu420, dsp::PixelFormat::kGrey, true},
      {drm_fourcc::kNv21, dsp::PixelFormat::kGrey, true},
  };
  LibcameraFormatChoice c;
  for (const Pref& p : kPrefs) {
    for (std::size_t i = 0; i < count; ++i) {
      if (fourccs[i] != p.fourcc) continue;
      c.found = true;
      c.index = i;
      c.fourcc = p.fourcc;
      c.output = p.output;
      c.luma_plane_only = p.luma_only;
      return c;
    }
  }
  return c;
}

int packed_row_bytes(dsp::PixelFormat format, int width) noexcept {
  switch (format) {
    case dsp::PixelFormat::kRgb888:
      return width * 3;
    case dsp::PixelFormat::kYuyv:
      return width * 2;
    case dsp::PixelFormat::kGrey:
      return width;
  }
  return 0;
}

CameraStatus make_frame_view(dsp::PixelFormat format, const std::uint8_t* data, std::size_t bytes,
                             int width, int height, int stride_bytes,
                             dsp::FrameView& out) noexcept {
  const int row = packed_row_bytes(format, width);
  if (row <= 0 || height <= 0 || (format == dsp::PixelFormat::kYuyv && width % 2 != 0)) {
    return CameraStatus::error(CameraError::kBadConfig, "invalid frame geometry %dx%d %s", width,
                               height, to_string(format));
  }
  if (data == nullptr) return CameraStatus::error(CameraError::kCorruptFrame, "null frame buffer");
  const int stride = stride_bytes == 0 ? row : stride_bytes;
  if (stride < row) {
    return CameraStatus::error(CameraError::kCorruptFrame,
                               "stride %d bytes is shorter than a %s row of %d pixels (%d bytes)",
                               stride, to_string(format), width, row);
  }
  const std::size_t need = static_cast<std::size_t>(stride) * static_cast<std::size_t>(height - 1) +
                           static_cast<std::size_t>(row);
  if (bytes < need) {
    return CameraStatus::error(CameraError::kCorruptFrame,
                               "short frame: %zu bytes, a %dx%d %s frame needs %zu", bytes, width,
                               height, to_string(format), need);
  }
  out.data = data;
  out.size_bytes = bytes;
  out.width = width;
  out.height = height;
  out.stride_bytes = stride;
  out.format = format;
  return CameraStatus::success();
}

CropPlan plan_centre_crop(dsp::PixelFormat format, int want_w, int want_h, int got_w, int got_h,
                          int stride_bytes) noexcept {
  CropPlan plan;
  if (want_w <= 0 || want_h <= 0 || got_w < want_w || got_h < want_h) return plan;
  if (got_w - want_w > kMaxCropPixels || got_h - want_h > kMaxCropPixels) return plan;
  if (format == dsp::PixelFormat::kYuyv && (want_w % 2 != 0 || got_w % 2 != 0)) return plan;
  const int row = packed_row_bytes(format, got_w);
  if (row <= 0) return plan;
  const int stride = stride_bytes == 0 ? row : stride_bytes;
  if (stride < row) return plan;
  plan.x0 = (got_w - want_w) / 2;
  plan.y0 = (got_h - want_h) / 2;
  if (format == dsp::PixelFormat::kYuyv) plan.x0 &= ~1;  // a Y0 U Y1 V macropixel is not split
  const int bytes_per_pixel = packed_row_bytes(format, 2) / 2;
  plan.byte_offset = static_cast<std::size_t>(plan.y0) * static_cast<std::size_t>(stride) +
                     static_cast<std::size_t>(plan.x0) * static_cast<std::size_t>(bytes_per_pixel);
  plan.ok = true;
  return plan;
}

PixelSize next_size_request(PixelSize want, PixelSize asked, PixelSize got) noexcept {
  PixelSize next = asked;
  if (got.width < want.width) next.width += std::max(1, want.width - got.width);
  if (got.height < want.height) next.height += std::max(1, want.height - got.height);
  return next;
}

}  // namespace tacse3::hal
