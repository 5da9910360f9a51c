// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the series of tacse3-replay --plot (replay_plot.hpp).
#include "tacse3/tools/replay_plot.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "tacse3/tools/metrics.hpp"

namespace tacse3::tools::plot {

namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::array<const char*, 3> kAxis{"x", "y", "z"};

// Rotation vector (deg) and position (mm) of a pose: the six plotted components.
std::array<double, 6> components(const dsp::Pose& p) {
  const Eigen::Vector3d r = dsp::so3_log(p.q) * kDeg;
  return {r.x(), r.y(), r.z(), p.p.x() * 1e3, p.p.y() * 1e3, p.p.z() * 1e3};
}

std::string heading(int c) {
  std::string h = c < 3 ? "rotation " : "translation ";
  h += kAxis[static_cast<std::size_t>(c % 3)];
  h += c < 3 ? " (deg)" : " (mm)";
  return h;
}

std::string lag_label(const char* what, double lag_s) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%s (lag %.0f ms)", what, lag_s * 1e3);
  return buf;
}

void add_error_panels(const SourceInfo& info, const std::vector<FrameResult>& frames,
                      const TrackingError& tracking, PlotData* d) {
  Series rot{lag_label("error", tracking.rotation_lag_s), Role::kError, {}};
  Series trans{lag_label("error", tracking.translation_lag_s), Role::kError, {}};
  const auto rot_lag = static_cast<std::int64_t>(std::llround(tracking.rotation_lag_s * 1e9));
  const auto trans_lag = static_cast<std::int64_t>(std::llround(tracking.translation_lag_s * 1e9));
  for (const FrameResult& f : frames) {
    if (!tracking.valid || f.t_ns < tracking.start_ns) {
      rot.y.push_back(kNaN);
      trans.y.push_back(kNaN);
      continue;
    }
    const dsp::Pose tr = truth_pose_at(info.truth, f.t_ns - rot_lag);
    const dsp::Pose tp = truth_pose_at(info.truth, f.t_ns - trans_lag);
    rot.y.push_back(rotation_error_deg(f.pose.q, tr.q));
    trans.y.push_back((f.pose.p - tp.p).norm() * 1e3);
  }
  d->panels.push_back(Panel{"rotation error (deg)", {std::move(rot)}, -1});
  d->panels.push_back(Panel{"translation error (mm)", {std::move(trans)}, -1});
}

// The panel's own series, or every series of its scale group.
std::vector<const std::vector<double>*> group_series(const PlotData& d, std::size_t i) {
  std::vector<const std::vector<double>*> ys;
  for (std::size_t j = 0; j < d.panels.size(); ++j) {
    const bool same = j == i || (d.panels[i].scale_group >= 0 &&
                                 d.panels[j].scale_group == d.panels[i].scale_group);
    if (!same) continue;
    for (const Series& s : d.panels[j].series) ys.push_back(&s.y);
  }
  return ys;
}

}  // namespace

std::vector<Range> panel_ranges(const PlotData& d) {
  std::vector<Range> out;
  for (std::size_t i = 0; i < d.panels.size(); ++i) {
    Range r = finite_range(group_series(d, i));
    if (r.hi - r.lo < kMinSpan) {
      const double mid = 0.5 * (r.lo + r.hi);
      const double lo = r.lo >= 0.0 ? std::max(0.0, mid - 0.5 * kMinSpan) : mid - 0.5 * kMinSpan;
      r = Range{lo, lo + kMinSpan};
    }
    out.push_back(r);
  }
  return out;
}

PlotData replay_plot_data(const SourceInfo& info, const std::vector<FrameResult>& frames,
                          const TrackingError& tracking) {
  PlotData d;
  const bool truth = info.has_truth();
  if (!truth) d.note = "no truth.csv: the estimate alone";
  std::array<Series, 6> est, tru;
  for (int c = 0; c < 6; ++c) {
    est[static_cast<std::size_t>(c)] = Series{"estimate", Role::kEstimate, {}};
    tru[static_cast<std::size_t>(c)] = Series{"truth", Role::kTruth, {}};
  }
  for (const FrameResult& f : frames) {
    d.t_s.push_back(static_cast<double>(f.t_ns - frames.front().t_ns) * 1e-9);
    const std::array<double, 6> e = components(f.pose);
    const std::array<double, 6> t =
        truth ? components(truth_pose_at(info.truth, f.t_ns)) : std::array<double, 6>{};
    for (std::size_t c = 0; c < 6; ++c) {
      est[c].y.push_back(e[c]);
      tru[c].y.push_back(t[c]);
    }
  }
  for (int c = 0; c < 6; ++c) {
    Panel p{heading(c), {}, c < 3 ? 0 : 1};
    if (truth) p.series.push_back(std::move(tru[static_cast<std::size_t>(c)]));
    p.series.push_back(std::move(est[static_cast<std::size_t>(c)]));
    d.panels.push_back(std::move(p));
  }
  if (truth) add_error_panels(info, frames, tracking, &d);
  return d;
}

}  // namespace tacse3::tools::plot
