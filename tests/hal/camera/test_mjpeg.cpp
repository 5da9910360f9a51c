// SPDX-License-Identifier: Apache-2.0
// Tests for MJPEG decoding: JPEGs encoded here with libturbojpeg, decoded and compared pixelwise.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "tacse3/hal/camera/mjpeg_decoder.hpp"

#if TACSE3_HAL_HAS_TURBOJPEG
#include <turbojpeg.h>
#endif

namespace tacse3::hal {
namespace {

constexpr int kW = 320;
constexpr int kH = 240;

#if TACSE3_HAL_HAS_TURBOJPEG

// A smooth test scene (gradients + soft blobs), like a gel image: JPEG keeps it within a few
// levels at quality 90.
std::vector<std::uint8_t> make_rgb() {
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(kW * kH * 3));
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const double blob =
          80.0 * std::exp(-((x - 100.0) * (x - 100.0) + (y - 120.0) * (y - 120.0)) / 900.0);
      const double r = 40.0 + 0.5 * x + blob;
      const double g = 60.0 + 0.6 * y + 0.5 * blob;
      const double b = 200.0 - 0.3 * x - 0.2 * y;
      std::uint8_t* p = &rgb[static_cast<std::size_t>((y * kW + x) * 3)];
      p[0] = static_cast<std::uint8_t>(std::clamp(r, 0.0, 255.0));
      p[1] = static_cast<std::uint8_t>(std::clamp(g, 0.0, 255.0));
      p[2] = static_cast<std::uint8_t>(std::clamp(b, 0.0, 255.0));
    }
  }
  return rgb;
}

// BT.601 full-range luma, what JPEG's Y channel holds.
std::vector<std::uint8_t> luma_of(const std::vector<std::uint8_t>& rgb) {
  std::vector<std::uint8_t> y(static_cast<std::size_t>(kW * kH));
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double v = 0.299 * rgb[3 * i] + 0.587 * rgb[3 * i + 1] + 0.114 * rgb[3 * i + 2];
    y[i] = static_cast<std::uint8_t>(std::lround(v));
  }
  return y;
}

std::vector<std::uint8_t> encode(const std::vector<std::uint8_t>& rgb, int subsamp, int quality,
                                 int width = kW, int height = kH) {
  tjhandle h = tjInitCompress();
  unsigned char* out = nullptr;
  unsigned long size = 0;
  const int r = tjCompress2(h, rgb.data(), width, width * 3, height, TJPF_RGB, &out, &size, subsamp,
                            quality, 0);
  EXPECT_EQ(r, 0) << tjGetErrorStr2(h);
  std::vector<std::uint8_t> jpeg(out, out + size);
  tjFree(out);
  tjDestroy(h);
  return jpeg;
}

struct Diff {
  int max = 0;
  double mean = 0;
};

Diff compare(const std::uint8_t* a, const std::uint8_t* b, std::size_t n) {
  Diff d;
  double sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const int e = std::abs(static_cast<int>(a[i]) - static_cast<int>(b[i]));
    d.max = std::max(d.max, e);
    sum += e;
  }
  d.mean = sum / static_cast<double>(n);
  return d;
}

TEST(MjpegDecoder, DecodesToGreyLuma) {
  const auto rgb = make_rgb();
  const auto jpeg = encode(rgb, TJSAMP_422, 90);  // UVC MJPEG is 4:2:2
  MjpegDecoder dec;
  ASSERT_TRUE(dec.init(kW, kH, dsp::PixelFormat::kGrey).ok());
  EXPECT_EQ(dec.output_bytes(), static_cast<std::size_t>(kW * kH));
  std::vector<std::uint8_t> out(dec.output_bytes());
  dsp::FrameView v;
  const CameraStatus st = dec.decode(jpeg.data(), jpeg.size(), out.data(), out.size(), v);
  ASSERT_TRUE(st.ok()) << st.message();
  EXPECT_EQ(v.data, out.data());
  EXPECT_EQ(v.format, dsp::PixelFormat::kGrey);
  EXPECT_EQ(v.width, kW);
  EXPECT_EQ(v.height, kH);
  EXPECT_EQ(v.stride_bytes, kW);
  const Diff d = compare(out.data(), luma_of(rgb).data(), out.size());
  EXPECT_LE(d.max, 4);
  EXPECT_LE(d.mean, 0.5);
  std::printf("MJPEG q90 4:2:2 -> GREY vs reference luma: max |err| %d, mean %.3f\n", d.max,
              d.mean);
}

