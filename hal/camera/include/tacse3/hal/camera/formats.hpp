// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: pixel format codes, format negotiation choices and raw-buffer -> FrameView checks.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "tacse3/dsp/types.hpp"
#include "tacse3/hal/camera.hpp"

namespace tacse3::hal {

constexpr std::uint32_t make_fourcc(char a, char b, char c, char d) noexcept {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(a)) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(b)) << 8) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(c)) << 16) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(d)) << 24);
}

// V4L2 pixel formats (identical values to V4L2_PIX_FMT_*; checked against videodev2.h).
namespace v4l2_fourcc {
inline constexpr std::uint32_t kYuyv = make_fourcc('Y', 'U', 'Y', 'V');
inline constexpr std::uint32_t kRgb24 = make_fourcc('R', 'G', 'B', '3');  // bytes R G B
inline constexpr std::uint32_t kGrey = make_fourcc('G', 'R', 'E', 'Y');
inline constexpr std::uint32_t kMjpeg = make_fourcc('M', 'J', 'P', 'G');
inline constexpr std::uint32_t kJpeg = make_fourcc('J', 'P', 'E', 'G');
}  // namespace v4l2_fourcc

// libcamera (DRM) pixel formats. DRM names describe a little-endian word, so libcamera's BGR888
// is the one stored as bytes R G B.
namespace drm_fourcc {
inline constexpr std::uint32_t kYuyv = make_fourcc('Y', 'U', 'Y', 'V');
inline constexpr std::uint32_t kBgr888 = make_fourcc('B', 'G', '2', '4');  // bytes R G B
inline constexpr std::uint32_t kRgb888 = make_fourcc('R', 'G', '2', '4');  // bytes B G R
inline constexpr std::uint32_t kR8 = make_fourcc('R', '8', ' ', ' ');
inline constexpr std::uint32_t kYuv420 = make_fourcc('Y', 'U', '1', '2');
inline constexpr std::uint32_t kYvu420 = make_fourcc('Y', 'V', '1', '2');
inline constexpr std::uint32_t kNv12 = make_fourcc('N', 'V', '1', '2');
inline constexpr std::uint32_t kNv21 = make_fourcc('N', 'V', '2', '1');
}  // namespace drm_fourcc

// "YUYV", or "0x12345678" for codes that are not printable.
std::array<char, 12> fourcc_string(std::uint32_t fourcc) noexcept;

// Copies at most src_len bytes of src (up to its NUL) into a CameraInfo text field, truncated to
// fit and always NUL-terminated; the rest of the field is zeroed. For driver strings such as
// v4l2_capability::card, which need not be NUL-terminated.
template <std::size_t N>
void copy_text(std::array<char, N>& dst, const char* src, std::size_t src_len) noexcept {
  dst.fill('\0');
  for (std::size_t n = 0; n + 1 < N && n < src_len && src[n] != '\0'; ++n) dst[n] = src[n];
}
template <std::size_t N>
void copy_text(std::array<char, N>& dst, const char* src) noexcept {
  copy_text(dst, src, static_cast<std::size_t>(-1));
}

const char* to_string(dsp::PixelFormat format) noexcept;

// A frame interval in seconds, num / den (V4L2 struct v4l2_fract). 0/0 = unknown.
struct FrameInterval {
  std::uint32_t num = 0;
  std::uint32_t den = 0;
  bool known() const noexcept { return num != 0 && den != 0; }
};

// True when the interval is at most 1/fps (0.5 % slack: UVC rounds to 100 ns units).
bool interval_reaches_fps(FrameInterval interval, int fps) noexcept;

// One format a V4L2 device offers, summarised for the requested size.
struct V4l2FormatOffer {
  std::uint32_t fourcc = 0;
  bool size_ok = false;   // the requested width x height is offered (discrete or stepwise)
  FrameInterval fastest;  // shortest interval at that size (unknown if the driver won't say)
};

