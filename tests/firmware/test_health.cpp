// SPDX-License-Identifier: Apache-2.0
// firmware tests: sensor health and the state machine (booting, contact, degraded, fault,
// recovery).
#include <gtest/gtest.h>

#include "tacse3/firmware/health.hpp"

using namespace tacse3::firmware;

namespace {
constexpr std::int64_t kMs = 1'000'000;

SensorObservation streaming(std::int64_t last) {
  return {true, false, true, last};
}
}  // namespace

TEST(Health, StaleAndLostThresholds) {
  const HealthConfig c;  // 50 ms / 500 ms
  EXPECT_EQ(sensor_health({false, false, false, 0}, 0, c), SensorHealth::kNotAvailable);
  EXPECT_EQ(sensor_health(streaming(0), 50 * kMs, c), SensorHealth::kOk);
  EXPECT_EQ(sensor_health(streaming(0), 50 * kMs + 1, c), SensorHealth::kStale);
  EXPECT_EQ(sensor_health(streaming(0), 500 * kMs, c), SensorHealth::kStale);
  EXPECT_EQ(sensor_health(streaming(0), 500 * kMs + 1, c), SensorHealth::kLost);
  SensorObservation unplugged = streaming(0);
  unplugged.disconnected = true;
  EXPECT_EQ(sensor_health(unplugged, 1, c), SensorHealth::kLost) << "a disconnect is lost at once";
}

TEST(Health, StateMachineWalksEveryState) {
  StateMachine m;
  m.start(0);
  StateInputs in;
  in.sensors[0] = {true, false, false, 0};
  in.sensors[1] = {true, false, false, 0};
  EXPECT_EQ(m.update(in, 10 * kMs).state, State::kBooting);
  in.sensors[0] = streaming(20 * kMs);
  EXPECT_EQ(m.update(in, 20 * kMs).state, State::kBooting) << "waits for both sensors";
  in.sensors[1] = streaming(25 * kMs);
  EXPECT_EQ(m.update(in, 25 * kMs).state, State::kNoContact);
  in.contact = true;
  StateOutput o = m.update(in, 26 * kMs);
  EXPECT_EQ(o.state, State::kTracking);
  EXPECT_EQ(o.fault, FaultCode::kNone);
  // Right unplugged: degraded at once, fault code names it.
  in.sensors[1].disconnected = true;
  in.sensors[0] = streaming(30 * kMs);
  o = m.update(in, 30 * kMs);
  EXPECT_EQ(o.state, State::kDegradedSingleSensor);
  EXPECT_EQ(o.health[1], SensorHealth::kLost);
  EXPECT_EQ(o.fault, FaultCode::kRightSensorLost);
  // Left goes silent too: stale (still degraded), then lost -> fault.
  o = m.update(in, 90 * kMs);
  EXPECT_EQ(o.state, State::kDegradedSingleSensor);
  EXPECT_EQ(o.health[0], SensorHealth::kStale);
  o = m.update(in, 531 * kMs);
  EXPECT_EQ(o.state, State::kFault);
  EXPECT_EQ(o.fault, FaultCode::kBothSensorsLost);
  // Both return: back to tracking.
  in.sensors[0] = streaming(600 * kMs);
  in.sensors[1] = streaming(600 * kMs);
  o = m.update(in, 601 * kMs);
  EXPECT_EQ(o.state, State::kTracking);
  EXPECT_EQ(o.health[0], SensorHealth::kOk);
  EXPECT_EQ(o.health[1], SensorHealth::kOk);
}

TEST(Health, BootTimeoutAndSingleSensorBoards) {
  HealthConfig c;
  c.boot_timeout_ns = 1000 * kMs;
  StateMachine m(c);
  m.start(0);
  StateInputs in;
  in.sensors[0] = streaming(0);
  in.sensors[1] = {true, false, false, 0};  // never streams
  EXPECT_EQ(m.update(in, 999 * kMs).state, State::kBooting);
  in.sensors[0] = streaming(1000 * kMs);
  const StateOutput o = m.update(in, 1000 * kMs);
  EXPECT_EQ(o.state, State::kDegradedSingleSensor);
  EXPECT_EQ(o.fault, FaultCode::kRightSensorLost);
  // A board with only a left sensor tracks normally and faults when it is lost.
  StateMachine single;
  single.start(0);
  StateInputs one;
  one.sensors[0] = streaming(5 * kMs);
  EXPECT_EQ(single.update(one, 5 * kMs).state, State::kNoContact);
  EXPECT_EQ(single.update(one, 5 * kMs).health[1], SensorHealth::kNotAvailable);
  const StateOutput f = single.update(one, 600 * kMs);
  EXPECT_EQ(f.state, State::kFault);
  EXPECT_EQ(f.fault, FaultCode::kLeftSensorLost);
}
