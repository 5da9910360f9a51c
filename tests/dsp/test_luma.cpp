// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: the luma conversion to the U8.2 working image with the 2x2 box and with the
// 4x4 binomial, all formats and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "support/synthetic.hpp"
#include "tacse3/dsp/luma.hpp"
#include "tacse3/dsp_ref/luma_ref.hpp"

namespace tacse3::dsp {
namespace {

using test::frame_view;

// A frame with a repeating 2x2 pattern: every working pixel sees the same four sensor pixels.
std::vector<std::uint8_t> tiled_rgb(const std::uint8_t (&px)[4][3]) {
  std::vector<std::uint8_t> f(3 * kSensorWidth * kSensorHeight);
  for (int y = 0; y < kSensorHeight; ++y) {
    for (int x = 0; x < kSensorWidth; ++x) {
      const int k = 2 * (y & 1) + (x & 1);
      for (int c = 0; c < 3; ++c)
        f[static_cast<std::size_t>(3 * (y * kSensorWidth + x) + c)] = px[k][c];
    }
  }
  return f;
}

// One texture for the whole executable (building its luma lattice takes ~0.2 s).
const test::DotTexture& texture() {
  static const test::DotTexture tex(11);
  return tex;
}

// The working pixel by its definition (luma.hpp): Q8 luma `q8(i, j)` of sensor pixel (i, j),
// weights [1 3 3 1] over 2x - 1 .. 2x + 2 and 2y - 1 .. 2y + 2 clamped to the frame, one rounding.
template <class Q8>
int filtered(int x, int y, Q8 q8) {
  constexpr int kW[4] = {1, 3, 3, 1};
  long s = 0;
  for (int j = 0; j < 4; ++j) {
    for (int i = 0; i < 4; ++i) {
      s += kW[i] * kW[j] *
           q8(std::clamp(2 * x - 1 + i, 0, kSensorWidth - 1),
              std::clamp(2 * y - 1 + j, 0, kSensorHeight - 1));
    }
  }
  return static_cast<int>((s + 2048) >> 12);
}

// A YUYV frame whose Y0 of macropixel m on row y is (3m + y) & 0xFF, its Y1 (m + 7y) & 0xFF, and
// whose chroma bytes are 0xFF and 0, which no working pixel may show.
std::vector<std::uint8_t> yuyv_ramps() {
  std::vector<std::uint8_t> f(2 * kSensorWidth * kSensorHeight);
  for (int y = 0; y < kSensorHeight; ++y) {
    for (int m = 0; m < kSensorWidth / 2; ++m) {
      std::uint8_t* p = f.data() + static_cast<std::size_t>(y * 2 * kSensorWidth + 4 * m);
      p[0] = static_cast<std::uint8_t>((3 * m + y) & 0xFF);  // Y0
      p[1] = 0xFF;                                           // U (ignored)
      p[2] = static_cast<std::uint8_t>((m + 7 * y) & 0xFF);  // Y1
      p[3] = 0x00;                                           // V (ignored)
    }
  }
  return f;
}

WorkImage sentinel_image() {
  WorkImage img;
  img.px.fill(0xBEEF);
  return img;
}

TEST(Luma, RgbHandComputedBlocks) {
  // R G B of the block's top-left, top-right, bottom-left, bottom-right pixels.
  {
    // Pure red: sum R = 1020 -> (77 * 1020 + 128) >> 8 = 78668 >> 8 = 307.
    const std::uint8_t px[4][3] = {{255, 0, 0}, {255, 0, 0}, {255, 0, 0}, {255, 0, 0}};
    const auto f = tiled_rgb(px);
    WorkImage out;
    ASSERT_EQ(frame_to_work_image(frame_view(f, PixelFormat::kRgb888), out), Status::kOk);
    EXPECT_EQ(out.at(0, 0), 307);
    EXPECT_EQ(out.at(159, 119), 307);
  }
  {
    // Pure green: (150 * 1020 + 128) >> 8 = 153128 >> 8 = 598.
    const std::uint8_t px[4][3] = {{0, 255, 0}, {0, 255, 0}, {0, 255, 0}, {0, 255, 0}};
    const auto f = tiled_rgb(px);
    WorkImage out;
    ASSERT_EQ(frame_to_work_image(frame_view(f, PixelFormat::kRgb888), out), Status::kOk);
    EXPECT_EQ(out.at(17, 42), 598);
  }
  {
    // Pure blue: (29 * 1020 + 128) >> 8 = 29708 >> 8 = 116.
    const std::uint8_t px[4][3] = {{0, 0, 255}, {0, 0, 255}, {0, 0, 255}, {0, 0, 255}};
    const auto f = tiled_rgb(px);
    WorkImage out;
    ASSERT_EQ(frame_to_work_image(frame_view(f, PixelFormat::kRgb888), out), Status::kOk);
    EXPECT_EQ(out.at(80, 60), 116);
  }
  {
    // Mixed: R = 10+20+30+40 = 100, G = 200+0+50+5 = 255, B = 1+2+3+4 = 10
    // -> (7700 + 38250 + 290 + 128) >> 8 = 46368 >> 8 = 181 (181.125).
    const std::uint8_t px[4][3] = {{10, 200, 1}, {20, 0, 2}, {30, 50, 3}, {40, 5, 4}};
    const auto f = tiled_rgb(px);
    WorkImage out;
    ASSERT_EQ(frame_to_work_image(frame_view(f, PixelFormat::kRgb888), out), Status::kOk);
    EXPECT_EQ(out.at(3, 5), 181);
    // White: 256 * 1020 / 256 = 1020, the top of U8.2.
    const std::uint8_t white[4][3] = {
        {255, 255, 255}, {255, 255, 255}, {255, 255, 255}, {255, 255, 255}};
    const auto fw = tiled_rgb(white);
    ASSERT_EQ(frame_to_work_image(frame_view(fw, PixelFormat::kRgb888), out), Status::kOk);
    EXPECT_EQ(out.at(0, 0), 1020);
  }
}

TEST(Luma, YuyvUsesOnlyLumaBytes) {
  // Y0 U Y1 V per macropixel; working pixel x takes Y0, Y1 of macropixel x on two rows.
  const std::vector<std::uint8_t> f = yuyv_ramps();
  WorkImage out;
  ASSERT_EQ(frame_to_work_image(frame_view(f, PixelFormat::kYuyv), out), Status::kOk);
  // Hand check at (x, y) = (5, 2): rows 4 and 5, macropixel 5:
  // Y0 = 15 + 4 = 19, Y1 = 5 + 28 = 33, Y0' = 15 + 5 = 20, Y1' = 5 + 35 = 40 -> 112.
  EXPECT_EQ(out.at(5, 2), 112);
  for (int y = 0; y < kWorkHeight; ++y) {
    for (int x = 0; x < kWorkWidth; ++x) {
      int expect = 0;
      for (int r = 2 * y; r <= 2 * y + 1; ++r)
        expect += ((3 * x + r) & 0xFF) + ((x + 7 * r) & 0xFF);
      ASSERT_EQ(out.at(x, y), expect) << x << "," << y;
    }
  }
}

TEST(Luma, GreyIsTheExactBlockSum) {
  std::vector<std::uint8_t> f(kSensorWidth * kSensorHeight);
  for (std::size_t i = 0; i < f.size(); ++i)
    f[i] = static_cast<std::uint8_t>((i * 37 + i / 320) & 0xFF);
  WorkImage out;
  ASSERT_EQ(frame_to_work_image(frame_view(f, PixelFormat::kGrey), out), Status::kOk);
  // Hand check at (0, 0): bytes 0, 1, 320, 321 -> 0, 37, (320*37+1)&255 = 65, (321*37+1)&255 = 102.
  EXPECT_EQ(out.at(0, 0), 0 + 37 + 65 + 102);
  for (int y = 0; y < kWorkHeight; ++y) {
    for (int x = 0; x < kWorkWidth; ++x) {
      const auto at = [&](int i, int j) {
        return f[static_cast<std::size_t>(j * kSensorWidth + i)];
      };
      ASSERT_EQ(out.at(x, y), at(2 * x, 2 * y) + at(2 * x + 1, 2 * y) + at(2 * x, 2 * y + 1) +
                                  at(2 * x + 1, 2 * y + 1));
    }
  }
}

// The fixed-point image against the double reference: only the single final rounding differs,
// so |error| <= 0.5 LSB everywhere and the SNR is that of uniform rounding noise on a ~500-LSB
// signal (> 60 dB).
void expect_rounding_of(const WorkImage& out, const std::vector<double>& ref) {
  ASSERT_EQ(ref.size(), static_cast<std::size_t>(kWorkPixels));
  double sig = 0, err = 0, max_err = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const double e = out.px[i] - ref[i];
    sig += ref[i] * ref[i];
    err += e * e;
    max_err = std::max(max_err, std::abs(e));
  }
  EXPECT_LE(max_err, 0.5);
  EXPECT_GE(10.0 * std::log10(sig / err), 60.0);
}

// Fixed point against the double reference on a textured colour frame (expect_rounding_of),
// and each pixel by its integer definition.
TEST(Luma, RgbAgreesWithDoubleReference) {
  const test::DotTexture& tex = texture();
  const auto f = test::render_frame(tex, test::Warp::identity(), PixelFormat::kRgb888);
  WorkImage out;
  ASSERT_EQ(frame_to_work_image(frame_view(f, PixelFormat::kRgb888), out), Status::kOk);
  const std::vector<double> ref =
      dsp_ref::frame_to_work_image_ref(frame_view(f, PixelFormat::kRgb888));
  expect_rounding_of(out, ref);
  for (int i = 0; i < kWorkPixels; ++i) {
    // Independent integer formula, per pixel.
    const int x = i % kWorkWidth, y = i / kWorkWidth;
    int sr = 0, sg = 0, sb = 0;
    for (int r = 2 * y; r <= 2 * y + 1; ++r) {
      for (int c = 2 * x; c <= 2 * x + 1; ++c) {
        const std::uint8_t* p = f.data() + static_cast<std::size_t>(3 * (r * kSensorWidth + c));
        sr += p[0];
        sg += p[1];
        sb += p[2];
      }
    }
    ASSERT_EQ(out.px[static_cast<std::size_t>(i)], (77 * sr + 150 * sg + 29 * sb + 128) >> 8);
  }
}

TEST(Luma, YuyvAndGreyAgreeWithDoubleReferenceExactly) {
  const test::DotTexture& tex = texture();
  for (const PixelFormat fmt : {PixelFormat::kYuyv, PixelFormat::kGrey}) {
    const auto f = test::render_frame(tex, test::Warp::shift(1.5, -0.5), fmt);
    WorkImage out;
    ASSERT_EQ(frame_to_work_image(frame_view(f, fmt), out), Status::kOk);
    const auto ref = dsp_ref::frame_to_work_image_ref(frame_view(f, fmt));
    ASSERT_EQ(ref.size(), static_cast<std::size_t>(kWorkPixels));
    for (int i = 0; i < kWorkPixels; ++i) {
      ASSERT_EQ(out.px[static_cast<std::size_t>(i)], ref[static_cast<std::size_t>(i)]);
    }
  }
}

TEST(Luma, SameSceneInGreyAndYuyvGivesTheSameImage) {
  const test::DotTexture& tex = texture();
  const auto g = test::render_frame(tex, test::Warp::identity(), PixelFormat::kGrey);
  const auto y = test::render_frame(tex, test::Warp::identity(), PixelFormat::kYuyv);
  WorkImage a, b;
  ASSERT_EQ(frame_to_work_image(frame_view(g, PixelFormat::kGrey), a), Status::kOk);
  ASSERT_EQ(frame_to_work_image(frame_view(y, PixelFormat::kYuyv), b), Status::kOk);
  EXPECT_EQ(a.px, b.px);
}

TEST(Luma, PaddedStrideMatchesPacked) {
  const test::DotTexture& tex = texture();
  for (const PixelFormat fmt : {PixelFormat::kRgb888, PixelFormat::kYuyv, PixelFormat::kGrey}) {
    const auto packed = test::render_frame(tex, test::Warp::identity(), fmt);
    const int row = packed_row_bytes(fmt);
    const int stride = row + 24;
    // Last row without padding: size_bytes = (h - 1) * stride + row is enough.
    std::vector<std::uint8_t> padded(static_cast<std::size_t>((kSensorHeight - 1) * stride + row),
                                     0xA5);
    for (int y = 0; y < kSensorHeight; ++y) {
      std::copy_n(packed.data() + static_cast<std::size_t>(y * row), row,
                  padded.data() + static_cast<std::size_t>(y * stride));
    }
    FrameView v = frame_view(padded, fmt);
    v.stride_bytes = stride;
    WorkImage a, b;
    ASSERT_EQ(frame_to_work_image(frame_view(packed, fmt), a), Status::kOk);
    ASSERT_EQ(frame_to_work_image(v, b), Status::kOk);
    EXPECT_EQ(a.px, b.px);
  }
}

TEST(Luma, EmptyAndSaturatedFrames) {
  for (const PixelFormat fmt : {PixelFormat::kRgb888, PixelFormat::kYuyv, PixelFormat::kGrey}) {
    WorkImage out;
    const auto dark = test::constant_frame(0, fmt);
    ASSERT_EQ(frame_to_work_image(frame_view(dark, fmt), out), Status::kOk);
    for (const auto v : out.px) ASSERT_EQ(v, 0);
    const auto bright = test::constant_frame(255, fmt);
    ASSERT_EQ(frame_to_work_image(frame_view(bright, fmt), out), Status::kOk);
    for (const auto v : out.px) ASSERT_EQ(v, 1020);
  }
}

TEST(LumaBinomial, YuyvUsesOnlyLumaBytes) {
  // Y0 U Y1 V per macropixel: pixel 2m is Y0 of macropixel m, pixel 2m + 1 its Y1.
  const std::vector<std::uint8_t> f = yuyv_ramps();
  WorkImage out;
  ASSERT_EQ(frame_to_work_image(frame_view(f, PixelFormat::kYuyv), out, WorkImageFilter::kBinomial),
            Status::kOk);
  const auto q8 = [](int i, int j) {
    const int m = i / 2;
    return 256 * ((i % 2 == 0 ? 3 * m + j : m + 7 * j) & 0xFF);
  };
  for (int y = 0; y < kWorkHeight; ++y) {
    for (int x = 0; x < kWorkWidth; ++x)
      ASSERT_EQ(out.at(x, y), filtered(x, y, q8)) << x << "," << y;
  }
}

// One bright sensor pixel at (2 x0, 2 y0) lands with the binomial's weights: 3 * 3 on working
// pixel (x0, y0), 3 * 1 on (x0 - 1, y0) and (x0, y0 - 1), 1 * 1 on (x0 - 1, y0 - 1), nothing
// on x0 + 1 or y0 + 1 (the 4x4 window of x0 + 1 starts at 2 x0 + 1). U8.2: 255 * w / 16.
TEST(LumaBinomial, AnImpulseSpreadsAsTheBinomial) {
  for (const PixelFormat fmt : {PixelFormat::kGrey, PixelFormat::kYuyv}) {
    auto f = test::constant_frame(0, fmt);
    const int x0 = 40, y0 = 30;
    const int bytes_per_px = fmt == PixelFormat::kGrey ? 1 : 2;
    f[static_cast<std::size_t>(bytes_per_px * (2 * y0 * kSensorWidth + 2 * x0))] = 255;
    WorkImage out;
    ASSERT_EQ(frame_to_work_image(frame_view(f, fmt), out, WorkImageFilter::kBinomial),
              Status::kOk);
    EXPECT_EQ(out.at(x0, y0), 143);         // 2295 / 16 = 143.44
    EXPECT_EQ(out.at(x0 - 1, y0), 48);      // 765 / 16 = 47.81
    EXPECT_EQ(out.at(x0, y0 - 1), 48);      //
    EXPECT_EQ(out.at(x0 - 1, y0 - 1), 16);  // 255 / 16 = 15.94
    EXPECT_EQ(out.at(x0 + 1, y0), 0);
    EXPECT_EQ(out.at(x0, y0 + 1), 0);
    int total = 0;
    for (const auto v : out.px) total += v;
    EXPECT_EQ(total, 143 + 2 * 48 + 16);
  }
}

TEST(LumaBinomial, GreyIsTheFilterOfItsBytes) {
  std::vector<std::uint8_t> f(kSensorWidth * kSensorHeight);
  for (std::size_t i = 0; i < f.size(); ++i)
    f[i] = static_cast<std::uint8_t>((i * 37 + i / 320) & 0xFF);
  WorkImage out;
  ASSERT_EQ(frame_to_work_image(frame_view(f, PixelFormat::kGrey), out, WorkImageFilter::kBinomial),
            Status::kOk);
  const auto q8 = [&](int i, int j) {
    return 256 * f[static_cast<std::size_t>(j * kSensorWidth + i)];
  };
  for (int y = 0; y < kWorkHeight; ++y) {
    for (int x = 0; x < kWorkWidth; ++x)
      ASSERT_EQ(out.at(x, y), filtered(x, y, q8)) << x << "," << y;
  }
}

// The same for the binomial.
TEST(LumaBinomial, RgbAgreesWithDoubleReference) {
  const test::DotTexture& tex = texture();
  const auto f = test::render_frame(tex, test::Warp::identity(), PixelFormat::kRgb888);
  WorkImage out;
  ASSERT_EQ(
      frame_to_work_image(frame_view(f, PixelFormat::kRgb888), out, WorkImageFilter::kBinomial),
      Status::kOk);
  const std::vector<double> ref = dsp_ref::frame_to_work_image_ref(
      frame_view(f, PixelFormat::kRgb888), WorkImageFilter::kBinomial);
  ASSERT_EQ(ref.size(), static_cast<std::size_t>(kWorkPixels));
  const auto q8 = [&](int i, int j) {
    const std::uint8_t* p = f.data() + static_cast<std::size_t>(3 * (j * kSensorWidth + i));
    return 77 * p[0] + 150 * p[1] + 29 * p[2];
  };
  expect_rounding_of(out, ref);
  for (int i = 0; i < kWorkPixels; ++i) {
    ASSERT_EQ(out.px[static_cast<std::size_t>(i)], filtered(i % kWorkWidth, i / kWorkWidth, q8));
  }
}

// GREY and YUYV: the same single rounding, |error| <= 0.5 LSB.
TEST(LumaBinomial, YuyvAndGreyAgreeWithDoubleReference) {
  const test::DotTexture& tex = texture();
  for (const PixelFormat fmt : {PixelFormat::kYuyv, PixelFormat::kGrey}) {
    const auto f = test::render_frame(tex, test::Warp::shift(1.5, -0.5), fmt);
    WorkImage out;
    ASSERT_EQ(frame_to_work_image(frame_view(f, fmt), out, WorkImageFilter::kBinomial),
              Status::kOk);
    const auto ref =
        dsp_ref::frame_to_work_image_ref(frame_view(f, fmt), WorkImageFilter::kBinomial);
    ASSERT_EQ(ref.size(), static_cast<std::size_t>(kWorkPixels));
    for (int i = 0; i < kWorkPixels; ++i) {
      ASSERT_LE(std::abs(out.px[static_cast<std::size_t>(i)] - ref[static_cast<std::size_t>(i)]),
                0.5)
          << i;
    }
  }
}

// A constant frame stays constant through the binomial, up to the clamped edge; the brightest
// frame is the top of U8.2.
TEST(LumaBinomial, EmptyAndSaturatedFrames) {
  for (const PixelFormat fmt : {PixelFormat::kRgb888, PixelFormat::kYuyv, PixelFormat::kGrey}) {
    WorkImage out;
    ASSERT_EQ(frame_to_work_image(frame_view(test::constant_frame(0, fmt), fmt), out,
                                  WorkImageFilter::kBinomial),
              Status::kOk);
    for (const auto v : out.px) ASSERT_EQ(v, 0);
    ASSERT_EQ(frame_to_work_image(frame_view(test::constant_frame(255, fmt), fmt), out,
                                  WorkImageFilter::kBinomial),
              Status::kOk);
    for (const auto v : out.px) ASSERT_EQ(v, 1020);
  }
}

TEST(Luma, BadInputIsRejectedAndOutputUntouched) {
  const auto grey = test::constant_frame(77, PixelFormat::kGrey);
  const WorkImage sentinel = sentinel_image();
  const auto expect_rejected = [&](const FrameView& v, Status want) {
    for (const WorkImageFilter filter : {WorkImageFilter::kBox, WorkImageFilter::kBinomial}) {
      WorkImage out = sentinel;
      EXPECT_EQ(frame_to_work_image(v, out, filter), want);
      EXPECT_EQ(out.px, sentinel.px);
    }
    EXPECT_EQ(check_frame(v), want);
  };
  FrameView v = frame_view(grey, PixelFormat::kGrey);
  {
    FrameView b = v;
    b.data = nullptr;
    expect_rejected(b, Status::kNullFrame);
  }
  {
    FrameView b = v;
    b.width = 640;
    expect_rejected(b, Status::kBadFrameSize);
    b.width = 319;
    expect_rejected(b, Status::kBadFrameSize);
    b = v;
    b.height = 480;
    expect_rejected(b, Status::kBadFrameSize);
    b.height = 0;
    expect_rejected(b, Status::kBadFrameSize);
  }
  {
    FrameView b = v;
    b.size_bytes -= 1;
    expect_rejected(b, Status::kBadFrameSize);
    b.size_bytes = 0;
    expect_rejected(b, Status::kBadFrameSize);
  }
  {
    FrameView b = v;
    b.stride_bytes = 319;
    expect_rejected(b, Status::kBadFrameSize);
    b.stride_bytes = -320;
    expect_rejected(b, Status::kBadFrameSize);
    b.stride_bytes = 400;  // valid stride, but the buffer is too small for it
    expect_rejected(b, Status::kBadFrameSize);
  }
  {
    FrameView b = v;
    b.format = static_cast<PixelFormat>(7);
    expect_rejected(b, Status::kBadPixelFormat);
  }
  {
    // A GREY-sized buffer declared as RGB888 or YUYV is too small.
    FrameView b = v;
    b.format = PixelFormat::kRgb888;
    expect_rejected(b, Status::kBadFrameSize);
    b.format = PixelFormat::kYuyv;
    expect_rejected(b, Status::kBadFrameSize);
  }
  EXPECT_TRUE(dsp_ref::frame_to_work_image_ref(FrameView{}).empty());
}

}  // namespace
}  // namespace tacse3::dsp
