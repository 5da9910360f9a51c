// SPDX-License-Identifier: Apache-2.0
// tacse3-bench-accuracy's goal arithmetic: the worst row per goal, the mean over objects, the
// worst over goal-bearing profiles and the --fail-above check.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "cases.hpp"
#include "report.hpp"
#include "tacse3/tools/bench.hpp"

namespace ba = tacse3::bench_accuracy;

namespace {

ba::Row row(const char* motion, double magnitude, double final_deg, double tracking_rms) {
  ba::Row r;
  r.c.motion = motion;
  r.c.magnitude = magnitude;
  r.configs.resize(1);
  r.results.resize(1);
  r.slot.dual_joint = 0;
  r.results[0].errors.final_rotation_error_deg = final_deg;
  r.results[0].tracking.valid = tracking_rms >= 0.0;
  r.results[0].tracking.rotation_rms_deg = tracking_rms;
  return r;
}

std::size_t goal_index(const char* prefix) {
  for (std::size_t k = 0; k < ba::kGoalCount; ++k) {
    if (std::string(ba::kGoals[k].what).rfind(prefix, 0) == 0) return k;
  }
  ADD_FAILURE() << prefix;
  return 0;
}

}  // namespace

TEST(BenchReport, GoalsTakeTheWorstRowAndTheObjectMean) {
  std::vector<ba::Row> rows;
  rows.push_back(row("rx", 30, 0.5, 2.0));
  rows.back().vb = true;
  rows.push_back(row("ry", 30, 1.25, 0.75));
  rows.back().vb = true;
  rows.push_back(row("rz", 90, 5.0, 4.0));
  rows.back().vb = true;
  for (double e : {1.0, 2.0, 6.0}) {
    rows.push_back(row("rz", 30, e, -1.0));
    rows.back().vd = true;
  }
  rows.push_back(row("rx", 60, 30.0, 30.0));  // capped: shown, not counted
  rows.back().vb = true;
  rows.back().carried = false;
  rows.push_back(row("tx", 0.4, 0.125, -1.0));
  rows.back().stick = true;
  const ba::GoalValues g = ba::measure_goals(rows);
  EXPECT_DOUBLE_EQ(g.v[goal_index("tracking RMS")], 4.0);
  EXPECT_DOUBLE_EQ(g.v[goal_index("final rotation error at 30")], 1.25);
  EXPECT_TRUE(std::isnan(g.v[goal_index("final rotation error at 60")]));
  EXPECT_DOUBLE_EQ(g.v[goal_index("final rotation error at 90")], 5.0);
  EXPECT_DOUBLE_EQ(g.v[goal_index("objects at 30 deg: mean")], 3.0);
  EXPECT_DOUBLE_EQ(g.v[goal_index("objects at 30 deg: worst")], 6.0);
  EXPECT_DOUBLE_EQ(g.v[goal_index("stick motions")], 0.125);
  EXPECT_TRUE(std::isnan(g.v[goal_index("translation error")]));
}

TEST(BenchReport, StressProfilesAreShownButNotJudged) {
  std::vector<ba::ProfileOutcome> p(3);
  p[0].name = "a";
  p[1].name = "b";
  p[2].name = "capped";
  p[2].stress = true;
  const std::size_t track = goal_index("tracking RMS");
  for (auto& x : p) x.goals.v.fill(ba::kNaN);
  p[0].goals.v[track] = 1.0;
  p[1].goals.v[track] = 4.0;   // 4.0 > 2 × 1.5
  p[2].goals.v[track] = 40.0;  // stress: no verdict
  std::vector<std::string> failed;
  const std::string m = ba::goal_matrix(p, 2.0, &failed);
  ASSERT_EQ(failed.size(), 1u);
  EXPECT_NE(failed[0].find("b: tracking RMS"), std::string::npos);
  EXPECT_NE(m.find("| 1.00 | 4.00 | 40.00 | 4.00 | **no** |"), std::string::npos) << m;
  failed.clear();
  ba::goal_matrix(p, 3.0, &failed);
  EXPECT_TRUE(failed.empty());
}

TEST(BenchReport, AProfileThatFailsToCalibrateFailsTheCheck) {
  std::vector<ba::ProfileOutcome> p(1);
  p[0].name = "a";
  p[0].error = "calibration failed";
  std::vector<std::string> failed;
  const std::string m = ba::goal_matrix(p, 0.0, &failed);
  ASSERT_EQ(failed.size(), 1u);
  EXPECT_NE(m.find("failed"), std::string::npos);
}

// `all` is the named profiles and three random sensors; a random sensor can also be named.
TEST(BenchReport, AllIsTheNamedProfilesAndThreeRandomSensors) {
  std::vector<std::string> list;
  ASSERT_EQ(tacse3::tools::parse_profile_list("all", &list), "");
  EXPECT_EQ(list,
            (std::vector<std::string>{"reference", "soft-thick", "stiff-thin", "coulomb-rim",
                                      "halfspace-mjpeg", "random:1", "random:2", "random:3"}));
  ASSERT_EQ(tacse3::tools::parse_profile_list("random,random:12,soft-thick", &list), "");
  EXPECT_EQ(list, (std::vector<std::string>{"random", "random:12", "soft-thick"}));
  EXPECT_NE(tacse3::tools::parse_profile_list("reference,random:x", &list).find("random:x"),
            std::string::npos);
}
