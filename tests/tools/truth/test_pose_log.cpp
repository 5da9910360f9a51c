// SPDX-License-Identifier: Apache-2.0
// tacse3-truth: pose-log parsing, slerp interpolation and the frame composition, on analytic
// cases.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "tacse3/tools/truth/pose_log.hpp"
#include "tacse3/tools/truth/truth.hpp"

namespace {

namespace tr = tacse3::tools::truth;
constexpr double kPi = std::numbers::pi;

Eigen::Quaterniond about(const Eigen::Vector3d& axis, double angle) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
}

double angle_between(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return tr::rotation_angle(a.conjugate() * b);
}

TEST(PoseLog, QuaternionLogWithNanosecondsAndExtraColumns) {
  tr::PoseLog log;
  const std::string text =
      "t_ns, x,y,z,qw,qx,qy,qz,extra\n"
      "100,0.1,0.2,0.3,1,0,0,0,junk\n"
      "200,0.2,0.2,0.3,0.7071067811865476,0,0,0.7071067811865476,x\r\n";
  ASSERT_EQ(tr::parse_pose_log(text, "g.csv", &log), "");
  ASSERT_EQ(log.size(), 2u);
  EXPECT_EQ(log.rotation, tr::PoseLog::Rotation::kQuaternion);
  EXPECT_EQ(log.t_ns[1], 200);
  EXPECT_NEAR(angle_between(log.pose[1].q, about({0, 0, 1}, kPi / 2)), 0.0, 1e-12);
  // Half way: 45 deg about z (slerp), position half way.
  const tr::Pose mid = log.at(150);
  EXPECT_NEAR(angle_between(mid.q, about({0, 0, 1}, kPi / 4)), 0.0, 1e-12);
  EXPECT_NEAR(mid.p.x(), 0.15, 1e-15);
  EXPECT_TRUE(log.covers(100, 200));
  EXPECT_FALSE(log.covers(99, 200));
  EXPECT_FALSE(log.covers(100, 201));
}

