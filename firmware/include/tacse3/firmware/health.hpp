// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: per-sensor health and the daemon state machine (pure logic, times injected).
#pragma once

#include <array>
#include <cstdint>

#include "tacse3/protocol/types.hpp"

namespace tacse3::firmware {

using protocol::FaultCode;
using protocol::SensorHealth;
using protocol::State;

struct HealthConfig {
  std::int64_t stale_ns =
      50'000'000;  // no frame for this long: stale (the loop goes on without it)
  std::int64_t lost_ns = 500'000'000;  // ... and lost after this long
  // BOOTING ends when every configured sensor has streamed, or after this long (then the missing
  // sensor is lost and the state says so).
  std::int64_t boot_timeout_ns = 5'000'000'000;
};

// What the DSP thread knows about one sensor.
struct SensorObservation {
  bool configured = false;         // the board has this sensor
  bool disconnected = false;       // the camera reported a disconnect (lost at once)
  bool seen = false;               // at least one frame since start
  std::int64_t last_frame_ns = 0;  // arrival time of the last frame
};

SensorHealth sensor_health(const SensorObservation& s, std::int64_t now_ns,
                           const HealthConfig& c) noexcept;

struct StateInputs {
  std::array<SensorObservation, 2> sensors{};
  bool contact = false;  // the last processed sample had contact on a contributing pad
};

struct StateOutput {
  State state = State::kBooting;
  std::array<SensorHealth, 2> health{SensorHealth::kNotAvailable, SensorHealth::kNotAvailable};
  FaultCode fault = FaultCode::kNone;
};

// booting -> no-contact <-> tracking; degraded-single-sensor when one of two configured sensors
// is stale or lost; fault when every configured sensor is lost; back when they return.
class StateMachine {
 public:
  explicit StateMachine(const HealthConfig& config = {}) noexcept : config_(config) {}
  void start(std::int64_t now_ns) noexcept {
    start_ns_ = now_ns;
    booting_ = true;
  }
  StateOutput update(const StateInputs& in, std::int64_t now_ns) noexcept;
  const HealthConfig& config() const noexcept { return config_; }

 private:
  HealthConfig config_;
  std::int64_t start_ns_ = 0;
  bool booting_ = true;
};

}  // namespace tacse3::firmware
