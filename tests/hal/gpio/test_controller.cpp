// SPDX-License-Identifier: Apache-2.0
// Tests for the GPIO controller over a scripted backend, the null backend and absent chips.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "tacse3/hal/gpio.hpp"
#include "tacse3/hal/gpio/controller.hpp"

namespace tacse3::hal {
namespace {

constexpr std::int64_t kMs = 1'000'000;

// Records writes; inputs and edges are scripted by the test.
class FakeGpio final : public GpioBackend {
 public:
  explicit FakeGpio(std::vector<GpioLine> lines) : lines_(std::move(lines)) {}
  GpioStatus open(const GpioConfig&) override { return GpioStatus::success(); }
  bool has(GpioLine l) const override {
    for (GpioLine x : lines_) {
      if (x == l) return true;
    }
    return false;
  }
  GpioStatus write(GpioLine l, bool active) override {
    if (!has(l)) return GpioStatus::error(GpioError::kNotConfigured, "%s", to_string(l));
    writes.emplace_back(l, active);
    return GpioStatus::success();
  }
  GpioStatus read(GpioLine l, bool& active) override {
    active = l == GpioLine::kTareButton ? tare_level : gripper_level;
    return GpioStatus::success();
  }
  GpioStatus wait_edges(int, GpioEdge* edges, std::size_t capacity, std::size_t& count) override {
    count = 0;
    while (count < capacity && !queued.empty()) {
      edges[count++] = queued.front();
      queued.erase(queued.begin());
    }
    return GpioStatus::success();
  }
  void close() override {}
  const char* name() const override { return "fake"; }

  std::vector<std::pair<GpioLine, bool>> writes;
  std::vector<GpioEdge> queued;
  bool tare_level = false;
  bool gripper_level = false;

