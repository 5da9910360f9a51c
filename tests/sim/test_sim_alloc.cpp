// SPDX-License-Identifier: Apache-2.0
// The simulator allocates everything in create(): step() and render() never touch the heap.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <vector>

#include "tacse3/sim/profile.hpp"
#include "tacse3/sim/simulator.hpp"

// GCC 12 flags free() in a replaced operator delete as mismatched once inlined; the pair
// below is consistent (malloc/free), so the warning is a false positive here.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace {
std::atomic<long> g_allocations{0};
thread_local bool g_counting = false;
}  // namespace

void* operator new(std::size_t n) {
  if (g_counting) g_allocations.fetch_add(1);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  return operator new(n);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}

namespace tacse3::sim {
namespace {

TEST(SimAlloc, StepAndRenderDoNotAllocate) {
  for (Regime regime : {Regime::kSlide, Regime::kStick}) {
    SimConfig c;
    c.scenario.axis = MotionAxis::kTx;
    c.scenario.magnitude = regime == Regime::kSlide ? 10.0 : 0.5;
    c.scenario.regime = regime;
    std::string error;
    auto sim = Simulator::create(c, &error);
    ASSERT_TRUE(sim) << error;
    std::vector<std::uint8_t> rgb(sim->frame_bytes(3)), grey(sim->frame_bytes(1));
    const Scenario& scn = sim->scenario();
    g_allocations = 0;
    g_counting = true;
    for (int i = 0; i < scn.frame_count(); i += 6) {
      const std::int64_t t = scn.frame_time_ns(i);
      ASSERT_EQ(sim->render(Sensor::kLeft, t, rgb, 3), SimStatus::kOk);
      ASSERT_EQ(sim->render(Sensor::kRight, t, grey, 1), SimStatus::kOk);
      (void)sim->truth(t);
    }
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0) << to_string(regime);
    EXPECT_TRUE(sim->labels(Sensor::kLeft).in_contact);
  }
}

// Every profile's models (radial bulge, tanh and Coulomb-rim laws, friction map, half-space
// spread, MJPEG camera) allocate in create() only. libjpeg's own per-image pools are C malloc
// inside libturbojpeg, outside this count.
TEST(SimAlloc, ProfilesStepAndRenderDoNotAllocate) {
  for (const char* name :
       {"soft-thick", "stiff-thin", "coulomb-rim", "halfspace-mjpeg", "random"}) {
    for (Regime regime : {Regime::kSlide, Regime::kStick}) {
      SensorProfile p;
      ASSERT_TRUE(make_profile(name, 5, &p, nullptr));
      SimConfig c;
      c.scenario.axis = MotionAxis::kRz;
      c.scenario.magnitude = regime == Regime::kSlide ? 20.0 : 3.0;
      c.scenario.regime = regime;
      apply_profile(p, &c);
      std::string error;
      auto sim = Simulator::create(c, &error);
      ASSERT_TRUE(sim) << error;
      std::vector<std::uint8_t> rgb(sim->frame_bytes(3)), grey(sim->frame_bytes(1));
      const Scenario& scn = sim->scenario();
      g_allocations = 0;
      g_counting = true;
      for (int i = 0; i < scn.frame_count(); i += 12) {
        const std::int64_t t = scn.frame_time_ns(i);
        ASSERT_EQ(sim->render(Sensor::kLeft, t, rgb, 3), SimStatus::kOk);
        ASSERT_EQ(sim->render(Sensor::kRight, t, grey, 1), SimStatus::kOk);
      }
      g_counting = false;
      EXPECT_EQ(g_allocations.load(), 0) << name << " " << to_string(regime);
    }
  }
}

}  // namespace
}  // namespace tacse3::sim
