// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the geometry of tacse3-replay's --plot figure (docs/replay.md): data ranges, tick
// choice, stacked panels and the data-to-pixel transform. Pure arithmetic, no drawing.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tacse3::tools::plot {

struct Range {
  double lo = 0.0;
  double hi = 1.0;
};

// The extent of the finite values of all `series` (NaN and ±inf skipped): {0, 1} with none.
Range finite_range(const std::vector<const std::vector<double>*>& series);

// Axis ticks: a step of 1, 2, 2.5 or 5 times a power of ten, the smallest that covers `r` with at
// most `max_ticks` ticks, starting and ending on whole steps (the axis is [first, last] tick). A
// flat range v..v is widened to v ± 0.1 |v| (± 1 for v = 0) first.
struct Ticks {
  double step = 1.0;
  std::vector<double> values;  // first .. last, step apart
  int decimals = 0;            // digits after the point that print every value exactly
  double lo() const noexcept { return values.front(); }
  double hi() const noexcept { return values.back(); }
};
Ticks nice_ticks(Range r, int max_ticks = 6);

// A tick label: `decimals` digits after the point, never "-0".
std::string tick_label(double v, int decimals);

// Linear map from data [d0, d1] to pixels [p0, p1] (p1 < p0 for a y axis pointing up).
struct LinearMap {
  double d0 = 0.0, d1 = 1.0, p0 = 0.0, p1 = 1.0;
  double operator()(double v) const noexcept { return p0 + (v - d0) * (p1 - p0) / (d1 - d0); }
};

struct Rect {
  double x = 0.0, y = 0.0, w = 0.0, h = 0.0;
};

// The figure: a title band, `panels` panels stacked with a heading gap between them, sharing one
// time axis whose labels sit under the last panel, and a legend column on the right.
struct FigureLayout {
  double width = 0.0, height = 0.0;
  std::vector<Rect> panels;  // top to bottom
  double legend_x = 0.0;     // left edge of the legend column
};
inline constexpr double kFigureWidth = 900.0;
inline constexpr double kPanelHeight = 110.0;
inline constexpr double kPanelGap = 24.0;    // room for the next panel's heading
inline constexpr double kTitleBand = 62.0;   // title and note lines, then the first heading
inline constexpr double kBottomBand = 46.0;  // time tick labels and the axis label
inline constexpr double kLeftMargin = 70.0;  // y tick labels
inline constexpr double kRightMargin = 170.0;
FigureLayout figure_layout(std::size_t panels);

enum class Format { kSvg, kPng };
// The figure format from a file name's extension (.svg or .png, any case); nothing otherwise.
std::optional<Format> format_from_path(std::string_view path);

}  // namespace tacse3::tools::plot
