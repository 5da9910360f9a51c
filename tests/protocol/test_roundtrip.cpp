// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: random round trips over the full range, invalid markers and saturation.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <variant>

#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Decode the cycle frames back through the reassembler (the controller's path).
tp::Cycle decode_cycle(const tp::CycleFrames& frames, const tp::Endpoint& ep) {
  tp::CycleReassembler r(ep);
  tp::Cycle out;
  tp::CycleReassembler::Result res = tp::CycleReassembler::Result::kIgnored;
  for (std::size_t i = 0; i < frames.count; ++i) res = r.feed(frames.frames[i], out);
  EXPECT_EQ(res, tp::CycleReassembler::Result::kComplete);
  return out;
}

void expect_same(double got, double want, double lsb) {
  if (std::isnan(want)) {
    EXPECT_TRUE(std::isnan(got));
  } else {
    EXPECT_NEAR(got, want, lsb * 1e-6);
  }
}

void expect_same_cycle(const tp::Cycle& got, const tp::Cycle& want) {
  EXPECT_EQ(got.timestamp_us, want.timestamp_us);
  EXPECT_EQ(got.counter, want.counter);
  EXPECT_EQ(got.estimate_valid, want.estimate_valid);
  EXPECT_EQ(got.single_sensor, want.single_sensor);
  EXPECT_EQ(got.pose_reset, want.pose_reset);
  EXPECT_EQ(got.saturated, want.saturated);
  expect_same(got.angular.x, want.angular.x, 0.001);
  expect_same(got.angular.y, want.angular.y, 0.001);
  expect_same(got.angular.z, want.angular.z, 0.001);
  expect_same(got.linear.x, want.linear.x, 0.0001);
  expect_same(got.linear.y, want.linear.y, 0.0001);
  expect_same(got.linear.z, want.linear.z, 0.0001);
  expect_same(got.position.x, want.position.x, 0.00002);
  expect_same(got.position.y, want.position.y, 0.00002);
  expect_same(got.position.z, want.position.z, 0.00002);
  expect_same(got.orientation.w, want.orientation.w, 0.00025);
  expect_same(got.orientation.x, want.orientation.x, 0.00025);
  expect_same(got.orientation.y, want.orientation.y, 0.00025);
  expect_same(got.orientation.z, want.orientation.z, 0.00025);
  EXPECT_EQ(got.angular_saturated.x, want.angular_saturated.x);
  EXPECT_EQ(got.linear_saturated.y, want.linear_saturated.y);
  EXPECT_EQ(got.position_saturated.z, want.position_saturated.z);
}

}  // namespace

TEST(Quantize, RoundsHalfAwayFromZeroAndSaturates) {
  const tp::SignalDef& w = tp::table::kTwistAngular[0];  // 0.001 rad/s, int16
  bool sat = false;
  EXPECT_EQ(tp::quantize(w, 0.0005, &sat), 1);
  EXPECT_EQ(tp::quantize(w, -0.0005, &sat), -1);
  EXPECT_EQ(tp::quantize(w, 0.00049, &sat), 0);
  EXPECT_EQ(tp::quantize(w, 32.767, &sat), 32767);
  EXPECT_FALSE(sat);
  EXPECT_EQ(tp::quantize(w, 32.768, &sat), 32767);  // rounds to 32768: out of range
  EXPECT_TRUE(sat);
  EXPECT_EQ(tp::quantize(w, -40.0, &sat), -32767);  // never the invalid marker -32768
  EXPECT_TRUE(sat);
  EXPECT_EQ(tp::quantize(w, kNaN, &sat), -32768);
  EXPECT_FALSE(sat);
  EXPECT_EQ(tp::quantize(w, kInf, &sat), -32768);
  EXPECT_EQ(tp::quantize(w, -kInf, &sat), -32768);
  EXPECT_TRUE(std::isnan(tp::dequantize(w, -32768)));
  EXPECT_DOUBLE_EQ(tp::dequantize(w, -32767), -32.767);

  const tp::SignalDef& conf = tp::table::kStatus[10];  // u8, 0.004, 0..250, 255 invalid
  EXPECT_EQ(tp::quantize(conf, 1.0, &sat), 250);
  EXPECT_EQ(tp::quantize(conf, 1.5, &sat), 250);
  EXPECT_TRUE(sat);
  EXPECT_EQ(tp::quantize(conf, -0.1, &sat), 0);
  EXPECT_TRUE(sat);
  EXPECT_EQ(tp::quantize(conf, kNaN, &sat), 255);
  EXPECT_TRUE(std::isnan(tp::dequantize(conf, 255)));
}

