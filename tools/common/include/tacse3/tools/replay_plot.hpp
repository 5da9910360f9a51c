// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: what tacse3-replay --plot draws (docs/replay.md): the estimate against the truth
// per axis over time and the per-frame tracking error, as panels of series. No drawing here:
// plot_render.hpp draws a PlotData with cairo.
#pragma once

#include <string>
#include <vector>

#include "tacse3/tools/plot_layout.hpp"
#include "tacse3/tools/replay.hpp"

namespace tacse3::tools::plot {

enum class Role { kTruth, kEstimate, kError };

struct Series {
  std::string label;
  Role role = Role::kEstimate;
  std::vector<double> y;  // one per time of PlotData::t_s; NaN = no point there
};

struct Panel {
  std::string heading;  // quantity and unit, e.g. "rotation x (deg)"
  std::vector<Series> series;
  int scale_group = -1;  // panels of one group (>= 0) share their y range
};

struct PlotData {
  std::string title;
  std::string note;         // a second line, e.g. that there is no truth
  std::vector<double> t_s;  // seconds since the first frame
  std::vector<Panel> panels;
};

// The y range of each panel: its series' finite extent, the union over its scale group, widened
// about its middle to at least kMinSpan (from 0 up when that would take a range of values >= 0,
// such as an error, below 0).
std::vector<Range> panel_ranges(const PlotData& d);
// The smallest y span drawn (deg or mm): a still axis shows flat at this scale, not its rounding
// noise magnified to fill the panel; a tenth of the smallest tracking error the summary reports
// (0.1 deg, 0.1 mm in docs/replay.md's examples).
inline constexpr double kMinSpan = 0.01;

// Panels for a replay run: rotation x, y, z (deg; the rotation vector of the pose, so3_log) and
// translation x, y, z (mm), truth and estimate (the three rotation panels share one y scale, and
// the three translation panels another, so the axes compare at a glance); with truth, the rotation
// error (geodesic angle, deg) and translation error (mm) from the motion's start, each with the
// truth delayed by the lag `tracking` chose, so the curve is the one whose RMS the summary prints.
// Without truth the six estimate panels only, and `note` says so.
PlotData replay_plot_data(const SourceInfo& info, const std::vector<FrameResult>& frames,
                          const TrackingError& tracking);

}  // namespace tacse3::tools::plot
