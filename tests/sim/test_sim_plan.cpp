// SPDX-License-Identifier: Apache-2.0
// sim: the calibration plan's CSV as the simulated rig's scenarios.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "tacse3/sim/plan.hpp"

namespace {

namespace sim = tacse3::sim;

// tacse3-calibrate --plan --format csv, two of its lines.
const char* kPlan =
    "axis,magnitude,unit,regime,duration_s,pads_open_s,hold_s,determines\n"
    "rx,20,deg,slide,1,0.5,1,\"rotation_scale x, paper rotation_scale x; c_velocity\"\n"
    "tx,-0.5,mm,stick,0.5,0.05,0.2,\"pixel_pitch_m; \"\"quoted\"\"\"\n";

std::string parse_error(const std::string& text) {
  std::vector<sim::PlanMotion> p;
  std::string e;
  EXPECT_FALSE(sim::parse_plan(text, "p.csv", &p, &e));
  return e;
}

TEST(SimPlan, ParsesThePlanCsv) {
  std::vector<sim::PlanMotion> p;
  std::string e;
  ASSERT_TRUE(sim::parse_plan(kPlan, "p.csv", &p, &e)) << e;
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[0].axis, sim::MotionAxis::kRx);
  EXPECT_EQ(p[0].magnitude, 20.0);
  EXPECT_EQ(p[0].regime, sim::Regime::kSlide);
  EXPECT_EQ(p[0].duration_s, 1.0);
  EXPECT_EQ(p[0].pads_open_s, 0.5);
  EXPECT_EQ(p[0].hold_s, 1.0);
  EXPECT_EQ(p[1].axis, sim::MotionAxis::kTx);
  EXPECT_EQ(p[1].magnitude, -0.5);
  EXPECT_EQ(p[1].regime, sim::Regime::kStick);
  EXPECT_EQ(p[1].pads_open_s, 0.05);
  EXPECT_EQ(p[1].hold_s, 0.2);
}

TEST(SimPlan, ColumnsInAnyOrderAndCrLf) {
  std::vector<sim::PlanMotion> p;
  std::string e;
  ASSERT_TRUE(sim::parse_plan(
      "hold_s,pads_open_s,duration_s,regime,unit,magnitude,axis\r\n0.3,0.1,2,stick,deg,-3,rz\r\n",
      "p.csv", &p, &e))
      << e;
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p[0].axis, sim::MotionAxis::kRz);
  EXPECT_EQ(p[0].magnitude, -3.0);
  EXPECT_EQ(p[0].duration_s, 2.0);
  EXPECT_EQ(p[0].hold_s, 0.3);
}

TEST(SimPlan, TheScenarioPlaysTheLineFromRest) {
  sim::PlanMotion m;
  m.axis = sim::MotionAxis::kTy;
  m.magnitude = 10.0;
  m.regime = sim::Regime::kSlide;
  m.duration_s = 1.0;
  m.pads_open_s = 0.5;
  m.hold_s = 1.0;
  sim::ScenarioSpec base;
  base.loop = true;
  base.release_s = 0.3;
  const sim::Scenario s(sim::plan_scenario(m, base));
  EXPECT_EQ(s.phase(0.49), sim::Phase::kApproach);  // the pads are open for pads_open_s
  EXPECT_DOUBLE_EQ(s.motion_end_s() - s.motion_start_s(), 1.0);
  EXPECT_DOUBLE_EQ(s.duration_s() - s.motion_end_s(), 1.0);
  EXPECT_TRUE(s.sliding());
  EXPECT_FALSE(s.spec().loop);
  EXPECT_NEAR(s.pose(s.duration_s()).p.y(), 10.0, 1e-12);
}

TEST(SimPlan, BadInputNamesTheLineAndField) {
  EXPECT_EQ(parse_error(""),
            "p.csv: empty; it must be the CSV of tacse3-calibrate --plan --format csv");
  EXPECT_EQ(parse_error("axis,magnitude\nrx,1\n"),
            "p.csv line 1 (header): no column \"unit\"; the plan is the CSV of tacse3-calibrate "
            "--plan --format csv");
  const std::string h = "axis,magnitude,unit,regime,duration_s,pads_open_s,hold_s\n";
  EXPECT_EQ(parse_error(h), "p.csv: no motion after the header");
  EXPECT_EQ(parse_error(h + "rw,1,deg,stick,1,0.5,1\n"),
            "p.csv line 2: axis \"rw\": must be rx, ry, rz, tx or ty");
  EXPECT_EQ(parse_error(h + "rx,1,mm,stick,1,0.5,1\n"),
            "p.csv line 2: unit \"mm\": axis rx is in deg");
  EXPECT_EQ(parse_error(h + "rx,1,deg,roll,1,0.5,1\n"),
            "p.csv line 2: regime \"roll\": must be stick or slide");
  EXPECT_EQ(parse_error(h + "rx,1,deg,stick,1,0.5,1\nrx,x,deg,stick,1,0.5,1\n"),
            "p.csv line 3: magnitude \"x\": not a number");
  EXPECT_EQ(parse_error(h + "rx,1,deg,stick,0,0.5,1\n"), "p.csv line 2: duration_s 0: must be > 0");
  EXPECT_EQ(parse_error(h + "tx,80,mm,slide,1,0.5,1\n"),
            "p.csv line 2: the simulator cannot play this motion: motion magnitude must be within "
            "+-360 deg (rotations) or +-50 mm (translations)");
  EXPECT_EQ(parse_error(h + "rx,1,deg,stick,1,0.5,1,\"open\n"),
            "p.csv line 2: a quoted field does not end");
}

}  // namespace