 private:
  std::vector<GpioLine> lines_;
};

const std::vector<GpioLine> kAll = {GpioLine::kStatusLed, GpioLine::kTareButton,
                                    GpioLine::kSensorTrigger, GpioLine::kGripperClosed};

std::vector<bool> led_writes(const FakeGpio& g) {
  std::vector<bool> out;
  for (const auto& [line, level] : g.writes) {
    if (line == GpioLine::kStatusLed) out.push_back(level);
  }
  return out;
}

TEST(GpioController, LedFollowsTheStatePatternAndWritesOnlyChanges) {
  FakeGpio g(kAll);
  GpioController c(g);
  ASSERT_TRUE(c.start(0).ok());  // booting: on at t=0
  for (std::int64_t t = 0; t <= 1000 * kMs; t += 10 * kMs) ASSERT_TRUE(c.tick(t).ok());
  // 250 on / 250 off over 1 s: on, off, on, off, on (t = 1000 ms starts a new period).
  EXPECT_EQ(led_writes(g), (std::vector<bool>{true, false, true, false, true}));

  g.writes.clear();
  c.set_state(LedState::kTracking);
  for (std::int64_t t = 1010 * kMs; t <= 3000 * kMs; t += 10 * kMs) ASSERT_TRUE(c.tick(t).ok());
  EXPECT_TRUE(led_writes(g).empty());  // already on, steady: no writes
  EXPECT_TRUE(c.led_on());

  c.set_state(LedState::kFault);
  for (std::int64_t t = 3010 * kMs; t < 3210 * kMs; t += 10 * kMs) ASSERT_TRUE(c.tick(t).ok());
  // 50 on / 50 off from 3010 ms; the LED is already on, so the first write is the 3060 ms off.
  EXPECT_EQ(led_writes(g), (std::vector<bool>{false, true, false}));
}

TEST(GpioController, BouncyTarePressCountsOnce) {
  FakeGpio g(kAll);
  GpioController c(g, GpioTiming{20 * kMs, 0});
  ASSERT_TRUE(c.start(0).ok());
  const GpioEdge bounce[] = {{GpioLine::kTareButton, true, 100 * kMs},
                             {GpioLine::kTareButton, false, 101 * kMs},
                             {GpioLine::kTareButton, true, 102 * kMs},
                             {GpioLine::kTareButton, false, 102 * kMs + 500'000},
                             {GpioLine::kTareButton, true, 103 * kMs}};
  c.on_edges(bounce, 5);
  EXPECT_EQ(c.next_deadline_ns(104 * kMs), 123 * kMs);
  ASSERT_TRUE(c.tick(110 * kMs).ok());
  EXPECT_EQ(c.take_inputs().tare_presses, 0u);
  ASSERT_TRUE(c.tick(123 * kMs).ok());
  ASSERT_TRUE(c.tick(300 * kMs).ok());
  EXPECT_EQ(c.take_inputs().tare_presses, 1u);
  EXPECT_EQ(c.take_inputs().tare_presses, 0u);  // taken
  // Release with bounce: no press.
  const GpioEdge release[] = {{GpioLine::kTareButton, false, 500 * kMs},
                              {GpioLine::kTareButton, true, 501 * kMs},
                              {GpioLine::kTareButton, false, 502 * kMs}};
  c.on_edges(release, 3);
  ASSERT_TRUE(c.tick(600 * kMs).ok());
  EXPECT_EQ(c.take_inputs().tare_presses, 0u);
  // Two real presses later.
  const GpioEdge two[] = {{GpioLine::kTareButton, true, 1000 * kMs}};
  c.on_edges(two, 1);
  ASSERT_TRUE(c.tick(1100 * kMs).ok());
  const GpioEdge up[] = {{GpioLine::kTareButton, false, 1200 * kMs}};
  c.on_edges(up, 1);
  ASSERT_TRUE(c.tick(1300 * kMs).ok());
  const GpioEdge again[] = {{GpioLine::kTareButton, true, 1400 * kMs}};
  c.on_edges(again, 1);
  ASSERT_TRUE(c.tick(1500 * kMs).ok());
  EXPECT_EQ(c.take_inputs().tare_presses, 2u);
}

TEST(GpioController, ButtonHeldAtStartIsNotAPress) {
  FakeGpio g(kAll);
  g.tare_level = true;
  GpioController c(g);
  ASSERT_TRUE(c.start(0).ok());
  ASSERT_TRUE(c.tick(1000 * kMs).ok());
  EXPECT_EQ(c.take_inputs().tare_presses, 0u);
}

TEST(GpioController, GripperClosedIsDebouncedAndReported) {
  FakeGpio g(kAll);
  GpioController c(g, GpioTiming{20 * kMs, 0});
  ASSERT_TRUE(c.start(0).ok());
  EXPECT_FALSE(c.gripper_closed());
  const GpioEdge close_edges[] = {{GpioLine::kGripperClosed, true, 50 * kMs},
                                  {GpioLine::kGripperClosed, false, 51 * kMs},
                                  {GpioLine::kGripperClosed, true, 52 * kMs}};
  c.on_edges(close_edges, 3);
  ASSERT_TRUE(c.tick(60 * kMs).ok());
  EXPECT_FALSE(c.gripper_closed());
  ASSERT_TRUE(c.tick(72 * kMs).ok());
  EXPECT_TRUE(c.gripper_closed());
  GpioInputs in = c.take_inputs();
  EXPECT_TRUE(in.gripper_closed);
  EXPECT_TRUE(in.gripper_changed);
  in = c.take_inputs();
  EXPECT_TRUE(in.gripper_closed);
  EXPECT_FALSE(in.gripper_changed);
}

TEST(GpioController, PollRunsTheBackendOnTheMonotonicClock) {
  FakeGpio g(kAll);
  GpioController c(g, GpioTiming{0, 0});  // no debounce window
  ASSERT_TRUE(c.start(0).ok());
  // A CLOCK_REALTIME-stamped edge (pre-5.7 kernels) is re-stamped with the wake-up time.
  g.queued.push_back({GpioLine::kTareButton, true, 1'700'000'000'000'000'000});
  ASSERT_TRUE(c.poll(0).ok());
  ASSERT_TRUE(c.poll(0).ok());
  EXPECT_EQ(c.take_inputs().tare_presses, 1u);
}

TEST(GpioController, TriggerPulse) {
  FakeGpio g(kAll);
  GpioController c(g, GpioTiming{20 * kMs, 50'000});
  ASSERT_TRUE(c.pulse_trigger().ok());
  ASSERT_EQ(g.writes.size(), 2u);
  EXPECT_EQ(g.writes[0], std::make_pair(GpioLine::kSensorTrigger, true));
  EXPECT_EQ(g.writes[1], std::make_pair(GpioLine::kSensorTrigger, false));
}

TEST(GpioController, MissingLinesAreSkippedOrReported) {
  FakeGpio g({});  // a board without any line
  GpioController c(g);
  ASSERT_TRUE(c.start(0).ok());
  for (std::int64_t t = 0; t < 1000 * kMs; t += 10 * kMs) ASSERT_TRUE(c.tick(t).ok());
  EXPECT_TRUE(g.writes.empty());
  const GpioStatus st = c.pulse_trigger();
  EXPECT_EQ(st.code, GpioError::kNotConfigured);
  EXPECT_NE(std::strstr(st.message(), "sensor_trigger"), nullptr) << st.message();
}

TEST(NullGpio, HasNothingAndSleepsInsteadOfSpinning) {
  auto g = make_null_gpio();
  GpioConfig cfg;
  cfg.line(GpioLine::kStatusLed).enabled = true;
  ASSERT_TRUE(g->open(cfg).ok());
  EXPECT_FALSE(g->has(GpioLine::kStatusLed));
  EXPECT_EQ(g->write(GpioLine::kStatusLed, true).code, GpioError::kNotConfigured);
  bool level = true;
  EXPECT_EQ(g->read(GpioLine::kTareButton, level).code, GpioError::kNotConfigured);
  EXPECT_FALSE(level);
  GpioEdge e[4];
  std::size_t n = 99;
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(g->wait_edges(30, e, 4, n).ok());
  const auto waited = std::chrono::steady_clock::now() - t0;
  EXPECT_EQ(n, 0u);
  EXPECT_GE(waited, std::chrono::milliseconds(29));
  GpioController c(*g);
  ASSERT_TRUE(c.start(0).ok());
  EXPECT_TRUE(c.poll(5).ok());
  EXPECT_STREQ(g->name(), "null");
}

TEST(LibgpiodGpio, NoLinesConfiguredOpensNothing) {
  auto g = make_libgpiod_gpio();
  const GpioStatus st = g->open(GpioConfig{});
  if (!libgpiod_available()) {
    EXPECT_EQ(st.code, GpioError::kUnavailable);
    return;
  }
  EXPECT_TRUE(st.ok()) << st.message();
  EXPECT_FALSE(g->has(GpioLine::kStatusLed));
  EXPECT_EQ(g->write(GpioLine::kStatusLed, true).code, GpioError::kNotConfigured);
}

TEST(LibgpiodGpio, AbsentChipIsAClearError) {
  auto g = make_libgpiod_gpio();
  GpioConfig cfg;
  cfg.chip = "/dev/gpiochip-nonexistent";
  cfg.line(GpioLine::kStatusLed) = GpioLineConfig{true, "", "", 17, false, GpioBias::kAsIs};
  const GpioStatus st = g->open(cfg);
  if (!libgpiod_available()) {
    EXPECT_EQ(st.code, GpioError::kUnavailable);
    return;
  }
  EXPECT_EQ(st.code, GpioError::kNotFound) << st.message();
  EXPECT_NE(std::strstr(st.message(), "status_led"), nullptr) << st.message();
  EXPECT_NE(std::strstr(st.message(), "/dev/gpiochip-nonexistent"), nullptr) << st.message();
  EXPECT_FALSE(g->has(GpioLine::kStatusLed));
}

TEST(LibgpiodGpio, LineWithoutNameOrOffsetIsABadConfig) {
  if (!libgpiod_available()) GTEST_SKIP();
  auto g = make_libgpiod_gpio();
  GpioConfig cfg;
  cfg.line(GpioLine::kTareButton).enabled = true;
  const GpioStatus st = g->open(cfg);
  EXPECT_EQ(st.code, GpioError::kBadConfig);
  EXPECT_NE(std::strstr(st.message(), "tare_button"), nullptr) << st.message();
}

TEST(LibgpiodGpio, NamedLineOnNoChipIsNotFound) {
  if (!libgpiod_available()) GTEST_SKIP();
  auto g = make_libgpiod_gpio();
  GpioConfig cfg;
  cfg.chip = "";  // search every chip (there are none here)
  cfg.line(GpioLine::kGripperClosed) =
      GpioLineConfig{true, "", "GPIO27", -1, true, GpioBias::kPullUp};
  const GpioStatus st = g->open(cfg);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(std::strstr(st.message(), "GPIO27"), nullptr) << st.message();
}

}  // namespace
}  // namespace tacse3::hal
