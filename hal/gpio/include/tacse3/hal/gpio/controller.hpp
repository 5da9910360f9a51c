// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: LED blink patterns, button debounce and the controller driving a GpioBackend.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

#include "tacse3/hal/gpio.hpp"

namespace tacse3::hal {

// Daemon states shown on the status LED.
enum class LedState : std::uint8_t { kOff = 0, kBooting, kNoContact, kTracking, kDegraded, kFault };

const char* to_string(LedState s) noexcept;

// A repeating sequence of durations in ms, alternately LED on and LED off, starting with on.
// count == 0: always off; count == 1: always on.
struct BlinkPattern {
  std::array<std::uint16_t, 6> ms{};
  std::uint8_t count = 0;

  std::int64_t period_ns() const noexcept;
};

// The pattern table:
//   off        dark
//   booting    250 on / 250 off                 (2 Hz blink)
//   no-contact 100 on / 1900 off                (short flash every 2 s: alive, idle)
//   tracking   on                               (steady)
//   degraded   100 on / 150 off / 100 on / 650 off  (double flash every second)
//   fault      50 on / 50 off                   (10 Hz flicker)
const BlinkPattern& blink_pattern(LedState s) noexcept;

// LED level `elapsed_ns` after the pattern started.
bool led_level(const BlinkPattern& p, std::int64_t elapsed_ns) noexcept;
// Time from `elapsed_ns` until the level next changes (INT64_MAX for steady patterns).
std::int64_t led_next_change_ns(const BlinkPattern& p, std::int64_t elapsed_ns) noexcept;

// Time-based debounce: the debounced level follows the raw level once the raw level has not
// changed for `window_ns`. A glitch shorter than the window never shows; contact bounce delays
// the change by the window after the last bounce. Pure logic: times are injected.
class Debouncer {
 public:
  explicit Debouncer(std::int64_t window_ns = 20'000'000, bool level = false) noexcept
      : window_ns_(window_ns), stable_(level), raw_(level) {}

  // Set both levels (initial read), no pending change.
  void reset(bool level, std::int64_t now_ns) noexcept;
  // A raw edge: `level` is the level after it, at t_ns. An edge that repeats the current raw
  // level (its opposite edge was lost) still restarts the window.
  void edge(bool level, std::int64_t t_ns) noexcept;
  // Commits a raw level stable for the window as of now_ns; true when the debounced level
  // changed (read it with level()).
  bool update(std::int64_t now_ns) noexcept;

  bool level() const noexcept { return stable_; }
  bool pending() const noexcept { return raw_ != stable_; }
  // When update() will commit the pending level (INT64_MAX when nothing is pending).
  std::int64_t deadline_ns() const noexcept;

 private:
  std::int64_t window_ns_;
  bool stable_;
  bool raw_;
  std::int64_t raw_since_ns_ = 0;
};

struct GpioTiming {
  std::int64_t debounce_ns = 20'000'000;    // tare button and gripper switch
  std::int64_t trigger_pulse_ns = 100'000;  // width of a sensor trigger pulse
};

// What the inputs did since the last take_inputs().
struct GpioInputs {
  std::uint32_t tare_presses = 0;  // debounced press (inactive -> active) transitions
  bool gripper_closed = false;     // debounced level now
  bool gripper_changed = false;
};

// Drives a GpioBackend: the LED pattern for the current state, debounced inputs, the trigger.
// Run poll() in a loop on one GPIO thread. set_state(), take_inputs() and gripper_closed() are
// lock-free and may be called from any thread (e.g. the DSP thread).
class GpioController {
 public:
  explicit GpioController(GpioBackend& backend, const GpioTiming& timing = {}) noexcept;

  // Reads the inputs' levels (no press is reported for a button held at start).
  GpioStatus start(std::int64_t now_ns);
  // Thread-safe; the pattern restarts (LED on) at the next tick().
  void set_state(LedState s) noexcept { requested_.store(s, std::memory_order_release); }
  LedState state() const noexcept { return requested_.load(std::memory_order_acquire); }

  // Pure-logic steps (tests inject time):
  void on_edges(const GpioEdge* edges, std::size_t count) noexcept;
  GpioStatus tick(std::int64_t now_ns);
  // When tick() next has something to do (LED change or debounce commit).
  std::int64_t next_deadline_ns(std::int64_t now_ns) const noexcept;

  // Waits for edges up to timeout_ms, but no longer than the next LED/debounce deadline, then
  // runs on_edges() and tick() on CLOCK_MONOTONIC. Edge timestamps more than 1 s away from
  // CLOCK_MONOTONIC (kernels before 5.7 stamp GPIO events with CLOCK_REALTIME) are replaced by
  // the wake-up time.
  GpioStatus poll(int timeout_ms);

  GpioInputs take_inputs() noexcept;
  bool gripper_closed() const noexcept { return gripper_level_.load(std::memory_order_acquire); }

  // One trigger pulse: active, trigger_pulse_ns, inactive. kNotConfigured without the line.
  GpioStatus pulse_trigger();

  bool led_on() const noexcept { return led_on_; }

 private:
  GpioBackend& backend_;
  GpioTiming timing_;
  Debouncer tare_;
  Debouncer gripper_;
  std::atomic<LedState> requested_{LedState::kBooting};
  LedState shown_ = LedState::kOff;
  std::int64_t shown_since_ns_ = 0;
  bool led_on_ = false;
  bool led_written_ = false;
  std::atomic<std::uint32_t> tare_presses_{0};
  std::atomic<bool> gripper_level_{false};
  std::atomic<bool> gripper_changed_{false};
};

}  // namespace tacse3::hal
