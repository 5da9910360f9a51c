// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: the sim rig's plan mode: a motion per recording from rest, the robot's log and
// the simulator's truth beside the recording, and clear errors.
#include <gtest/gtest.h>
#include <time.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "tacse3/hal/camera/clock.hpp"
#include "tacse3/hal/camera/sim_camera.hpp"
#include "tacse3/sim/plan.hpp"
#include "tacse3/sim/scenario.hpp"

namespace {

namespace fs = std::filesystem;
namespace hal = tacse3::hal;
namespace sim = tacse3::sim;

const char* kHeader = "axis,magnitude,unit,regime,duration_s,pads_open_s,hold_s,determines\n";

class SimRigPlan : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tacse3_sim_rig_plan_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "rec-00001");
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write_plan(const std::string& lines) {
    const fs::path p = dir_ / "plan.csv";
    std::ofstream(p) << kHeader << lines;
    return p;
  }
  std::shared_ptr<hal::SimRig> make_rig(const fs::path& plan, std::string* err) {
    hal::SimRigConfig c;
    c.scene.plan = plan.string();
    c.scene.realtime = false;
    c.tcp_to_grasp = {0.01, -0.005, 0.16, 1, 0, 0, 0};
    return hal::SimRig::create(c, err);
  }
  fs::path dir_;
};

