// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: sensor health and state machine.
#include "tacse3/firmware/health.hpp"

namespace tacse3::firmware {

SensorHealth sensor_health(const SensorObservation& s, std::int64_t now_ns,
                           const HealthConfig& c) noexcept {
  if (!s.configured) return SensorHealth::kNotAvailable;
  if (s.disconnected || !s.seen) return SensorHealth::kLost;
  const std::int64_t age = now_ns - s.last_frame_ns;
  if (age > c.lost_ns) return SensorHealth::kLost;
  if (age > c.stale_ns) return SensorHealth::kStale;
  return SensorHealth::kOk;
}

StateOutput StateMachine::update(const StateInputs& in, std::int64_t now_ns) noexcept {
  StateOutput out;
  int configured = 0;
  int ok = 0;
  int lost = 0;
  int seen = 0;
  for (std::size_t i = 0; i < 2; ++i) {
    const SensorObservation& s = in.sensors[i];
    out.health[i] = sensor_health(s, now_ns, config_);
    if (!s.configured) continue;
    ++configured;
    seen += s.seen ? 1 : 0;
    ok += out.health[i] == SensorHealth::kOk ? 1 : 0;
    lost += out.health[i] == SensorHealth::kLost ? 1 : 0;
  }
  if (booting_) {
    if (seen == configured && configured > 0) {
      booting_ = false;
    } else if (now_ns - start_ns_ < config_.boot_timeout_ns) {
      out.state = State::kBooting;
      return out;
    } else {
      booting_ = false;
    }
  }
  const bool left_lost = out.health[0] == SensorHealth::kLost;
  const bool right_lost = out.health[1] == SensorHealth::kLost;
  if (configured == 0 || lost == configured) {
    out.state = State::kFault;
    out.fault = configured == 2 ? FaultCode::kBothSensorsLost
                                : (in.sensors[0].configured ? FaultCode::kLeftSensorLost
                                                            : FaultCode::kRightSensorLost);
    return out;
  }
  if (ok < configured) {
    out.state = State::kDegradedSingleSensor;
    out.fault = left_lost ? FaultCode::kLeftSensorLost
                          : (right_lost ? FaultCode::kRightSensorLost : FaultCode::kNone);
    return out;
  }
  out.state = in.contact ? State::kTracking : State::kNoContact;
  return out;
}

}  // namespace tacse3::firmware