TEST(RoundTrip, RandomCyclesClassicAndFd) {
  std::mt19937_64 rng(0x7AC5E3);
  std::uniform_real_distribution<double> w(-32.767, 32.767);
  std::uniform_real_distribution<double> v(-3.2767, 3.2767);
  std::uniform_real_distribution<double> p(-0.65534, 0.65534);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<std::uint64_t> t(0, 0xFFFFFFFFFFFEull);
  std::bernoulli_distribution coin(0.5);
  for (int mode = 0; mode < 4; ++mode) {
    tp::TxConfig tx;
    tx.endpoint.node_id = static_cast<std::uint8_t>(1 + mode * 20);
    tx.frame_mode = (mode & 1) != 0 ? tp::FrameMode::kFd : tp::FrameMode::kClassic;
    tx.endpoint.layout.mode = (mode & 2) != 0 ? tp::IdMode::kExtended : tp::IdMode::kStandard;
    for (int i = 0; i < 500; ++i) {
      tp::Cycle c;
      c.timestamp_us = t(rng);
      c.estimate_valid = coin(rng);
      c.single_sensor = coin(rng);
      c.pose_reset = coin(rng);
      c.angular = {w(rng), w(rng), w(rng)};
      c.linear = {v(rng), v(rng), v(rng)};
      c.position = {p(rng), p(rng), p(rng)};
      c.orientation = {unit(rng), unit(rng), unit(rng), unit(rng)};
      tp::CycleFrames f;
      ASSERT_EQ(tp::encode_cycle(c, static_cast<std::uint8_t>(i), tx, f), tp::Status::kOk);
      EXPECT_FALSE(f.sent.saturated);
      // The receiver sees exactly what the encoder reports as sent ...
      expect_same_cycle(decode_cycle(f, tx.endpoint), f.sent);
      // ... which is the input to within half an LSB.
      EXPECT_NEAR(f.sent.angular.x, c.angular.x, 0.0005 + 1e-12);
      EXPECT_NEAR(f.sent.linear.y, c.linear.y, 0.00005 + 1e-12);
      EXPECT_NEAR(f.sent.position.z, c.position.z, 0.00001 + 1e-12);
      EXPECT_EQ(f.sent.timestamp_us, c.timestamp_us);
      // The quaternion is normalised and sent with w >= 0.
      const tp::Quaternion& q = c.orientation;
      const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
      if (n >= 0.5 && n <= 2.0) {
        const double s = (q.w < 0 ? -1.0 : 1.0) / n;
        EXPECT_NEAR(f.sent.orientation.w, q.w * s, 0.000125 + 1e-12);
        EXPECT_NEAR(f.sent.orientation.z, q.z * s, 0.000125 + 1e-12);
        EXPECT_GE(f.sent.orientation.w, 0.0);
      } else {
        EXPECT_TRUE(std::isnan(f.sent.orientation.w));
      }
    }
  }
}

