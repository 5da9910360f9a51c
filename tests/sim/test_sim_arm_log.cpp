// SPDX-License-Identifier: Apache-2.0
// sim: the robot arm's TCP log (the object-clamped rig of docs/truth.md).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "tacse3/sim/arm_log.hpp"

namespace {

namespace sim = tacse3::sim;

struct Row {
  std::int64_t t_ns = 0;
  sim::RigidPose pose;
};

std::vector<Row> parse(const std::string& csv) {
  std::vector<Row> rows;
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t_ns,x,y,z,qw,qx,qy,qz");
  while (std::getline(in, line)) {
    Row r;
    long long t = 0;
    double v[7];
    EXPECT_EQ(std::sscanf(line.c_str(), "%lld,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &t, &v[0], &v[1], &v[2],
                          &v[3], &v[4], &v[5], &v[6]),
              8);
    r.t_ns = t;
    r.pose.p = Eigen::Vector3d(v[0], v[1], v[2]);
    r.pose.q = Eigen::Quaterniond(v[3], v[4], v[5], v[6]);
    rows.push_back(r);
  }
  return rows;
}

// A turn about G's z of 0.2 rad/s and a drift along x of 1 mm/s from board time 0.
sim::RigidPose truth(std::int64_t t) {
  const double s = static_cast<double>(t) * 1e-9;
  sim::RigidPose m;
  m.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.2 * s, Eigen::Vector3d::UnitZ()));
  m.p = Eigen::Vector3d(1e-3 * s, 0, 0);
  return m;
}

sim::RigidPose tcp_to_grasp() {
  sim::RigidPose g;
  g.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1, 0).normalized()));
  g.p = Eigen::Vector3d(0.01, -0.005, 0.16);
  return g;
}

constexpr std::int64_t kOffset = 1'764'000'000'123'456'789;  // a CLOCK_REALTIME-sized offset

TEST(SimArmLog, NoiselessLogIsTheTcpOfTheMovingGripper) {
  sim::ArmSpec spec;
  spec.jitter_ns = 0;
  spec.noise_mm = 0.0;
  spec.noise_deg = 0.0;
  sim::ArmLog arm(5, tcp_to_grasp(), spec);
  const auto rows =
      parse(arm.gripper_log(truth, 0, 1'000'000'000, kOffset, sim::ArmLogFormat::kQuaternionNs));
  ASSERT_EQ(rows.size(), 126u);  // 125 Hz over 1 s, both ends
  for (const Row& r : rows) {
    EXPECT_EQ((r.t_ns - kOffset) % 8'000'000, 0);
    // The pose of G in the world, from the log: T_w,tcp * T_tcp,G; relative to the first frame
    // it is the truth's inverse (the object is still, G moves).
    const sim::RigidPose wg = r.pose * arm.tcp_to_grasp();
    const sim::RigidPose rel = arm.world_to_grasp0().inverse() * wg;
    const sim::RigidPose want = truth(r.t_ns - kOffset).inverse();
    EXPECT_LT(rel.q.angularDistance(want.q), 1e-9);
    EXPECT_LT((rel.p - want.p).norm(), 1e-8);
  }
  // G starts 0.3-0.5 m in front of the robot.
  EXPECT_GT(arm.world_to_grasp0().p.x(), 0.3);
  EXPECT_LT(arm.world_to_grasp0().p.x(), 0.5);
}

TEST(SimArmLog, JitterAndNoiseHaveTheArmsSize) {
  sim::ArmLog arm(9, tcp_to_grasp());
  const auto rows =
      parse(arm.gripper_log(truth, 0, 40'000'000'000, kOffset, sim::ArmLogFormat::kQuaternionNs));
  ASSERT_GT(rows.size(), 4900u);
  double pos2 = 0, rot2 = 0;
  std::int64_t max_jitter = 0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const Row& r = rows[k];
    const std::int64_t j = r.t_ns - kOffset - static_cast<std::int64_t>(k) * 8'000'000;
    max_jitter = std::max(max_jitter, std::abs(j));
    const sim::RigidPose clean =
        arm.world_to_grasp0() * truth(r.t_ns - kOffset).inverse() * arm.tcp_to_grasp().inverse();
    pos2 += (r.pose.p - clean.p).squaredNorm();
    const double a = r.pose.q.angularDistance(clean.q);
    rot2 += a * a;
  }
  const double n = static_cast<double>(rows.size());
  EXPECT_LE(max_jitter, 1'000'000);
  EXPECT_GT(max_jitter, 900'000);
  // rms 0.05 mm and 0.01 deg: the sample rms of ~5000 rows lies within 3 % of it.
  EXPECT_NEAR(std::sqrt(pos2 / n) * 1e3, 0.05, 0.0015);
  EXPECT_NEAR(std::sqrt(rot2 / n) * 180.0 / std::numbers::pi, 0.01, 0.0003);
}

TEST(SimArmLog, SameSeedSameLog) {
  sim::ArmLog a(3, tcp_to_grasp()), b(3, tcp_to_grasp()), c(4, tcp_to_grasp());
  const std::string la = a.gripper_log(truth, 0, 1'000'000'000, 0, sim::ArmLogFormat::kQuaternion);
  EXPECT_EQ(la, b.gripper_log(truth, 0, 1'000'000'000, 0, sim::ArmLogFormat::kQuaternion));
  EXPECT_NE(la, c.gripper_log(truth, 0, 1'000'000'000, 0, sim::ArmLogFormat::kQuaternion));
  EXPECT_EQ(la.substr(0, la.find('\n')), "t,x,y,z,qw,qx,qy,qz");
}

}  // namespace