struct V4l2FormatChoice {
  bool found = false;
  std::size_t index = 0;  // into the offers
  std::uint32_t fourcc = 0;
  dsp::PixelFormat output = dsp::PixelFormat::kGrey;  // what frames will carry
  bool mjpeg = false;                                 // decoded by the backend
  bool meets_rate = false;                            // fastest interval reaches the requested fps
};

// Preference order of the raw formats the pipeline takes directly: YUYV, RGB24, GREY, then
// MJPEG/JPEG (decoded). Returns 0 for the best, larger for worse, -1 for unusable formats.
int v4l2_preference_rank(std::uint32_t fourcc, bool allow_mjpeg) noexcept;

// Negotiation: among the offers with the requested size, take the most preferred format that
// reaches the requested rate; if none does, the fastest known one (preference order on ties),
// and formats with an unknown rate last. So a UVC sensor whose YUYV tops out at 30 fps but whose
// MJPEG does 120 fps gets MJPEG.
V4l2FormatChoice choose_v4l2_format(const V4l2FormatOffer* offers, std::size_t count, int fps,
                                    bool allow_mjpeg, dsp::PixelFormat mjpeg_output) noexcept;

struct LibcameraFormatChoice {
  bool found = false;
  std::size_t index = 0;
  std::uint32_t fourcc = 0;
  dsp::PixelFormat output = dsp::PixelFormat::kGrey;
  bool luma_plane_only = false;  // planar YUV: the frame is its Y plane, seen as GREY
};

// libcamera stream formats in preference order: YUYV, BGR888 (bytes R G B), R8, then the
// planar/semi-planar YUV 4:2:0 formats whose first plane is a full-resolution GREY image.
LibcameraFormatChoice choose_libcamera_format(const std::uint32_t* fourccs,
                                              std::size_t count) noexcept;

// Centre crop of a larger delivered mode down to the configured size. Some pipelines cannot
// produce every size: libcamera 0.0.3's vimc handler proposes 318 for 320 and
// grants 324 for 322, and a
// CSI sensor may have a 328x246 binned mode and no 320x240 one. Cropping keeps the pixel pitch
// (a scaled mode would not), so the calibration stays valid; the pad centre stays the image
// centre. The crop is bounded so a wildly different mode (a smaller field of view the user did
// not ask for) is still refused.
inline constexpr int kMaxCropPixels = 32;  // per dimension, both sides together

struct CropPlan {
  bool ok = false;
  int x0 = 0;                   // first delivered column kept (even for YUYV: whole macropixels)
  int y0 = 0;                   // first delivered row kept
  std::size_t byte_offset = 0;  // of pixel (x0, y0) from the buffer start: y0 * stride + x0 * bpp
};

// The crop that takes `want_w` x `want_h` from the centre of a delivered `got_w` x `got_h` frame
// with rows of `stride_bytes`. !ok when the delivered mode is smaller than wanted in either
// dimension, exceeds it by more than kMaxCropPixels, or the geometry is invalid.
CropPlan plan_centre_crop(dsp::PixelFormat format, int want_w, int want_h, int got_w, int got_h,
                          int stride_bytes) noexcept;

// The next size to ask a pipeline for after it adjusted `asked` to `got`, so that the grant
// ends up at least `want`: each dimension that came back short grows by its shortfall (at least
// 1 px). Returns `asked` unchanged when `got` already covers `want`.
struct PixelSize {
  int width = 0;
  int height = 0;
};
PixelSize next_size_request(PixelSize want, PixelSize asked, PixelSize got) noexcept;

// Bytes in one tightly packed row of `format` at `width` (YUYV: width must be even).
int packed_row_bytes(dsp::PixelFormat format, int width) noexcept;

// Wraps a raw driver buffer as a FrameView after checking it holds a whole frame:
// stride >= packed row, bytes >= stride * (height - 1) + packed row. kCorruptFrame otherwise.
CameraStatus make_frame_view(dsp::PixelFormat format, const std::uint8_t* data, std::size_t bytes,
                             int width, int height, int stride_bytes, dsp::FrameView& out) noexcept;

}  // namespace tacse3::hal