TEST(RoundTrip, InvalidMarkersAndSaturation) {
  tp::Cycle c;
  c.timestamp_us = tp::kTimestampInvalid + 5;  // beyond 48 bits: not representable -> invalid
  c.angular = {kNaN, 100.0, -100.0};
  c.linear = {kInf, 3.2767, -3.2768};
  c.position = {0.7, -0.7, kNaN};
  c.orientation = {kNaN, 0, 0, 0};
  for (auto mode : {tp::FrameMode::kClassic, tp::FrameMode::kFd}) {
    tp::TxConfig tx;
    tx.frame_mode = mode;
    tp::CycleFrames f;
    ASSERT_EQ(tp::encode_cycle(c, 15, tx, f), tp::Status::kOk);
    const tp::Cycle got = decode_cycle(f, tx.endpoint);
    EXPECT_EQ(got.timestamp_us, tp::kTimestampInvalid);
    EXPECT_TRUE(std::isnan(got.angular.x));
    EXPECT_DOUBLE_EQ(got.angular.y, 32.767);
    EXPECT_DOUBLE_EQ(got.angular.z, -32.767);
    EXPECT_FALSE(got.angular_saturated.x);
    EXPECT_TRUE(got.angular_saturated.y);
    EXPECT_TRUE(got.angular_saturated.z);
    EXPECT_TRUE(std::isnan(got.linear.x));
    EXPECT_DOUBLE_EQ(got.linear.y, 3.2767);
    EXPECT_FALSE(got.linear_saturated.y);
    EXPECT_DOUBLE_EQ(got.linear.z, -3.2767);
    EXPECT_TRUE(got.linear_saturated.z);
    EXPECT_DOUBLE_EQ(got.position.x, 0.65534);
    EXPECT_DOUBLE_EQ(got.position.y, -0.65534);
    EXPECT_TRUE(got.position_saturated.x);
    EXPECT_TRUE(std::isnan(got.position.z));
    EXPECT_TRUE(std::isnan(got.orientation.w));
    EXPECT_TRUE(std::isnan(got.orientation.x));
    EXPECT_TRUE(got.saturated);
    EXPECT_EQ(got.counter, 15);
  }
  // A quaternion of norm ~0 is "not available", not a division by zero.
  c.orientation = {0, 0, 0, 0};
  tp::CycleFrames f;
  ASSERT_EQ(tp::encode_cycle(c, 0, tp::TxConfig{}, f), tp::Status::kOk);
  EXPECT_TRUE(std::isnan(f.sent.orientation.w));
}

