// SPDX-License-Identifier: Apache-2.0
// firmware tests: the daemon on the sim board with real threads: a sensor unplugged mid-stream
// (degraded within 3 frame periods, no lost or garbled cycle), replugged (back to dual), a
// calibration reload that is rejected and one that is applied, and a stop within 1 s.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "bus_events.hpp"
#include "tacse3/firmware/daemon.hpp"
#include "tacse3/hal/camera/sim_camera.hpp"

namespace fs = std::filesystem;
using namespace tacse3;
using namespace tacse3::firmware;

namespace {

bool wait_for(const std::function<bool()>& cond, double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    if (cond()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return cond();
}

std::string read_all(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST(DaemonSim, UnplugDegradesReplugRecoversNoCycleLost) {
  const fs::path dir = fs::temp_directory_path() / ("tacse3-fw-daemon-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const fs::path log = dir / "bus.log";
  const fs::path cal_file = dir / "calibration.toml";
  fs::copy_file(TACSE3_SIM_CALIBRATION, cal_file, fs::copy_options::overwrite_existing);

  // The sim board with frames as fast as the loop takes them (realtime off): paced in real time
  // on a loaded machine each simulated sensor skips the instants it rendered too late, on its
  // own, and pairs become rare; unpaced, both deliver every instant. The stale/lost times are
  // raised from 50/500 ms for the same reason (tests/firmware/test_health.cpp covers those
  // thresholds); an unplug is a disconnect and is lost at once whatever they are.
  std::string text = read_all(fs::path(TACSE3_SOURCE_BOARDS_DIR) / "sim/board.toml");
  text.replace(text.find("realtime = true"), 15, "realtime = false");
  text.replace(text.find("stale_ms = 50"), 13, "stale_ms = 1000");
  text.replace(text.find("lost_ms = 500"), 13, "lost_ms = 2000");
  config::BoardConfig board;
  std::string e;
  ASSERT_TRUE(config::parse_board(text, "sim-test", &board, &e)) << e;
  board.can.backend = config::CanBackend::kLog;
  board.can.log = log.string();
  Options opt;
  opt.verbosity = 0;
  CalibrationSource cal;
  ASSERT_TRUE(load_calibration_source(cal_file.string(), &cal, &e)) << e;
  auto d = Daemon::create(board, opt, cal, stderr, &e);
  ASSERT_TRUE(d) << e;
  ASSERT_NE(d->sim_camera(1), nullptr);
  int rc = -1;
  std::thread t([&] { rc = d->run(false); });
  const auto emitted = [&] { return d->shared().emitted.load(); };

  // Past the grasp and the turn (2 s of the scenario at 120 Hz): both pads hold the sphere.
  ASSERT_TRUE(wait_for([&] { return emitted() >= 260; }, 120)) << "the daemon did not stream";
  // SIGHUP path: a bad file is rejected and the last good calibration stays; a good one applies.
  std::ofstream(cal_file)
      << "format = \"tacse3-calibration\"\nversion = 1\n[sensor]\nc_velocity = 500\n";
  std::string msg;
  EXPECT_FALSE(d->reload_calibration(&msg));
  EXPECT_NE(msg.find(cal_file.string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("c_velocity"), std::string::npos) << msg;
  // A FIFO at the path is refused at once; it used to block the reload for good.
  fs::remove(cal_file);
  ASSERT_EQ(::mkfifo(cal_file.c_str(), 0600), 0);
  const auto t_fifo = std::chrono::steady_clock::now();
  EXPECT_FALSE(d->reload_calibration(&msg));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t_fifo).count(), 1.0);
  EXPECT_NE(msg.find(cal_file.string() + ": is a FIFO"), std::string::npos) << msg;
  fs::remove(cal_file);
  fs::copy_file(TACSE3_SIM_CALIBRATION, cal_file, fs::copy_options::overwrite_existing);
  EXPECT_TRUE(d->reload_calibration(&msg)) << msg;

  std::uint64_t mark = emitted();
  d->sim_camera(1)->unplug();
  ASSERT_TRUE(wait_for([&] { return emitted() >= mark + 40; }, 60));
  EXPECT_EQ(d->state(), protocol::State::kDegradedSingleSensor);
  mark = emitted();
  d->sim_camera(1)->replug();
  ASSERT_TRUE(wait_for([&] { return emitted() >= mark + 60; }, 60));
  EXPECT_NE(d->state(), protocol::State::kDegradedSingleSensor);
  const auto t_stop = std::chrono::steady_clock::now();
  d->request_stop();
  t.join();
  const double stop_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_stop).count();
  EXPECT_EQ(rc, 0);
  EXPECT_LT(stop_s, 1.0) << "clean stop within 1 s";

  test::BusEvents b;
  ASSERT_TRUE(b.feed_log(read_all(log)));
  EXPECT_EQ(b.undecodable, 0u);
  EXPECT_EQ(b.reassembly.counter_gaps, 0u);
  EXPECT_EQ(b.reassembly.incomplete, 0u);
  EXPECT_EQ(b.reassembly.crc_errors, 0u);
  ASSERT_GE(b.cycles.size(), 160u);
  // Cycles are frame instants of the 120 Hz grid, strictly increasing, also across the unplug and
  // the replug (after the replug the right sensor's backlog is dropped as late until it catches
  // up, and the left carries every instant meanwhile).
  const double period_us = 1e6 / 120.0;
  for (std::size_t i = 1; i < b.cycles.size(); ++i) {
    const double k =
        static_cast<double>(b.cycles[i].timestamp_us - b.cycles[0].timestamp_us) / period_us;
    ASSERT_GT(b.cycles[i].timestamp_us, b.cycles[i - 1].timestamp_us) << "cycle " << i;
    ASSERT_NEAR(k, std::round(k), 2.0 / period_us) << "cycle " << i << " is off the frame grid";
  }
  // Degraded within 3 frame periods: sample time from the last frame pair (the unplugged sensor's
  // last frame) to the sample at which the state became DEGRADED. (The bus alone cannot tell: a
  // cycle is also flagged single-sensor when only one pad has contact.)
  //
  // The bound holds where the loop keeps up with 120 Hz (the optimised build, also under qemu).
  // The ASan+UBSan build's loop manages only ~20-30 cycles/s on 2 cores (test_run.cpp): the
  // capture rings overflow, so the processed sample time jumps over dropped frames and "3 frame
  // periods of sample time" stops meaning 3 periods of the sensor's stream (CI saw 308 ms once,
  // passing in the runs before). There the check is only that DEGRADED came within 1 s.
#if defined(__SANITIZE_ADDRESS__)
  constexpr std::int64_t kMaxDegradedLagNs = 1'000'000'000;
#else
  constexpr std::int64_t kMaxDegradedLagNs = 3 * 8'333'334;
#endif
  const std::int64_t lag = d->summary().engine.degraded_after_pair_ns;
  EXPECT_GE(lag, 0);
  EXPECT_LE(lag, kMaxDegradedLagNs) << "degraded " << lag << " ns of frames after the unplug";
  bool degraded_seen = false, dual_again = false, recovered_status = false;
  for (const auto& ev : b.order) {
    if (ev.kind == test::BusEvents::Event::kCycle) {
      const bool single = b.cycles[ev.index].single_sensor;
      if (degraded_seen && !single) {
        dual_again = true;
      }
    } else if (ev.kind == test::BusEvents::Event::kStatus) {
      const auto& s = b.statuses[ev.index];
      if (!degraded_seen && s.state == protocol::State::kDegradedSingleSensor) {
        degraded_seen = true;
        EXPECT_EQ(s.health_right, protocol::SensorHealth::kLost);
        EXPECT_EQ(s.health_left, protocol::SensorHealth::kOk);
      } else if (dual_again && s.state != protocol::State::kDegradedSingleSensor &&
                 s.health_right == protocol::SensorHealth::kOk) {
        recovered_status = true;
      }
    }
  }
  EXPECT_TRUE(degraded_seen);
  EXPECT_TRUE(dual_again);
  EXPECT_TRUE(recovered_status);
  // StatusTiming carries the DSP time (latency needs paced frames: bench/latency).
  ASSERT_FALSE(b.timings.empty());
  EXPECT_GT(b.timings.back().dsp_time_s, 0.0);
  EXPECT_GT(d->summary().engine.pairs, 200u);
  fs::remove_all(dir);
}
