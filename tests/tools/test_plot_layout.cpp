// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: the geometry of tacse3-replay --plot (tools/plot_layout.hpp) and its series
// (tools/replay_plot.hpp), with exact values: tick choices for known ranges, pixels of known
// points, the shared scales, and the series of a run whose estimate is the truth.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "tacse3/tools/plot_layout.hpp"
#include "tacse3/tools/replay_plot.hpp"

namespace tp = tacse3::tools::plot;
namespace tt = tacse3::tools;

namespace {

using V = std::vector<double>;

TEST(PlotTicks, PicksTheSmallestStepWithinTheTickCount) {
  // Step 1 needs 11 ticks over [0, 9.3]; 2 covers it with 6 (0..10).
  tp::Ticks t = tp::nice_ticks({0.0, 9.3}, 6);
  EXPECT_EQ(t.step, 2.0);
  EXPECT_EQ(t.values, (V{0, 2, 4, 6, 8, 10}));
  EXPECT_EQ(t.decimals, 0);
  // 0.2 would need 9 ticks (-0.4..1.2), 0.25 eight (-0.5..1.25): 0.5 gives five.
  t = tp::nice_ticks({-0.37, 1.2}, 6);
  EXPECT_EQ(t.values, (V{-0.5, 0.0, 0.5, 1.0, 1.5}));
  EXPECT_EQ(t.decimals, 1);
  // The replay figure's time axis for a 1.175 s run: 0.1 would need 13 ticks.
  t = tp::nice_ticks({0.0, 1.175}, 10);
  EXPECT_EQ(t.values, (V{0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.2}));
  EXPECT_EQ(t.values[3], 0.6);  // the double nearest 0.6, not 3 × 0.2
  // A rotation error of at most 0.15 deg in five ticks: 0.025 needs seven.
  t = tp::nice_ticks({0.0, 0.15}, 5);
  EXPECT_EQ(t.values, (V{0.0, 0.05, 0.1, 0.15}));
  EXPECT_EQ(t.decimals, 2);
}

TEST(PlotTicks, TwoAndAHalfNegativeAndFlatRanges) {
  tp::Ticks t = tp::nice_ticks({0.0, 10.0}, 5);
  EXPECT_EQ(t.step, 2.5);
  EXPECT_EQ(t.values, (V{0.0, 2.5, 5.0, 7.5, 10.0}));
  EXPECT_EQ(t.decimals, 1);
  t = tp::nice_ticks({-7.2, -3.1}, 6);
  EXPECT_EQ(t.values, (V{-8, -7, -6, -5, -4, -3}));
  // Flat: 0 -> ±1, 50 -> ±5.
  t = tp::nice_ticks({0.0, 0.0}, 5);
  EXPECT_EQ(t.values, (V{-1.0, -0.5, 0.0, 0.5, 1.0}));
  t = tp::nice_ticks({50.0, 50.0}, 5);
  EXPECT_EQ(t.values, (V{45.0, 47.5, 50.0, 52.5, 55.0}));
  // Bounds already on a step stay the axis ends.
  t = tp::nice_ticks({-2.0, 4.0}, 4);
  EXPECT_EQ(t.values, (V{-2, 0, 2, 4}));
}

TEST(PlotTicks, Labels) {
  EXPECT_EQ(tp::tick_label(-0.0001, 2), "0.00");
  EXPECT_EQ(tp::tick_label(-0.5, 1), "-0.5");
  EXPECT_EQ(tp::tick_label(0.15, 2), "0.15");
  EXPECT_EQ(tp::tick_label(10.0, 0), "10");
}

TEST(PlotLayout, PanelsAndPixels) {
  const tp::FigureLayout f = tp::figure_layout(8);
  // 62 title + 8 × 110 panels + 7 × 24 gaps + 46 time axis.
  EXPECT_EQ(f.height, 1156.0);
  EXPECT_EQ(f.width, 900.0);
  ASSERT_EQ(f.panels.size(), 8u);
  EXPECT_EQ(f.panels[0].y, 62.0);
  EXPECT_EQ(f.panels[1].y, 196.0);
  EXPECT_EQ(f.panels[7].y + f.panels[7].h, 1110.0);
  EXPECT_EQ(f.panels[0].x, 70.0);
  EXPECT_EQ(f.panels[0].w, 660.0);
  EXPECT_EQ(f.legend_x, 744.0);
  // y of 2.5 on a [0, 10] axis in the first panel: 172 − 2.5 / 10 × 110.
  const tp::LinearMap ym{0.0, 10.0, 172.0, 62.0};
  EXPECT_EQ(ym(2.5), 144.5);
  EXPECT_EQ(ym(0.0), 172.0);
  EXPECT_EQ(ym(10.0), 62.0);
  // t = 0.5 s on the 0..1.2 s time axis: 70 + 0.5 / 1.2 × 660.
  const tp::LinearMap xm{0.0, 1.2, 70.0, 730.0};
  EXPECT_DOUBLE_EQ(xm(0.5), 345.0);
  EXPECT_EQ(xm(1.2), 730.0);
}

TEST(PlotLayout, FormatFromExtension) {
  EXPECT_EQ(tp::format_from_path("a/b.svg"), tp::Format::kSvg);
  EXPECT_EQ(tp::format_from_path("B.PNG"), tp::Format::kPng);
  EXPECT_FALSE(tp::format_from_path("a/b.pdf"));
  EXPECT_FALSE(tp::format_from_path("a/b"));
  EXPECT_FALSE(tp::format_from_path("a.svg/b"));
  EXPECT_FALSE(tp::format_from_path("a/.svg"));
  EXPECT_FALSE(tp::format_from_path(""));
}

TEST(PlotLayout, FiniteRangeSkipsNaN) {
  const V a{1.0, std::nan(""), -2.0}, b{HUGE_VAL, 5.0};
  const tp::Range r = tp::finite_range({&a, &b});
  EXPECT_EQ(r.lo, -2.0);
  EXPECT_EQ(r.hi, 5.0);
  const V none{std::nan("")};
  EXPECT_EQ(tp::finite_range({&none}).hi, 1.0);
}

TEST(PlotLayout, ScaleGroupsAndTheSmallestSpan) {
  tp::PlotData d;
  d.t_s = {0.0, 1.0};
  d.panels.push_back({"a", {{"s", tp::Role::kEstimate, {0.0, 4.0}}}, 0});
  d.panels.push_back({"b", {{"s", tp::Role::kEstimate, {-1.0, 0.0}}}, 0});
  d.panels.push_back({"c", {{"s", tp::Role::kEstimate, {2.0, 2.001}}}, -1});
  d.panels.push_back({"d", {{"s", tp::Role::kError, {0.001, 0.002}}}, -1});
  const std::vector<tp::Range> r = tp::panel_ranges(d);
  ASSERT_EQ(r.size(), 4u);
  EXPECT_EQ(r[0].lo, -1.0);  // a and b share -1..4
  EXPECT_EQ(r[1].hi, 4.0);
  EXPECT_DOUBLE_EQ(r[2].lo, 2.0005 - 0.5 * tp::kMinSpan);  // widened about its middle
  EXPECT_NEAR(r[2].hi - r[2].lo, tp::kMinSpan, 1e-12);
  EXPECT_EQ(r[3].lo, 0.0);  // an error range widens from 0 up
  EXPECT_EQ(r[3].hi, tp::kMinSpan);
}

// A run about z whose estimate equals the truth: 0 deg until 0.1 s, then 10 deg/s.
tt::SourceInfo ramp_info(int n, bool truth) {
  tt::SourceInfo info;
  for (int i = 0; i < n; ++i) {
    const std::int64_t t = 1000000000LL + i * 10000000LL;  // 100 Hz from t = 1 s
    info.t_ns.push_back(t);
    if (!truth) continue;
    const double a = std::max(0.0, 0.01 * i - 0.1) * 10.0 * std::numbers::pi / 180.0;
    const Eigen::Quaterniond q(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()));
    info.truth.push_back({t, q.w(), q.x(), q.y(), q.z(), 1e-3 * i, 0.0, 0.0});
  }
  return info;
}