TEST(MjpegDecoder, DecodesToRgb) {
  const auto rgb = make_rgb();
  const auto jpeg = encode(rgb, TJSAMP_420, 95);
  MjpegDecoder dec;
  ASSERT_TRUE(dec.init(kW, kH, dsp::PixelFormat::kRgb888).ok());
  std::vector<std::uint8_t> out(dec.output_bytes());
  ASSERT_EQ(out.size(), rgb.size());
  dsp::FrameView v;
  ASSERT_TRUE(dec.decode(jpeg.data(), jpeg.size(), out.data(), out.size(), v).ok());
  EXPECT_EQ(v.format, dsp::PixelFormat::kRgb888);
  EXPECT_EQ(v.stride_bytes, kW * 3);
  const Diff d = compare(out.data(), rgb.data(), out.size());
  EXPECT_LE(d.max, 10);  // chroma subsampling at the blob's edge
  EXPECT_LE(d.mean, 1.0);
  std::printf("MJPEG q95 4:2:0 -> RGB888 vs source: max |err| %d, mean %.3f\n", d.max, d.mean);
  // One known pixel: the blob centre is reddish.
  const std::uint8_t* c = &out[static_cast<std::size_t>((120 * kW + 100) * 3)];
  EXPECT_GT(c[0], c[2]);
}

// UVC cameras send MJPEG without Huffman tables (DHT); the decoder must use the standard ones.
TEST(MjpegDecoder, DecodesMjpegWithoutHuffmanTables) {
  const auto rgb = make_rgb();
  const auto jpeg = encode(rgb, TJSAMP_422, 90);  // standard (non-optimised) tables
  std::vector<std::uint8_t> stripped;
  std::size_t i = 0;
  int removed = 0;
  while (i + 4 <= jpeg.size()) {
    if (jpeg[i] == 0xff && jpeg[i + 1] == 0xc4) {  // DHT segment
      const std::size_t len = (static_cast<std::size_t>(jpeg[i + 2]) << 8) | jpeg[i + 3];
      i += 2 + len;
      ++removed;
      continue;
    }
    if (jpeg[i] == 0xff && jpeg[i + 1] == 0xda) break;  // start of scan: copy the rest
    stripped.push_back(jpeg[i]);
    ++i;
  }
  stripped.insert(stripped.end(), jpeg.begin() + static_cast<std::ptrdiff_t>(i), jpeg.end());
  ASSERT_GT(removed, 0);
  MjpegDecoder dec;
  ASSERT_TRUE(dec.init(kW, kH, dsp::PixelFormat::kGrey).ok());
  std::vector<std::uint8_t> a(dec.output_bytes());
  std::vector<std::uint8_t> b(dec.output_bytes());
  dsp::FrameView v;
  ASSERT_TRUE(dec.decode(jpeg.data(), jpeg.size(), a.data(), a.size(), v).ok());
  const CameraStatus st = dec.decode(stripped.data(), stripped.size(), b.data(), b.size(), v);
  ASSERT_TRUE(st.ok()) << st.message();
  EXPECT_EQ(compare(a.data(), b.data(), a.size()).max, 0);
}