std::vector<std::string> lines_of(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

TEST_F(SimRigPlan, BadPlanNamesTheFile) {
  std::string err;
  EXPECT_FALSE(make_rig(dir_ / "none.csv", &err));
  EXPECT_EQ(err, "[sim] plan " + (dir_ / "none.csv").string() +
                     ": no such file; write it with tacse3-calibrate --plan --format csv");
  EXPECT_FALSE(
      make_rig(write_plan("rz,3,deg,stick,0.5,0.5,1,x\nrq,3,deg,stick,0.5,0.5,1,x\n"), &err));
  EXPECT_EQ(err, "[sim] plan " + (dir_ / "plan.csv").string() +
                     " line 3: axis \"rq\": must be rx, ry, rz, tx or ty");
  EXPECT_FALSE(make_rig(dir_, &err));
  EXPECT_NE(err.find("is a directory, not a file"), std::string::npos) << err;
}

TEST_F(SimRigPlan, PlaysOneMotionPerRecordingFromRest) {
  // A 3 deg torsion and a 0.5 mm stick translation, with short rests.
  std::string err;
  auto rig =
      make_rig(write_plan("rz,3,deg,stick,0.2,0.05,0.1,x\ntx,0.5,mm,stick,0.2,0.05,0.1,x\n"), &err);
  ASSERT_TRUE(rig) << err;
  ASSERT_EQ(rig->plan_size(), 2u);
  hal::SimCameraConfig lc, rc;
  lc.sensor = sim::Sensor::kLeft;
  lc.format = tacse3::dsp::PixelFormat::kGrey;
  rc = lc;
  rc.sensor = sim::Sensor::kRight;
  auto left = rig->make_camera(lc), right = rig->make_camera(rc);
  ASSERT_TRUE(left->open() && right->open() && left->start() && right->start());
  std::vector<std::int64_t> stamps;
  auto grab = [&](int n) {
    for (int i = 0; i < n; ++i) {
      hal::Frame fl, fr;
      ASSERT_TRUE(left->next_frame(fl, 1000).ok());
      ASSERT_TRUE(right->next_frame(fr, 1000).ok());
      ASSERT_EQ(fl.timestamp_ns, fr.timestamp_ns);
      stamps.push_back(fl.timestamp_ns);
      left->release(fl);
      right->release(fr);
    }
  };
  grab(10);  // at rest
  for (std::int64_t t : stamps)
    EXPECT_EQ(rig->truth(t).q.angularDistance(Eigen::Quaterniond::Identity()), 0.0);
  ASSERT_EQ(rig->next_motion_problem(), "");
  rig->start_motion(dir_ / "rec-00001");
  // pads open 0.05 s + grasp 0.4 + settle 0.1 + motion 0.2 + hold 0.1 = 0.85 s = 102 frames.
  grab(110);
  const std::int64_t last = stamps.back();
  EXPECT_NEAR(
      rig->truth(last).q.angularDistance(Eigen::Quaterniond::Identity()) * 180.0 / std::numbers::pi,
      3.0, 1e-9);
  ASSERT_EQ(rig->stop_motion(), "");
  grab(3);  // at rest again: the pads opened
  EXPECT_EQ(rig->truth(stamps.back()).q.angularDistance(Eigen::Quaterniond::Identity()), 0.0);

  // The simulator's truth: one row per frame from a second before the motion (here: from the first
  // frame) until the pads open; the
  // plan's motion started at one of the grabbed frames (after the start call).
  const auto truth = lines_of(dir_ / "rec-00001/robot/sim-truth.csv");
  ASSERT_GT(truth.size(), 110u);
  EXPECT_EQ(truth[0], "t_ns,qw,qx,qy,qz,px,py,pz");
  const sim::Scenario scn(sim::plan_scenario(
      sim::PlanMotion{sim::MotionAxis::kRz, 3.0, sim::Regime::kStick, 0.2, 0.05, 0.1},
      sim::ScenarioSpec{}));
  long long t_first_motion = 0;
  for (std::size_t i = 1; i < truth.size(); ++i) {
    long long t = 0;
    double qw = 0;
    ASSERT_EQ(std::sscanf(truth[i].c_str(), "%lld,%lf", &t, &qw), 2);
    if (qw < 1.0 && t_first_motion == 0) t_first_motion = t;
  }
  // The first row that has turned is the first frame after the motion starts: the grasp began
  // pads_open + grasp + settle before, at most three frames after the last rest frame grabbed.
  const double start_s = static_cast<double>(t_first_motion) * 1e-9 - scn.motion_start_s();
  const double after_rest = start_s - static_cast<double>(stamps[9]) * 1e-9;
  EXPECT_GT(after_rest, 0.0) << "the motion starts after the call, from rest";
  EXPECT_LE(after_rest, 4.0 / 120.0);

  // The robot's log: t_ns on CLOCK_REALTIME, 125 Hz, from 1 s before the motion to 0.2 s after
  // the pads opened.
  const auto arm = lines_of(dir_ / "rec-00001/robot/gripper.csv");
  EXPECT_EQ(arm[0], "t_ns,x,y,z,qw,qx,qy,qz");
  timespec r{}, m{};
  clock_gettime(CLOCK_REALTIME, &r);
  clock_gettime(CLOCK_MONOTONIC, &m);
  const double offset = (static_cast<double>(r.tv_sec) - static_cast<double>(m.tv_sec)) +
                        (static_cast<double>(r.tv_nsec) - static_cast<double>(m.tv_nsec)) * 1e-9;
  long long a0 = 0, a1 = 0;
  ASSERT_EQ(std::sscanf(arm[1].c_str(), "%lld", &a0), 1);
  ASSERT_EQ(std::sscanf(arm.back().c_str(), "%lld", &a1), 1);
  const double span = static_cast<double>(a1 - a0) * 1e-9;
  EXPECT_NEAR(static_cast<double>(arm.size() - 2) / span, 125.0, 1.0);
  EXPECT_NEAR(static_cast<double>(a0) * 1e-9 - offset, static_cast<double>(stamps[10]) * 1e-9 - 1.0,
              0.1);

  // The second motion, then the plan is over.
  rig->start_motion(dir_ / "rec-00002");
  fs::create_directories(dir_ / "rec-00002");
  grab(5);
  EXPECT_EQ(rig->stop_motion(), "");
  EXPECT_TRUE(fs::exists(dir_ / "rec-00002/robot/gripper.csv"));
  EXPECT_EQ(rig->next_motion_problem(), "every motion of the sim plan " +
                                            (dir_ / "plan.csv").string() +
                                            " was recorded (2); restart tacse3d to play it again");
  EXPECT_EQ(rig->stop_motion(), "no motion is playing");
}

TEST(SimRigNoPlan, IsNoRecordedMotion) {
  hal::SimRigConfig c;
  std::string err;
  auto rig = hal::SimRig::create(c, &err);
  ASSERT_TRUE(rig) << err;
  EXPECT_FALSE(rig->has_plan());
  EXPECT_EQ(rig->next_motion_problem(), "the sim rig has no [sim] plan");
}

}  // namespace