std::vector<tt::FrameResult> frames_on_truth(const tt::SourceInfo& info) {
  std::vector<tt::FrameResult> frames;
  for (std::size_t i = 0; i < info.t_ns.size(); ++i) {
    tt::FrameResult f;
    f.t_ns = info.t_ns[i];
    if (info.has_truth()) f.pose = tt::to_pose(info.truth[i]);
    frames.push_back(f);
  }
  return frames;
}

TEST(ReplayPlotData, EstimateOnTheTruthCoincides) {
  const tt::SourceInfo info = ramp_info(61, true);
  const std::vector<tt::FrameResult> frames = frames_on_truth(info);
  std::vector<tacse3::dsp::Pose> poses;
  for (const auto& f : frames) poses.push_back(f.pose);
  const tt::TrackingError tr = tt::tracking_error(poses, info.truth, info.t_ns);
  const tp::PlotData d = tp::replay_plot_data(info, frames, tr);
  ASSERT_EQ(d.panels.size(), 8u);
  EXPECT_TRUE(d.note.empty());
  EXPECT_EQ(d.t_s.front(), 0.0);
  EXPECT_DOUBLE_EQ(d.t_s.back(), 0.6);
  EXPECT_EQ(d.panels[2].heading, "rotation z (deg)");
  for (int p = 0; p < 6; ++p) {
    const auto& s = d.panels[static_cast<std::size_t>(p)].series;
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(s[0].role, tp::Role::kTruth);
    EXPECT_EQ(s[1].role, tp::Role::kEstimate);
    EXPECT_EQ(s[0].y, s[1].y) << d.panels[static_cast<std::size_t>(p)].heading;
  }
  // Frame 60: 0.5 s of 10 deg/s about z, 60 mm along x.
  EXPECT_NEAR(d.panels[2].series[1].y.back(), 5.0, 1e-9);
  EXPECT_NEAR(d.panels[0].series[1].y.back(), 0.0, 1e-12);
  EXPECT_NEAR(d.panels[3].series[1].y.back(), 60.0, 1e-9);
  // The error panels: no point before the motion starts (frame 0 moves along x), 0 after.
  const auto& rot_err = d.panels[6].series[0].y;
  EXPECT_EQ(d.panels[6].series[0].role, tp::Role::kError);
  EXPECT_EQ(d.panels[6].series[0].label, "error (lag 0 ms)");
  EXPECT_TRUE(tr.valid);
  for (std::size_t i = 0; i < rot_err.size(); ++i) {
    if (info.t_ns[i] < tr.start_ns) {
      EXPECT_TRUE(std::isnan(rot_err[i])) << i;
    } else {
      EXPECT_NEAR(rot_err[i], 0.0, 1e-6) << i;
      EXPECT_NEAR(d.panels[7].series[0].y[i], 0.0, 1e-9) << i;
    }
  }
}

TEST(ReplayPlotData, WithoutTruthTheEstimateAlone) {
  const tt::SourceInfo info = ramp_info(5, false);
  const tp::PlotData d = tp::replay_plot_data(info, frames_on_truth(info), tt::TrackingError{});
  ASSERT_EQ(d.panels.size(), 6u);
  EXPECT_NE(d.note.find("no truth.csv"), std::string::npos);
  for (const auto& p : d.panels) {
    ASSERT_EQ(p.series.size(), 1u);
    EXPECT_EQ(p.series[0].role, tp::Role::kEstimate);
  }
}

}  // namespace
