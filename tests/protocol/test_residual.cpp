// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: the controller example's residual post-processor a_corr = a_base + Gamma theta.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "residual.hpp"
#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;
namespace ex = tacse3::example;
using PP = ex::ResidualPostProcessor<6>;

namespace {

tp::Quaternion about_z(double angle) {
  return {std::cos(angle / 2), 0, 0, std::sin(angle / 2)};
}

tp::Cycle cycle_at(int k, double angle, bool valid = true) {
  tp::Cycle c;
  c.timestamp_us = 1000000 + static_cast<std::uint64_t>(k) * 8333;
  c.estimate_valid = valid;
  c.orientation = about_z(angle);
  c.angular = {0.0, 0.0, 1.2};
  return c;
}

PP::Config counter_rotate(double gain) {
  PP::Config cfg;
  for (int i = 0; i < 3; ++i) cfg.gamma[3 + i][i] = -gain;
  return cfg;
}

}  // namespace

TEST(Residual, LogMapOfKnownRotations) {
  const tp::Vec3 a = ex::log_map(about_z(0.3));
  EXPECT_NEAR(a.z, 0.3, 1e-15);
  EXPECT_NEAR(a.x, 0.0, 1e-15);
  const tp::Vec3 b = ex::log_map({-std::cos(0.1), -std::sin(0.1), 0, 0});  // -q: same rotation
  EXPECT_NEAR(b.x, 0.2, 1e-14);
  const tp::Vec3 c = ex::log_map({1, 1e-12, 0, 0});
  EXPECT_NEAR(c.x, 2e-12, 1e-24);
}

TEST(Residual, IncrementalRotationAndCorrection) {
  PP post(counter_rotate(0.5));
  post.observe(cycle_at(0, 0.0));
  PP::Action base{0.001, 0.002, 0.0, 0.0, 0.0, 0.0};
  // Three cycles of 0.01 rad about z between two control steps.
  for (int k = 1; k <= 3; ++k) post.observe(cycle_at(k, 0.01 * k));
  tp::Vec3 theta;
  const PP::Action a = post.step(base, &theta);
  EXPECT_NEAR(theta.z, 0.03, 1e-12);
  EXPECT_NEAR(theta.x, 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(a[0], 0.001);
  EXPECT_DOUBLE_EQ(a[1], 0.002);
  EXPECT_NEAR(a[5], -0.5 * 0.03, 1e-12);
  // Nothing new: no correction.
  const PP::Action b = post.step(base, &theta);
  EXPECT_NEAR(theta.z, 0.0, 1e-15);
  EXPECT_NEAR(b[5], 0.0, 1e-15);
}

TEST(Residual, InvalidCyclesAndPoseResets) {
  PP post(counter_rotate(1.0));
  post.observe(cycle_at(0, 0.2));
  post.observe(cycle_at(1, 0.25));
  post.observe(cycle_at(2, 3.0, false));  // invalid estimate: ignored
  tp::Cycle nan = cycle_at(3, 0.0);
  nan.orientation.w = std::nan("");
  post.observe(nan);  // orientation not available: ignored
  // Tare: the pose restarts at identity; the jump 0.25 -> 0 is not a motion.
  tp::Cycle reset = cycle_at(4, 0.0);
  reset.pose_reset = true;
  post.observe(reset);
  post.observe(cycle_at(5, 0.02));
  tp::Vec3 theta;
  post.step(PP::Action{}, &theta);
  EXPECT_NEAR(theta.z, 0.05 + 0.02, 1e-12);
}

TEST(Residual, ClampsLargeSteps) {
  PP::Config cfg = counter_rotate(1.0);
  cfg.max_step_angle_rad = 0.1;
  PP post(cfg);
  post.observe(cycle_at(0, 0.0));
  post.observe(cycle_at(1, 0.5));
  tp::Vec3 theta;
  post.step(PP::Action{}, &theta);
  EXPECT_NEAR(theta.z, 0.1, 1e-12);
  EXPECT_EQ(post.clamped_steps(), 1u);
}

TEST(Residual, TwistSourceIntegratesOmega) {
  PP::Config cfg = counter_rotate(1.0);
  cfg.source = ex::ThetaSource::kTwist;
  PP post(cfg);
  for (int k = 0; k <= 12; ++k) post.observe(cycle_at(k, 0.0));
  tp::Vec3 theta;
  post.step(PP::Action{}, &theta);
  EXPECT_NEAR(theta.z, 1.2 * 12 * 0.008333, 1e-12);
}

// End to end: encoder -> candump text -> parser -> reassembler -> post-processor.
TEST(Residual, ThroughTheWire) {
  PP post(counter_rotate(1.0));
  tp::CycleReassembler reasm;
  double total = 0.0;
  for (int k = 0; k < 120; ++k) {
    tp::Cycle c = cycle_at(k, 0.004 * k);
    tp::CycleFrames frames;
    ASSERT_EQ(tp::encode_cycle(c, static_cast<std::uint8_t>(k), tp::TxConfig{}, frames),
              tp::Status::kOk);
    for (std::size_t i = 0; i < frames.count; ++i) {
      tp::LogRecord rec;
      rec.iface = {'c', 'a', 'n', '0'};
      rec.frame = frames.frames[i];
      char line[tp::kCandumpLineMax];
      ASSERT_GT(tp::format_candump_line(rec, line, sizeof line), 0u);
      tp::LogRecord back;
      ASSERT_EQ(tp::parse_candump_line(line, back), tp::Status::kOk);
      tp::Cycle out;
      if (reasm.feed(back.frame, out) == tp::CycleReassembler::Result::kComplete) {
        post.observe(out);
        tp::Vec3 theta;
        post.step(PP::Action{}, &theta);
        if (k > 0) {
          EXPECT_NEAR(theta.z, 0.004, 6e-4);  // one quaternion LSB is 2.5e-4
        }
        total += theta.z;
      }
    }
  }
  EXPECT_NEAR(total, 0.004 * 119, 6e-4);
}
