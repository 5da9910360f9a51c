// SPDX-License-Identifier: Apache-2.0
// firmware tests: the DSP thread's doorbell (a ring is never lost, it ends a wait early, the wait
// is bounded) and pinning a pad's thread to a CPU.
#include <gtest/gtest.h>
#include <sched.h>

#include <thread>

#include "tacse3/firmware/doorbell.hpp"
#include "tacse3/firmware/system.hpp"
#include "tacse3/hal/camera/clock.hpp"

using namespace tacse3;
using namespace tacse3::firmware;

namespace {

constexpr std::int64_t kLong = 10'000'000'000;  // a wait no test may sit out

std::int64_t waited_ns(Doorbell& bell, std::uint32_t seen, std::int64_t timeout_ns) {
  const std::int64_t t0 = hal::monotonic_ns();
  bell.wait(seen, timeout_ns);
  return hal::monotonic_ns() - t0;
}

}  // namespace

// A frame handed over between reading the counter and waiting: the wait returns at once.
TEST(Doorbell, RingBeforeTheWaitIsNotLost) {
  Doorbell bell;
  const std::uint32_t seen = bell.value();
  bell.ring();
  EXPECT_EQ(bell.value(), seen + 1);
  EXPECT_LT(waited_ns(bell, seen, kLong), 1'000'000'000);
}

TEST(Doorbell, RingWakesTheWaiter) {
  Doorbell bell;
  const std::uint32_t seen = bell.value();
  std::thread ringer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    bell.ring();
  });
  const std::int64_t ns = waited_ns(bell, seen, kLong);
  ringer.join();
  EXPECT_GE(ns, 15'000'000);
  EXPECT_LT(ns, 5'000'000'000) << "woken by the timeout, not the ring";
}

TEST(Doorbell, WaitWithoutRingEndsAtTheTimeout) {
  Doorbell bell;
  const std::int64_t ns = waited_ns(bell, bell.value(), 20'000'000);
  EXPECT_GE(ns, 19'000'000);
  EXPECT_LT(ns, 5'000'000'000);
}

// [realtime] pad_cpus: the capture thread pins itself; a CPU that does not exist is named.
TEST(PinThread, PinsToTheCpuOrSaysWhyNot) {
  std::string ok, missing, none;
  cpu_set_t after;
  CPU_ZERO(&after);
  std::thread t([&] {
    none = pin_current_thread(-1);
    ok = pin_current_thread(0);
    sched_getaffinity(0, sizeof(after), &after);
    missing = pin_current_thread(4095);
  });
  t.join();
  EXPECT_EQ(none, "");
  EXPECT_EQ(ok, "");
  EXPECT_EQ(CPU_COUNT(&after), 1);
  EXPECT_TRUE(CPU_ISSET(0, &after));
  EXPECT_NE(missing.find("CPU 4095 does not exist"), std::string::npos) << missing;
}
