// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: the --plot figure drawn with cairo (tools/plot_render.hpp): the SVG holds one
// stroke per series and legend sample in the role's colour, a truth and an estimate that are
// equal draw the same path, and the PNG decodes at the layout's size with the role colours in it.
#include <cairo.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "tacse3/tools/plot_render.hpp"

namespace tp = tacse3::tools::plot;

namespace {

// Two panels of a sine (truth and estimate, the estimate offset by `offset`) and an error panel.
tp::PlotData synthetic(double offset) {
  tp::PlotData d;
  d.title = "synthetic";
  tp::Series truth{"truth", tp::Role::kTruth, {}}, est{"estimate", tp::Role::kEstimate, {}};
  tp::Series err{"error", tp::Role::kError, {}};
  for (int i = 0; i <= 120; ++i) {
    d.t_s.push_back(i / 120.0);
    truth.y.push_back(std::sin(i / 20.0));
    est.y.push_back(std::sin(i / 20.0) + offset);
    err.y.push_back(i < 10 ? std::nan("") : std::abs(offset));
  }
  d.panels.push_back({"a (deg)", {truth, est}, 0});
  d.panels.push_back({"b (mm)", {truth, est}, -1});
  d.panels.push_back({"error (deg)", {err}, -1});
  return d;
}

std::string rgb_key(tp::Rgb c) {
  return std::to_string(c.r) + "," + std::to_string(c.g) + "," + std::to_string(c.b);
}

// The d attribute of every stroked path, by stroke colour ("r,g,b" in 0..255). cairo writes
// <path style="...;stroke:rgb(R%,G%,B%);..." d="..."/>. (No std::regex: GCC 12's -O1 sanitizer
// build warns inside it.)
std::map<std::string, std::vector<std::string>> strokes(const std::string& svg) {
  std::map<std::string, std::vector<std::string>> out;
  for (std::size_t at = svg.find("<path "); at != std::string::npos;
       at = svg.find("<path ", at + 1)) {
    const std::string tag = svg.substr(at, svg.find('>', at) - at);
    const std::size_t c = tag.find("stroke:rgb(");
    const std::size_t d = tag.find(" d=\"");
    if (c == std::string::npos || d == std::string::npos) continue;
    double pct[3] = {0, 0, 0};
    if (std::sscanf(tag.c_str() + c, "stroke:rgb(%lf%%,%lf%%,%lf%%)", &pct[0], &pct[1], &pct[2]) !=
        3) {
      continue;
    }
    const auto v = [&](int k) { return static_cast<int>(std::lround(pct[k] * 2.55)); };
    out[rgb_key({v(0), v(1), v(2)})].push_back(tag.substr(d + 4, tag.find('"', d + 4) - d - 4));
  }
  return out;
}

TEST(PlotRender, SvgSeriesAndLegendStrokes) {
  std::string svg, err;
  ASSERT_TRUE(tp::render(synthetic(0.3), tp::Format::kSvg, &svg, &err)) << err;
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("viewBox=\"0 0 900 " +
                     std::to_string(static_cast<int>(tp::figure_layout(3).height)) + "\""),
            std::string::npos);
  const auto s = strokes(svg);
  // Per panel: the series, then its legend sample.
  ASSERT_EQ(s.count(rgb_key(tp::kTruthColour)), 1u);
  EXPECT_EQ(s.at(rgb_key(tp::kTruthColour)).size(), 4u);
  EXPECT_EQ(s.at(rgb_key(tp::kEstimateColour)).size(), 4u);
  EXPECT_EQ(s.at(rgb_key(tp::kErrorColour)).size(), 2u);
  // Offset 0.3: the estimate's path is another path.
  EXPECT_NE(s.at(rgb_key(tp::kTruthColour))[0], s.at(rgb_key(tp::kEstimateColour))[0]);
}

TEST(PlotRender, EqualSeriesDrawTheSamePath) {
  std::string svg, err;
  ASSERT_TRUE(tp::render(synthetic(0.0), tp::Format::kSvg, &svg, &err)) << err;
  const auto s = strokes(svg);
  const auto& truth = s.at(rgb_key(tp::kTruthColour));
  const auto& est = s.at(rgb_key(tp::kEstimateColour));
  ASSERT_EQ(truth.size(), 4u);
  ASSERT_EQ(est.size(), 4u);
  for (std::size_t i = 0; i < 4; i += 2) {  // series strokes; 1 and 3 are legend samples
    EXPECT_GT(truth[i].size(), 1000u);      // 121 points
    EXPECT_EQ(truth[i], est[i]) << "panel " << i / 2;
  }
}

struct PngReader {
  const std::string* bytes;
  std::size_t at = 0;
};

cairo_status_t read_png(void* closure, unsigned char* data, unsigned int length) {
  auto* r = static_cast<PngReader*>(closure);
  if (r->at + length > r->bytes->size()) return CAIRO_STATUS_READ_ERROR;
  std::copy_n(r->bytes->data() + r->at, length, data);
  r->at += length;
  return CAIRO_STATUS_SUCCESS;
}

TEST(PlotRender, PngSizeAndColours) {
  std::string png, err;
  ASSERT_TRUE(tp::render(synthetic(0.3), tp::Format::kPng, &png, &err)) << err;
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  PngReader reader{&png};
  cairo_surface_t* img = cairo_image_surface_create_from_png_stream(read_png, &reader);
  ASSERT_EQ(cairo_surface_status(img), CAIRO_STATUS_SUCCESS);
  const tp::FigureLayout f = tp::figure_layout(3);
  EXPECT_EQ(cairo_image_surface_get_width(img), static_cast<int>(f.width));
  EXPECT_EQ(cairo_image_surface_get_height(img), static_cast<int>(f.height));
  std::map<std::string, int> count;
  int non_white = 0;
  const int w = cairo_image_surface_get_width(img), h = cairo_image_surface_get_height(img);
  const int stride = cairo_image_surface_get_stride(img);
  const unsigned char* px = cairo_image_surface_get_data(img);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      std::uint32_t v;
      std::memcpy(&v, px + y * stride + x * 4, 4);  // native-endian 0xAARRGGBB
      const tp::Rgb c{static_cast<int>((v >> 16) & 0xff), static_cast<int>((v >> 8) & 0xff),
                      static_cast<int>(v & 0xff)};
      ++count[rgb_key(c)];
      non_white += (v & 0xffffff) != 0xffffff;
    }
  }
  cairo_surface_destroy(img);
  // The truth band (3 px) and the legend samples (22 px on a pixel row) are drawn unblended.
  EXPECT_GT(count[rgb_key(tp::kTruthColour)], 200);
  EXPECT_GT(count[rgb_key(tp::kEstimateColour)], 40);
  EXPECT_GT(count[rgb_key(tp::kErrorColour)], 20);
  EXPECT_GT(non_white, w * h / 50);
}

// The fonts' caches freed once every test has drawn, for the sanitizer build's leak check.
class ReleaseCairo : public ::testing::Environment {
 public:
  void TearDown() override { tp::release_static_data(); }
};
const auto* const kReleaseCairo = ::testing::AddGlobalTestEnvironment(new ReleaseCairo);

}  // namespace
