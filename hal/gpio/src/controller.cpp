// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: LED blink patterns, button debounce and the controller driving a GpioBackend.
#include "tacse3/hal/gpio/controller.hpp"

#include <time.h>

#include <algorithm>
#include <climits>

namespace tacse3::hal {
namespace {

constexpr std::int64_t kMs = 1'000'000;

std::int64_t now_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

constexpr BlinkPattern kOffPattern{{}, 0};
constexpr BlinkPattern kBootingPattern{{250, 250}, 2};
constexpr BlinkPattern kNoContactPattern{{100, 1900}, 2};
constexpr BlinkPattern kTrackingPattern{{1}, 1};
constexpr BlinkPattern kDegradedPattern{{100, 150, 100, 650}, 4};
constexpr BlinkPattern kFaultPattern{{50, 50}, 2};

}  // namespace

const char* to_string(LedState s) noexcept {
  switch (s) {
    case LedState::kOff:
      return "off";
    case LedState::kBooting:
      return "booting";
    case LedState::kNoContact:
      return "no-contact";
    case LedState::kTracking:
      return "tracking";
    case LedState::kDegraded:
      return "degraded";
    case LedState::kFault:
      return "fault";
  }
  return "unknown";
}

std::int64_t BlinkPattern::period_ns() const noexcept {
  std::int64_t sum = 0;
  for (std::size_t i = 0; i < count; ++i) sum += ms[i];
  return sum * kMs;
}

const BlinkPattern& blink_pattern(LedState s) noexcept {
  switch (s) {
    case LedState::kOff:
      return kOffPattern;
    case LedState::kBooting:
      return kBootingPattern;
    case LedState::kNoContact:
      return kNoContactPattern;
    case LedState::kTracking:
      return kTrackingPattern;
    case LedState::kDegraded:
      return kDegradedPattern;
    case LedState::kFault:
      return kFaultPattern;
  }
  return kFaultPattern;
}

bool led_level(const BlinkPattern& p, std::int64_t elapsed_ns) noexcept {
  if (p.count == 0) return false;
  if (p.count == 1) return true;
  const std::int64_t period = p.period_ns();
  if (period <= 0) return false;
  const std::int64_t t = std::max<std::int64_t>(elapsed_ns, 0) % period;
  std::int64_t end = 0;
  for (std::size_t i = 0; i < p.count; ++i) {
    end += p.ms[i] * kMs;
    if (t < end) return i % 2 == 0;
  }
  return false;
}

std::int64_t led_next_change_ns(const BlinkPattern& p, std::int64_t elapsed_ns) noexcept {
  if (p.count <= 1) return INT64_MAX;
  const std::int64_t period = p.period_ns();
  if (period <= 0) return INT64_MAX;
  const std::int64_t t = std::max<std::int64_t>(elapsed_ns, 0) % period;
  std::int64_t end = 0;
  for (std::size_t i = 0; i < p.count; ++i) {
    end += p.ms[i] * kMs;
    if (t < end) return end - t;
  }
  return period - t;
}

void Debouncer::reset(bool level, std::int64_t now_ns) noexcept {
  stable_ = level;
  raw_ = level;
  raw_since_ns_ = now_ns;
}

void Debouncer::edge(bool level, std::int64_t t_ns) noexcept {
  raw_ = level;
  raw_since_ns_ = t_ns;
}

bool Debouncer::update(std::int64_t now_ns) noexcept {
  if (raw_ == stable_ || now_ns - raw_since_ns_ < window_ns_) return false;
  stable_ = raw_;
  return true;
}

std::int64_t Debouncer::deadline_ns() const noexcept {
  return raw_ == stable_ ? INT64_MAX : raw_since_ns_ + window_ns_;
}

GpioController::GpioController(GpioBackend& backend, const GpioTiming& timing) noexcept
    : backend_(backend), timing_(timing), tare_(timing.debounce_ns), gripper_(timing.debounce_ns) {}

GpioStatus GpioController::start(std::int64_t now) {
  bool level = false;
  if (backend_.has(GpioLine::kTareButton)) {
    GpioStatus st = backend_.read(GpioLine::kTareButton, level);
    if (!st.ok()) return st;
  }
  tare_.reset(level, now);
  level = false;
  if (backend_.has(GpioLine::kGripperClosed)) {
    GpioStatus st = backend_.read(GpioLine::kGripperClosed, level);
    if (!st.ok()) return st;
  }
  gripper_.reset(level, now);
  gripper_level_.store(level, std::memory_order_release);
  return tick(now);
}

void GpioController::on_edges(const GpioEdge* edges, std::size_t count) noexcept {
  for (std::size_t i = 0; i < count; ++i) {
    if (edges[i].line == GpioLine::kTareButton) {
      tare_.edge(edges[i].active, edges[i].timestamp_ns);
    } else if (edges[i].line == GpioLine::kGripperClosed) {
      gripper_.edge(edges[i].active, edges[i].timestamp_ns);
    }
  }
}

GpioStatus GpioController::tick(std::int64_t now) {
  const LedState want = requested_.load(std::memory_order_acquire);
  if (want != shown_) {
    shown_ = want;
    shown_since_ns_ = now;
  }
  const bool level = led_level(blink_pattern(shown_), now - shown_since_ns_);
  GpioStatus st;
  if (backend_.has(GpioLine::kStatusLed) && (level != led_on_ || !led_written_)) {
    st = backend_.write(GpioLine::kStatusLed, level);
    led_written_ = st.ok();
  }
  led_on_ = level;

  if (tare_.update(now) && tare_.level()) tare_presses_.fetch_add(1, std::memory_order_acq_rel);
  if (gripper_.update(now)) {
    gripper_level_.store(gripper_.level(), std::memory_order_release);
    gripper_changed_.store(true, std::memory_order_release);
  }
  return st;
}

std::int64_t GpioController::next_deadline_ns(std::int64_t now) const noexcept {
  if (requested_.load(std::memory_order_acquire) != shown_) return now;
  std::int64_t next = INT64_MAX;
  const std::int64_t led = led_next_change_ns(blink_pattern(shown_), now - shown_since_ns_);
  if (led != INT64_MAX) next = now + led;
  next = std::min(next, tare_.deadline_ns());
  next = std::min(next, gripper_.deadline_ns());
  return next;
}

GpioStatus GpioController::poll(int timeout_ms) {
  std::int64_t now = now_ns();
  std::int64_t until = timeout_ms < 0 ? INT64_MAX : now + timeout_ms * kMs;
  until = std::min(until, next_deadline_ns(now));
  int wait_ms = -1;
  if (until != INT64_MAX) {
    const std::int64_t left = std::max<std::int64_t>(until - now, 0);
    wait_ms = static_cast<int>(std::min<std::int64_t>((left + kMs - 1) / kMs, INT_MAX));
  }
  std::array<GpioEdge, 16> edges{};
  std::size_t count = 0;
  GpioStatus st = backend_.wait_edges(wait_ms, edges.data(), edges.size(), count);
  now = now_ns();
  for (std::size_t i = 0; i < count; ++i) {
    const std::int64_t skew = edges[i].timestamp_ns - now;
    if (skew > 1'000'000'000 || skew < -1'000'000'000) edges[i].timestamp_ns = now;
  }
  on_edges(edges.data(), count);
  GpioStatus t = tick(now);
  return st.ok() ? t : st;
}

GpioInputs GpioController::take_inputs() noexcept {
  GpioInputs in;
  in.tare_presses = tare_presses_.exchange(0, std::memory_order_acq_rel);
  in.gripper_closed = gripper_level_.load(std::memory_order_acquire);
  in.gripper_changed = gripper_changed_.exchange(false, std::memory_order_acq_rel);
  return in;
}

GpioStatus GpioController::pulse_trigger() {
  if (!backend_.has(GpioLine::kSensorTrigger)) {
    return GpioStatus::error(GpioError::kNotConfigured,
                             "GPIO sensor_trigger: not in the board file");
  }
  GpioStatus st = backend_.write(GpioLine::kSensorTrigger, true);
  if (!st.ok()) return st;
  if (timing_.trigger_pulse_ns > 0) {
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(timing_.trigger_pulse_ns / 1'000'000'000);
    ts.tv_nsec = static_cast<long>(timing_.trigger_pulse_ns % 1'000'000'000);
    clock_nanosleep(CLOCK_MONOTONIC, 0, &ts, nullptr);
  }
  return backend_.write(GpioLine::kSensorTrigger, false);
}

}  // namespace tacse3::hal