TEST(MjpegDecoder, RejectsWrongSizeGarbageAndSmallBuffers) {
  const std::vector<std::uint8_t> small_rgb(static_cast<std::size_t>(160 * 120 * 3), 128);
  const auto small = encode(small_rgb, TJSAMP_422, 90, 160, 120);
  MjpegDecoder dec;
  ASSERT_TRUE(dec.init(kW, kH, dsp::PixelFormat::kGrey).ok());
  std::vector<std::uint8_t> out(dec.output_bytes());
  dsp::FrameView v;
  CameraStatus st = dec.decode(small.data(), small.size(), out.data(), out.size(), v);
  EXPECT_EQ(st.code, CameraError::kCorruptFrame);
  EXPECT_NE(std::strstr(st.message(), "160x120"), nullptr) << st.message();

  std::vector<std::uint8_t> junk(5000, 0x55);
  EXPECT_EQ(dec.decode(junk.data(), junk.size(), out.data(), out.size(), v).code,
            CameraError::kCorruptFrame);
  junk[0] = 0xff;
  junk[1] = 0xd8;  // a start marker followed by garbage
  EXPECT_EQ(dec.decode(junk.data(), junk.size(), out.data(), out.size(), v).code,
            CameraError::kCorruptFrame);
  EXPECT_EQ(dec.decode(nullptr, 0, out.data(), out.size(), v).code, CameraError::kCorruptFrame);

  const auto good = encode(make_rgb(), TJSAMP_422, 90);
  EXPECT_EQ(dec.decode(good.data(), good.size(), out.data(), out.size() - 1, v).code,
            CameraError::kBadConfig);
  EXPECT_EQ(v.data, nullptr);
}

TEST(MjpegDecoder, TruncatedFrameNeverCrashes) {
  const auto jpeg = encode(make_rgb(), TJSAMP_422, 90);
  MjpegDecoder dec;
  ASSERT_TRUE(dec.init(kW, kH, dsp::PixelFormat::kGrey).ok());
  std::vector<std::uint8_t> out(dec.output_bytes());
  for (std::size_t cut : {jpeg.size() / 2, jpeg.size() - 10, std::size_t{700}, std::size_t{10}}) {
    dsp::FrameView v;
    const CameraStatus st = dec.decode(jpeg.data(), cut, out.data(), out.size(), v);
    // libjpeg reports a cut scan as a warning and fills the rest: delivered, and counted.
    if (st.ok()) {
      EXPECT_EQ(v.data, out.data());
    } else {
      EXPECT_EQ(st.code, CameraError::kCorruptFrame);
    }
  }
  EXPECT_GE(dec.warnings(), 1u);
}

TEST(MjpegDecoder, InitRejectsBadOutputs) {
  MjpegDecoder dec;
  EXPECT_EQ(dec.init(kW, kH, dsp::PixelFormat::kYuyv).code, CameraError::kBadConfig);
  EXPECT_EQ(dec.init(0, kH, dsp::PixelFormat::kGrey).code, CameraError::kBadConfig);
  dsp::FrameView v;
  std::uint8_t b[4] = {0xff, 0xd8, 0, 0};
  EXPECT_EQ(dec.decode(b, 4, b, 4, v).code, CameraError::kBadState);
}

// Measures decode time of a 320x240 4:2:2 MJPEG frame (reported, loosely bounded).
TEST(MjpegDecoder, DecodeTime) {
  const auto jpeg = encode(make_rgb(), TJSAMP_422, 90);
  for (dsp::PixelFormat fmt : {dsp::PixelFormat::kGrey, dsp::PixelFormat::kRgb888}) {
    MjpegDecoder dec;
    ASSERT_TRUE(dec.init(kW, kH, fmt).ok());
    std::vector<std::uint8_t> out(dec.output_bytes());
    dsp::FrameView v;
    constexpr int kN = 300;
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < kN; ++i)
      ASSERT_TRUE(dec.decode(jpeg.data(), jpeg.size(), out.data(), out.size(), v).ok());
    const double us =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() /
        kN;
    std::printf("MJPEG 320x240 4:2:2 (%zu bytes) -> %s: %.1f us/frame\n", jpeg.size(),
                fmt == dsp::PixelFormat::kGrey ? "GREY" : "RGB888", us);
#if !TACSE3_HAL_TEST_EMULATED
    EXPECT_LT(us, 8333.0);  // must fit well inside a 120 Hz frame period
#endif
  }
}

#else  // !TACSE3_HAL_HAS_TURBOJPEG

TEST(MjpegDecoder, ReportsUnavailableWithoutTurbojpeg) {
  MjpegDecoder dec;
  EXPECT_FALSE(MjpegDecoder::available());
  EXPECT_EQ(dec.init(kW, kH, dsp::PixelFormat::kGrey).code, CameraError::kUnavailable);
}

#endif

}  // namespace
}  // namespace tacse3::hal
