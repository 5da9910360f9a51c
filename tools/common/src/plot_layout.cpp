// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the --plot figure's geometry (plot_layout.hpp).
#include "tacse3/tools/plot_layout.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>

namespace tacse3::tools::plot {

Range finite_range(const std::vector<const std::vector<double>*>& series) {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (const std::vector<double>* s : series) {
    for (const double v : *s) {
      if (!std::isfinite(v)) continue;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  if (lo > hi) return Range{};
  return Range{lo, hi};
}

namespace {

// m × 10^k, rounded once: dividing by an exact power of ten keeps 0.3 as the double nearest 0.3.
double scaled(double m, int k) {
  const double p = std::pow(10.0, std::abs(k));
  return k >= 0 ? m * p : m / p;
}

}  // namespace

Ticks nice_ticks(Range r, int max_ticks) {
  max_ticks = std::max(max_ticks, 2);
  if (!(r.hi > r.lo)) {
    const double m = r.lo != 0.0 ? 0.1 * std::abs(r.lo) : 1.0;
    r = Range{r.lo - m, r.lo + m};
  }
  const double span = r.hi - r.lo;
  constexpr std::array<double, 4> kMantissa{1.0, 2.0, 2.5, 5.0};
  int k = static_cast<int>(std::floor(std::log10(span / max_ticks))) - 1;
  for (;; ++k) {
    for (const double m : kMantissa) {
      const double step = scaled(m, k);
      // The tolerance keeps a bound that is a whole step (up to rounding) on that step.
      const double i0 = std::floor(r.lo / step + 1e-9);
      const double i1 = std::ceil(r.hi / step - 1e-9);
      if (i1 - i0 > max_ticks - 1) continue;
      Ticks t;
      t.step = step;
      for (double i = i0; i <= i1; i += 1.0) t.values.push_back(scaled(i * m, k));
      t.decimals = std::max(0, -k + (m == 2.5 ? 1 : 0));
      return t;
    }
  }
}

std::string tick_label(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, v);
  std::string s = buf;
  if (s.front() == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

FigureLayout figure_layout(std::size_t panels) {
  FigureLayout f;
  f.width = kFigureWidth;
  const double n = static_cast<double>(panels);
  f.height = kTitleBand + n * kPanelHeight + (n > 0 ? (n - 1.0) * kPanelGap : 0.0) + kBottomBand;
  const double w = kFigureWidth - kLeftMargin - kRightMargin;
  for (std::size_t i = 0; i < panels; ++i) {
    const double y = kTitleBand + static_cast<double>(i) * (kPanelHeight + kPanelGap);
    f.panels.push_back(Rect{kLeftMargin, y, w, kPanelHeight});
  }
  f.legend_x = kLeftMargin + w + 14.0;
  return f;
}

std::optional<Format> format_from_path(std::string_view path) {
  const std::size_t slash = path.find_last_of('/');
  const std::string_view name = slash == std::string_view::npos ? path : path.substr(slash + 1);
  const std::size_t dot = name.find_last_of('.');
  if (dot == std::string_view::npos || dot == 0) return std::nullopt;
  std::string ext(name.substr(dot + 1));
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == "svg") return Format::kSvg;
  if (ext == "png") return Format::kPng;
  return std::nullopt;
}

}  // namespace tacse3::tools::plot
