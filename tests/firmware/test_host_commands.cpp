// SPDX-License-Identifier: Apache-2.0
// firmware tests: commands on a host without CAN. tacse3d --board sim --can-socket PATH, a
// monitor on the socket decoding the stream, and tacse3-ctl --socket PATH sending tare, reset
// pose, finger separation and queries: the ACKs, the pose reset in the stream, the new
// separation read back; bad input from a peer that then vanishes, said once, the daemon going on.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>

#include "bus_events.hpp"
#include "run_cmd.hpp"
#include "tacse3/hal/can/unix_channel.hpp"
#if TACSE3_HAVE_RECORDER
#include "tacse3/recording/recording.hpp"
#endif

namespace fs = std::filesystem;
using namespace tacse3;

namespace {

using tacse3::test::read_all;
using tacse3::test::run_cmd;
using tacse3::test::RunResult;

double angle_deg(const protocol::Quaternion& q) {
  return Eigen::Quaterniond(q.w, q.x, q.y, q.z)
             .normalized()
             .angularDistance(Eigen::Quaterniond::Identity()) *
         180.0 / M_PI;
}

bool wait_for(const std::function<bool()>& cond, double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    if (cond()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return cond();
}

// The stream as a controller on the socket sees it.
class Monitor {
 public:
  explicit Monitor(std::unique_ptr<hal::can::UnixSocketChannel> ch) : ch_(std::move(ch)) {
    thread_ = std::thread([this] {
      while (!stop_.load()) {
        hal::can::RxFrame f;
        if (ch_->receive(f, 20) != hal::can::RxResult::kFrame) continue;
        const std::lock_guard<std::mutex> lock(mutex_);
        bus_.feed(f.frame);
      }
    });
  }
  ~Monitor() {
    stop_.store(true);
    thread_.join();
  }
  template <typename F>
  auto with(F f) {
    const std::lock_guard<std::mutex> lock(mutex_);
    return f(bus_);
  }

 private:
  std::unique_ptr<hal::can::UnixSocketChannel> ch_;
  std::mutex mutex_;
  test::BusEvents bus_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

class HostCommands : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tacse3-fw-hostcmd-" + std::to_string(getpid()));
    fs::create_directories(dir_);
    sock_ = (dir_ / "can.sock").string();
    // The sim board, looping, with stale/lost raised: on a shared machine a starved capture
    // thread must not turn the run into a single-sensor one (tests/firmware/test_health.cpp
    // covers those thresholds).
    std::string text = read_all(fs::path(TACSE3_SOURCE_BOARDS_DIR) / "sim/board.toml");
    text.replace(text.find("repeat = false"), 14, "repeat = true");
    text.replace(text.find("stale_ms = 50"), 13, "stale_ms = 1000");
    text.replace(text.find("lost_ms = 500"), 13, "lost_ms = 2000");
    // Where START_RECORDING writes.
    fs::create_directories(dir_ / "recordings");
    text += "\n[record]\ndir = \"" + (dir_ / "recordings").string() + "\"\n";
    std::ofstream(dir_ / "board.toml") << text;
    log_ = dir_ / "tacse3d.err";
    pid_ = fork();
    if (pid_ == 0) {
      std::FILE* err = std::freopen(log_.c_str(), "w", stderr);
      (void)err;
      const std::string board = (dir_ / "board.toml").string();
      execl(TACSE3D_BIN, TACSE3D_BIN, "--board", board.c_str(), "--calibration",
            TACSE3_SIM_CALIBRATION, "--can-socket", sock_.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    ASSERT_GT(pid_, 0);
  }
  void TearDown() override {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    fs::remove_all(dir_);
  }
  // SIGTERM, then the exit status.
  int stop_daemon() {
    kill(pid_, SIGTERM);
    int st = 0;
    waitpid(pid_, &st, 0);
    pid_ = -1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  }
  std::unique_ptr<hal::can::UnixSocketChannel> connect() {
    std::unique_ptr<hal::can::UnixSocketChannel> ch;
    std::string e;
    wait_for([&] { return (ch = hal::can::UnixSocketChannel::connect(sock_, e)) != nullptr; }, 60);
    return ch;
  }
  RunResult ctl(const std::string& args) {
    return run_cmd(std::string(TACSE3_CTL_BIN) + " --socket " + sock_ +
                   " --node 1 --timeout-ms 5000 " + args + " 2>&1");
  }

  fs::path dir_;
  fs::path log_;
  std::string sock_;
  pid_t pid_ = -1;
};

}  // namespace

TEST_F(HostCommands, CtlTaresResetsSetsAndQueriesASimDaemon) {
  auto ch = connect();
  ASSERT_NE(ch, nullptr) << read_all(log_);
  Monitor mon(std::move(ch));
  // Past the grasp and into the 30 degree turn.
  const auto max_angle = [&] {
    return mon.with([](test::BusEvents& b) {
      double m = 0.0;
      for (const auto& c : b.cycles) m = std::max(m, angle_deg(c.orientation));
      return m;
    });
  };
  ASSERT_TRUE(wait_for([&] { return max_angle() > 10.0; }, 120))
      << "no turn in the stream: " << max_angle() << " deg\n"
      << read_all(log_);

  // Reset while the pose is turned (the scenario loops, so try again if the moment was missed):
  // the first cycle after the command carries the reset flag and starts from identity: it holds
  // only the motion since the cycle before.
  const auto last_angle = [&] {
    return mon.with([](test::BusEvents& b) {
      return b.cycles.empty() ? 0.0 : angle_deg(b.cycles.back().orientation);
    });
  };
  bool reset_seen = false;
  for (int attempt = 0; attempt < 5 && !reset_seen; ++attempt) {
    ASSERT_TRUE(wait_for([&] { return last_angle() > 10.0; }, 60)) << read_all(log_);
    const std::size_t before = mon.with([](test::BusEvents& b) { return b.cycles.size(); });
    const int seq = 1 + attempt;
    const RunResult reset = ctl("--seq " + std::to_string(seq) + " reset-pose");
    ASSERT_EQ(reset.status, 0) << reset.out;
    EXPECT_EQ(reset.out, "node 1: RESET_POSE acknowledged (seq " + std::to_string(seq) + ")\n");
    std::size_t at = 0;
    ASSERT_TRUE(wait_for(
        [&] {
          return mon.with([&](test::BusEvents& b) {
            for (std::size_t i = before; i < b.cycles.size(); ++i) {
              if (b.cycles[i].pose_reset) {
                at = i;
                return true;
              }
            }
            return false;
          });
        },
        30));
    mon.with([&](test::BusEvents& b) {
      if (angle_deg(b.cycles[at - 1].orientation) < 5.0) return 0;  // the turn was over: again
      reset_seen = true;
      // What the object turned between the two cycles, from the sent angular rate (a loaded
      // machine may skip frames, so the gap can be several frame periods), with 0.5 deg for
      // the rate's own change and quantisation.
      const protocol::Cycle& c = b.cycles[at];
      const double dt_s =
          static_cast<double>(c.timestamp_us - b.cycles[at - 1].timestamp_us) * 1e-6;
      const double rate = std::sqrt(c.angular.x * c.angular.x + c.angular.y * c.angular.y +
                                    c.angular.z * c.angular.z);
      const double bound = rate * dt_s * 180.0 / M_PI * 1.5 + 0.5;
      EXPECT_LT(angle_deg(c.orientation), bound) << "dt " << dt_s << " s, rate " << rate;
      EXPECT_LT(angle_deg(c.orientation), 0.5 * angle_deg(b.cycles[at - 1].orientation));
      return 0;
    });
  }
  EXPECT_TRUE(reset_seen) << "never caught the pose turned";

  // The ACK went out on the socket too, where every peer hears it.
  EXPECT_TRUE(wait_for(
      [&] {
        return mon.with([](test::BusEvents& b) {
          for (const auto& a : b.acks)
            if (a.command == protocol::CommandCode::kResetPose) return true;
          return false;
        });
      },
      5));

  const RunResult tare = ctl("--seq 7 tare");
  EXPECT_EQ(tare.status, 0) << tare.out;
  EXPECT_EQ(tare.out, "node 1: TARE acknowledged (seq 7)\n");
  const RunResult sep = ctl("--seq 8 finger-separation 0.085");
  EXPECT_EQ(sep.status, 0) << sep.out;
  const RunResult q = ctl("--seq 9 query finger-separation");
  EXPECT_EQ(q.status, 0) << q.out;
  EXPECT_EQ(q.out, "node 1: QUERY finger separation 0.08500 m (seq 9)\n");
  const RunResult s = ctl("--seq 10 query stream");
  EXPECT_EQ(s.status, 0) << s.out;
  EXPECT_NE(s.out.find("stream enabled, rate divider 1 (120.0 Hz)"), std::string::npos) << s.out;
  // A node id the daemon does not have: no ACK (exit 4), and the message says what to check.
  const RunResult nack = run_cmd(std::string(TACSE3_CTL_BIN) + " --socket " + sock_ +
                                 " --node 2 --timeout-ms 300 --seq 11 tare 2>&1");
  EXPECT_EQ(nack.status, 4) << nack.out;
  EXPECT_NE(nack.out.find("does that tacse3d use node id 2?"), std::string::npos) << nack.out;

  EXPECT_EQ(stop_daemon(), 0) << read_all(log_);
  EXPECT_FALSE(fs::exists(sock_)) << "the socket file outlived the daemon";
}

#if TACSE3_HAVE_RECORDER
// A calibration session without a shell on the board: the controller sets the separation, starts
// recording N, lets it run, stops it; the recording holds the frames and the separation it set.
TEST_F(HostCommands, CtlStartsAndStopsARecordingWithTheLiveSeparation) {
  auto ch = connect();
  ASSERT_NE(ch, nullptr) << read_all(log_);
  Monitor mon(std::move(ch));
  const auto cycles = [&] { return mon.with([](test::BusEvents& b) { return b.cycles.size(); }); };
  ASSERT_TRUE(wait_for([&] { return cycles() > 10; }, 120)) << read_all(log_);
  const fs::path root = dir_ / "recordings";

  RunResult r = ctl("--seq 1 record-stop");
  EXPECT_EQ(r.status, 3) << r.out;
  EXPECT_NE(r.out.find("rejected STOP_RECORDING: NOT_RECORDING (10, seq 1)"), std::string::npos)
      << r.out;
  // An existing recording number is refused and left as it was.
  fs::create_directories(root / "rec-00002");
  std::ofstream(root / "rec-00002" / "keep.txt") << "mine\n";
  r = ctl("--seq 2 record-start 2");
  EXPECT_EQ(r.status, 3) << r.out;
  EXPECT_NE(r.out.find("RECORDING_EXISTS (12, seq 2)"), std::string::npos) << r.out;
  EXPECT_EQ(read_all(root / "rec-00002" / "keep.txt"), "mine\n");
  EXPECT_EQ(std::distance(fs::directory_iterator(root / "rec-00002"), fs::directory_iterator()), 1);

  // The rig block takes the separation the controller set, not the board file's 40 mm.
  r = ctl("--seq 3 finger-separation 0.0625");
  ASSERT_EQ(r.status, 0) << r.out;
  r = ctl("--seq 4 record-start 7");
  ASSERT_EQ(r.status, 0) << r.out << read_all(log_);
  EXPECT_EQ(r.out, "node 1: START_RECORDING acknowledged: recording rec-00007 (seq 4)\n");
  r = ctl("--seq 5 record-start 8");
  EXPECT_EQ(r.status, 3) << r.out;
  EXPECT_NE(r.out.find("ALREADY_RECORDING (9, seq 5)"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(root / "rec-00008"));
  const std::size_t at_start = cycles();
  ASSERT_TRUE(wait_for([&] { return cycles() > at_start + 60; }, 120)) << read_all(log_);
  r = ctl("--seq 6 record-stop");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(r.out, "node 1: STOP_RECORDING acknowledged (seq 6)\n");
  // Closed by the housekeeping thread, which then says how much it wrote.
  const std::string done = "recording " + (root / "rec-00007").string() + ": ";
  ASSERT_TRUE(wait_for([&] { return read_all(log_).find(done) != std::string::npos; }, 30))
      << read_all(log_);
  r = ctl("--seq 7 record-stop");
  EXPECT_EQ(r.status, 3) << r.out;

  auto reader = recording::RecordingReader::open(root / "rec-00007");
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  const recording::RecordingReader& rd = reader.value();
  // Every instant processed while recording is in it, dropped (a full ring on a loaded machine)
  // or skipped for a pad missing at that instant; the daemon's count is the reader's.
  const std::string log = read_all(log_);
  unsigned long long written = 0, dropped = 0, incomplete = 0;
  const std::size_t at = log.find(done);
  ASSERT_EQ(std::sscanf(log.c_str() + at + done.size(),
                        "%llu frames written, %llu dropped (ring full), %llu instants", &written,
                        &dropped, &incomplete),
            3)
      << log;
  EXPECT_EQ(rd.frame_count(), written);
  EXPECT_GE(written, 1u);
  EXPECT_GE(written + dropped + incomplete, 60u) << "60 cycles ran while recording\n" << log;
  EXPECT_EQ(rd.sensor_count(), 2u);
  EXPECT_DOUBLE_EQ(rd.info().rig.finger_separation_mm, 62.5);
  EXPECT_GT(rd.info().rig.pixel_pitch_mm, 0.0);
  recording::Image img;
  EXPECT_TRUE(rd.read_image(0, 0, &img).ok());

  EXPECT_EQ(stop_daemon(), 0) << read_all(log_);
}
#endif

TEST_F(HostCommands, BadInputFromAPeerThatVanishesIsSaidOnceAndHarmsNothing) {
  auto ch = connect();
  ASSERT_NE(ch, nullptr) << read_all(log_);
  // Garbage, an oversized line, then gone mid-line, three times over.
  const std::string junk = "garbage\n" + std::string(10000, 'A') + "\n(1.0) can0 03";
  for (int round = 0; round < 3; ++round) {
    const int fd = socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::snprintf(a.sun_path, sizeof a.sun_path, "%s", sock_.c_str());
    ASSERT_EQ(::connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a), 0);
    ASSERT_EQ(write(fd, junk.data(), junk.size()), static_cast<ssize_t>(junk.size()));
    close(fd);
  }
  // The daemon still answers.
  const RunResult q = ctl("--seq 2 query protocol-version");
  EXPECT_EQ(q.status, 0) << q.out << read_all(log_);
  EXPECT_EQ(q.out, "node 1: QUERY protocol version 1.1.0 (seq 2)\n");
  ch.reset();
  EXPECT_EQ(stop_daemon(), 0) << read_all(log_);
  const std::string err = read_all(log_);
  const std::string said =
      "ignoring input lines that are not candump -L (counted; first: \"garbage\")";
  const std::size_t at = err.find(said);
  ASSERT_NE(at, std::string::npos) << err;
  EXPECT_EQ(err.find(said, at + 1), std::string::npos) << "said more than once:\n" << err;
  EXPECT_NE(err.find("CAN socket: 6 bad input line(s) ignored (3 longer than 255 characters)"),
            std::string::npos)
      << err;
}