TEST(RoundTrip, StatusAndCommandsRandom) {
  std::mt19937_64 rng(42);
  std::uniform_int_distribution<int> u8(0, 255);
  std::uniform_real_distribution<double> area(0.0, 0.0065534);
  std::uniform_real_distribution<double> time(0.0, 0.065534);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 300; ++i) {
    tp::StatusGroup g;
    g.status.state = static_cast<tp::State>(u8(rng) % 5);
    g.status.health_left = static_cast<tp::SensorHealth>(u8(rng) % 4);
    g.status.health_right = static_cast<tp::SensorHealth>(u8(rng) % 4);
    g.status.contact_left = (u8(rng) & 1) != 0;
    g.status.slip_right = (u8(rng) & 1) != 0;
    g.status.fusion = static_cast<tp::FusionMethod>(u8(rng) % 2);
    g.status.velocity_mode = static_cast<tp::VelocityMode>(u8(rng) % 3);
    g.status.confidence = i % 17 == 0 ? kNaN : unit(rng);
    g.status.rate_divider = static_cast<std::uint8_t>(1 + u8(rng) % 120);
    g.status.fault = static_cast<tp::FaultCode>(u8(rng) % 8);
    g.status.rejected_commands = static_cast<std::uint8_t>(u8(rng));
    g.contact.area_left_m2 = area(rng);
    g.contact.area_right_m2 = i % 13 == 0 ? kNaN : area(rng);
    g.contact.confidence_left = unit(rng);
    g.timing.dsp_time_s = time(rng);
    g.timing.latency_p99_s = time(rng);
    g.counters.dropped_left = static_cast<std::uint16_t>(u8(rng) * 257);
    std::array<tp::CanFrame, 4> f;
    ASSERT_EQ(tp::encode_status_group(g, static_cast<std::uint8_t>(i), tp::TxConfig{}, f),
              tp::Status::kOk);
    tp::Decoded d;
    ASSERT_EQ(tp::decode(f[0], tp::IdLayout{}, d), tp::Status::kOk);
    const auto& s = std::get<tp::StatusMsg>(d.payload);
    EXPECT_EQ(s.state, g.status.state);
    EXPECT_EQ(s.health_left, g.status.health_left);
    EXPECT_EQ(s.health_right, g.status.health_right);
    EXPECT_EQ(s.contact_left, g.status.contact_left);
    EXPECT_EQ(s.slip_right, g.status.slip_right);
    EXPECT_EQ(s.fusion, g.status.fusion);
    EXPECT_EQ(s.velocity_mode, g.status.velocity_mode);
    EXPECT_EQ(std::isnan(s.confidence), std::isnan(g.status.confidence));
    if (!std::isnan(g.status.confidence)) {
      EXPECT_NEAR(s.confidence, g.status.confidence, 0.002);
    }
    EXPECT_EQ(s.rate_divider, g.status.rate_divider);
    EXPECT_EQ(s.fault, g.status.fault);
    EXPECT_EQ(s.rejected_commands, g.status.rejected_commands);
    EXPECT_EQ(s.counter, i & 15);
    ASSERT_EQ(tp::decode(f[1], tp::IdLayout{}, d), tp::Status::kOk);
    const auto& c = std::get<tp::ContactMsg>(d.payload);
    EXPECT_NEAR(c.area_left_m2, g.contact.area_left_m2, 0.5e-7 + 1e-15);
    EXPECT_EQ(std::isnan(c.area_right_m2), std::isnan(g.contact.area_right_m2));
    ASSERT_EQ(tp::decode(f[2], tp::IdLayout{}, d), tp::Status::kOk);
    EXPECT_NEAR(std::get<tp::TimingMsg>(d.payload).latency_p99_s, g.timing.latency_p99_s,
                0.5e-6 + 1e-15);
    ASSERT_EQ(tp::decode(f[3], tp::IdLayout{}, d), tp::Status::kOk);
    EXPECT_EQ(std::get<tp::CountersMsg>(d.payload).dropped_left, g.counters.dropped_left);
  }
  // Every valid finger separation survives the command round trip to the LSB (10 um).
  for (int raw = 100; raw <= 25000; raw += 7) {
    tp::Command cmd;
    cmd.code = tp::CommandCode::kSetFingerSeparation;
    cmd.finger_separation_m = raw * 0.00001;
    tp::CanFrame f;
    ASSERT_EQ(tp::encode(cmd, tp::TxConfig{}, f), tp::Status::kOk);
    const tp::CommandResult r = tp::validate_command(f, tp::Endpoint{});
    ASSERT_EQ(r.code, tp::AckCode::kAck);
    EXPECT_NEAR(r.command.finger_separation_m, cmd.finger_separation_m, 1e-12);
  }
}

TEST(RoundTrip, RawLayerIsBijectiveOnCoveredBits) {
  // unpack_raw then pack_raw reproduces every bit a signal covers, for every message.
  std::mt19937_64 rng(7);
  for (const tp::MessageDef& m : tp::kMessages) {
    SCOPED_TRACE(std::string(m.name));
    for (int i = 0; i < 200; ++i) {
      std::array<std::uint8_t, 64> in{};
      for (std::size_t k = 0; k < m.length; ++k) in[k] = static_cast<std::uint8_t>(rng());
      tp::RawMessage raw;
      tp::unpack_raw(m, in.data(), raw);
      std::array<std::uint8_t, 64> out{};
      tp::pack_raw(m, raw, out.data());
      for (std::size_t bit = 0; bit < m.length * 8u; ++bit) {
        bool covered = false;
        for (std::size_t s = 0; s < m.signals.size(); ++s) {
          if ((raw.present >> s & 1u) != 0 && bit >= m.signals[s].start &&
              bit < m.signals[s].start + m.signals[s].length) {
            covered = true;
          }
        }
        const int a = in[bit / 8] >> (bit % 8) & 1;
        const int b = out[bit / 8] >> (bit % 8) & 1;
        EXPECT_EQ(b, covered ? a : 0) << "bit " << bit;
      }
    }
  }
}