TEST(PoseLog, SlerpFollowsAConstantRateRotationAtAnyFraction) {
  // Samples every 8 ms of a 40 deg/s rotation about (1, 2, 3): slerp is exact between them.
  const Eigen::Vector3d axis(1, 2, 3);
  std::string text = "t,x,y,z,qw,qx,qy,qz\n";
  char buf[200];
  for (int i = 0; i < 10; ++i) {
    const double t = 5.0 + 0.008 * i;
    const Eigen::Quaterniond q = about(axis, 40.0 * kPi / 180.0 * 0.008 * i);
    std::snprintf(buf, sizeof(buf), "%.3f,0,0,0,%.17g,%.17g,%.17g,%.17g\n", t, q.w(), q.x(), q.y(),
                  q.z());
    text += buf;
  }
  tr::PoseLog log;
  ASSERT_EQ(tr::parse_pose_log(text, "g.csv", &log), "");
  EXPECT_EQ(log.t_ns.front(), 5'000'000'000);
  for (const std::int64_t dt : {1'000'000, 3'500'000, 13'000'000, 70'999'000}) {
    const double expected = 40.0 * kPi / 180.0 * static_cast<double>(dt) * 1e-9;
    EXPECT_NEAR(angle_between(log.at(5'000'000'000 + dt).q, about(axis, expected)), 0.0, 1e-9)
        << dt;
  }
}

TEST(PoseLog, RotationVectorLog) {
  tr::PoseLog log;
  ASSERT_EQ(tr::parse_pose_log("t,x,y,z,rx,ry,rz\n0,0,0,0,0,0,0\n1,0,0,0,0,0,1.5707963267948966\n",
                               "ur.csv", &log),
            "");
  EXPECT_EQ(log.rotation, tr::PoseLog::Rotation::kRotationVector);
  const Eigen::Quaterniond& q = log.pose[1].q;
  EXPECT_NEAR(q.w(), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(q.z(), std::sqrt(0.5), 1e-15);
  // A rotation vector of length > pi (UR logs switch between r and its long twin) is the same
  // rotation: slerp through it takes the short arc.
  const Eigen::Vector3d r(0, 0, 0.9 * kPi);
  const Eigen::Vector3d twin = -r.normalized() * (2 * kPi - r.norm());
  EXPECT_NEAR(angle_between(tr::from_rotation_vector(r), tr::from_rotation_vector(twin)), 0.0,
              1e-12);
  EXPECT_NEAR(tr::from_rotation_vector(Eigen::Vector3d(1e-6, 0, 0)).x(), 5e-7, 1e-18);
}

std::string parse_error(const std::string& text) {
  tr::PoseLog log;
  return tr::parse_pose_log(text, "g.csv", &log);
}

TEST(PoseLog, BadInputIsNamed) {
  EXPECT_EQ(parse_error("t_ns,x,y,z,qw,qx,qy,qz\n1,0,0,0,1,0,0,0\n1,0,0,0,1,0,0,0\n"),
            "g.csv line 3: time 1 ns is not after the previous row's 1 ns: the log must be "
            "strictly increasing in time");
  EXPECT_EQ(parse_error("t_ns,x,y,z,qw,qx,qy,qz\n1,0,0,0,1,0,0,0\n2,0,0,0,0.5,0,0,0\n"),
            "g.csv line 3: quaternion is not unit (norm 0.500000)");
  EXPECT_NE(parse_error("t,t_ns,x,y,z,qw,qx,qy,qz\n").find("exactly one time column"),
            std::string::npos);
  EXPECT_NE(parse_error("t,x,y,qw,qx,qy,qz\n").find("no column `z`"), std::string::npos);
  EXPECT_NE(parse_error("t,x,y,z,qw,qx,qy,qz,rx,ry,rz\n").find("exactly one of the two"),
            std::string::npos);
  EXPECT_NE(parse_error("t,x,y,z,qw,qx,qy\n").find("exactly one of the two"), std::string::npos);
  EXPECT_EQ(parse_error("t,x,y,z,rx,ry,rz\n0,0,0,0,0,0,0\n\n1,0,0,0,0,0,0\n"),
            "g.csv line 3: blank line inside the log");
  EXPECT_EQ(parse_error("t,x,y,z,rx,ry,rz\n0,0,0,0,0,0\n"),
            "g.csv line 2: 6 fields, the header has 7");
  EXPECT_EQ(parse_error("t,x,y,z,rx,ry,rz\n0,0,0,nan,0,0,0\n"),
            "g.csv line 2: field 4 must be a finite number, got \"nan\"");
  EXPECT_EQ(parse_error("t_ns,x,y,z,rx,ry,rz\n0.5,0,0,0,0,0,0\n"),
            "g.csv line 2: `t_ns` must be an integer, got \"0.5\"");
  EXPECT_EQ(parse_error("t,x,y,z,rx,ry,rz\n0,0,0,0,0,0,0\n"),
            "g.csv: fewer than two poses; nothing to interpolate");
  EXPECT_EQ(parse_error(""), "g.csv: empty; a pose log starts with a header line");
}

TEST(PoseText, ParsesAndRejects) {
  tr::Pose p;
  ASSERT_EQ(tr::parse_pose_text("0.1 0 0.2 0.7071067811865476 0.7071067811865476 0 0", &p), "");
  EXPECT_NEAR(p.p.z(), 0.2, 1e-15);
  EXPECT_NEAR(angle_between(p.q, about({1, 0, 0}, kPi / 2)), 0.0, 1e-12);
  EXPECT_NE(tr::parse_pose_text("0 0 0 1 0 0", &p), "");
  EXPECT_NE(tr::parse_pose_text("0 0 0 1 0 0 0 0", &p), "");
  EXPECT_EQ(tr::parse_pose_text("0 0 0 2 0 0 0", &p), "quaternion is not unit (norm 2.000000)");
}

// A log of `pose(t)` sampled at the given times.
template <class F>
tr::PoseLog sampled(const std::vector<std::int64_t>& t, F pose) {
  tr::PoseLog log;
  log.name = "log.csv";
  for (const std::int64_t ti : t) {
    log.t_ns.push_back(ti);
    log.pose.push_back(pose(static_cast<double>(ti) * 1e-9));
  }
  return log;
}

TEST(Truth, GripperTurningAboutTheWorldZWithATcpOffset) {
  // The TCP turns about the world z at 1 rad/s, G is 0.1 m along the TCP's x: the still object
  // turns by -theta about G's z and its first-frame grasp point c0 moves to Rz(-theta) c0 - c0.
  std::vector<std::int64_t> t;
  for (int i = 0; i <= 100; ++i) t.push_back(i * 10'000'000);
  const tr::PoseLog g = sampled(t, [](double s) { return tr::Pose{about({0, 0, 1}, s), {}}; });
  tr::Rig rig;
  rig.gripper = &g;
  rig.tcp_to_grasp.p = Eigen::Vector3d(0.1, 0, 0);
  std::vector<tacse3::recording::TruthSample> rows;
  const std::vector<std::int64_t> frames = {0, 250'000'000, 500'000'000};
  ASSERT_EQ(tr::make_truth(rig, frames, 0, &rows), "");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].qw, 1.0);
  EXPECT_NEAR(rows[0].px, 0.0, 1e-15);
  const double th = 0.5;
  const Eigen::Quaterniond q(rows[2].qw, rows[2].qx, rows[2].qy, rows[2].qz);
  EXPECT_NEAR(angle_between(q, about({0, 0, 1}, -th)), 0.0, 1e-9);
  const Eigen::Vector3d c0(0.1, 0, 0);
  const Eigen::Vector3d p = about({0, 0, 1}, -th) * c0 - c0;
  EXPECT_NEAR(rows[2].px, p.x(), 1e-9);
  EXPECT_NEAR(rows[2].py, p.y(), 1e-9);
  EXPECT_NEAR(rows[2].pz, 0.0, 1e-12);
  // The clock offset reads the log later: 0.25 s of offset turns frame 0.25 s into theta 0.5.
  ASSERT_EQ(tr::make_truth(rig, {0, 250'000'000}, 250'000'000, &rows), "");
  EXPECT_NEAR(angle_between(Eigen::Quaterniond(rows[1].qw, rows[1].qx, rows[1].qy, rows[1].qz),
                            about({0, 0, 1}, -0.25)),
              0.0, 1e-9);
}

TEST(Truth, ObjectTurnedByAStageInFrontOfAStillGripper) {
  // G = Rz(90 deg) in the world: G's x is the world's y and G's y is the world's -x. The object
  // turns about the world x through G's origin, i.e. about -y in G, and its G origin stays.
  std::vector<std::int64_t> t;
  for (int i = 0; i <= 100; ++i) t.push_back(i * 10'000'000);
  const Eigen::Vector3d c(0.3, 0.2, 0.1);  // G's origin in the world
  const tr::PoseLog obj = sampled(t, [&](double s) {
    const Eigen::Quaterniond r = about({1, 0, 0}, 0.8 * s);
    return tr::Pose{r, c - r * c};  // rotation about the axis through c
  });
  tr::Rig rig;
  rig.object = &obj;
  rig.fixed_tcp = tr::Pose{about({0, 0, 1}, kPi / 2), c};
  std::vector<tacse3::recording::TruthSample> rows;
  ASSERT_EQ(tr::make_truth(rig, {100'000'000, 600'000'000}, 0, &rows), "");
  const Eigen::Quaterniond q(rows[1].qw, rows[1].qx, rows[1].qy, rows[1].qz);
  EXPECT_NEAR(angle_between(q, about({0, -1, 0}, 0.4)), 0.0, 1e-9);
  EXPECT_NEAR(Eigen::Vector3d(rows[1].px, rows[1].py, rows[1].pz).norm(), 0.0, 1e-12);
}

TEST(Truth, BothMoveTogetherMeansNoRelativeMotion) {
  std::vector<std::int64_t> t;
  for (int i = 0; i <= 20; ++i) t.push_back(i * 50'000'000);
  const auto moving = [](double s) {
    return tr::Pose{about({1, 1, 0}, s), Eigen::Vector3d(0.1 * s, 0.2, -s)};
  };
  const tr::PoseLog g = sampled(t, moving), o = sampled(t, moving);
  tr::Rig rig;
  rig.gripper = &g;
  rig.object = &o;
  std::vector<tacse3::recording::TruthSample> rows;
  ASSERT_EQ(tr::make_truth(rig, {0, 500'000'000, 1'000'000'000}, 0, &rows), "");
  for (const auto& r : rows) {
    EXPECT_NEAR(r.qw, 1.0, 1e-12);
    EXPECT_NEAR(Eigen::Vector3d(r.px, r.py, r.pz).norm(), 0.0, 1e-12);
  }
}

TEST(Truth, LogThatDoesNotCoverTheRecordingIsRefused) {
  const tr::PoseLog g = sampled({1'000'000'000, 2'000'000'000}, [](double) { return tr::Pose{}; });
  tr::Rig rig;
  rig.gripper = &g;
  std::vector<tacse3::recording::TruthSample> rows;
  const std::string e = tr::make_truth(rig, {0, 500'000'000}, 800'000'000, &rows);
  EXPECT_EQ(e,
            "log.csv: covers log time 1.000000 .. 2.000000 s, but the recording needs 0.800000 .. "
            "1.300000 s (frame times + clock offset); record the robot for the whole recording "
            "or check the clock offset");
  EXPECT_TRUE(rows.empty());
}

TEST(Truth, CsvHasTheDocumentedHeaderAndPrecision) {
  const std::string s = tr::truth_csv({{8333333, 1, 0, 0, 0, 0.001, 0, 0}});
  EXPECT_EQ(s,
            "t_ns,qw,qx,qy,qz,px,py,pz\n8333333,1.000000000000,0.000000000000,0.000000000000,"
            "0.000000000000,0.001000000000,0.000000000000,0.000000000000\n");
}

}  // namespace
