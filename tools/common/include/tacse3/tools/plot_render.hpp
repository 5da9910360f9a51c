// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: draws a PlotData (replay_plot.hpp) as an SVG or PNG figure with cairo (Debian's
// libcairo2, which writes both formats). Built only where cairo is found (TACSE3_HAVE_PLOT).
#pragma once

#include <string>

#include "tacse3/tools/plot_layout.hpp"
#include "tacse3/tools/replay_plot.hpp"

namespace tacse3::tools::plot {

// The colours of the series roles (0..255 RGB), shared with the tests that look for them.
struct Rgb {
  int r = 0, g = 0, b = 0;
};
inline constexpr Rgb kTruthColour{230, 159, 0};     // orange (Okabe-Ito)
inline constexpr Rgb kEstimateColour{0, 114, 178};  // blue
inline constexpr Rgb kErrorColour{213, 94, 0};      // vermillion
inline constexpr Rgb kNoteColour{180, 0, 0};        // PlotData::note, e.g. "no truth.csv"

// The figure (figure_layout(d.panels.size()) pixels or points) as the bytes of an SVG or PNG
// file in *out. False with *error set when cairo fails.
bool render(const PlotData& d, Format format, std::string* out, std::string* error);

// cairo and fontconfig keep the fonts they loaded in process-wide caches. A program calls this
// after its last render(), with no cairo object alive, so the sanitizer build's leak check finds
// them freed.
void release_static_data() noexcept;

}  // namespace tacse3::tools::plot
