// SPDX-License-Identifier: Apache-2.0
// tacse3-truth on a simulated rig, end to end: recordings rendered by the simulator, a robot log
// made from each truth (random world pose, TCP offset, 125 Hz with jitter, a clock offset of
// several seconds, arm-level pose noise), truth.csv deleted and rebuilt by the program.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "tacse3/protocol/protocol.hpp"
#include "tacse3/tools/bench.hpp"
#include "tacse3/tools/can_log.hpp"
#include "tacse3/tools/metrics.hpp"
#include "tacse3/tools/replay.hpp"
#include "tacse3/tools/source.hpp"
#include "tacse3/tools/truth/pose_log.hpp"
#include "truth_rig.hpp"

namespace {

namespace fs = std::filesystem;
namespace tt = tacse3::tools;
namespace tr = tacse3::tools::truth;
namespace rec = tacse3::recording;
namespace dsp = tacse3::dsp;
namespace proto = tacse3::protocol;
using tacse3::tools::truth_test::RigLog;

// The clock offset of every generated log: robot time = recording time + kOffset.
constexpr std::int64_t kOffsetNs = 6'437'251'000;

class TruthSim : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("tacse3_test_truth_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    for (const auto& c : tacse3::tools::truth_test::cases()) {
      const fs::path d = dir_ / c.motion;
      const std::string e = tt::write_case_recording(c, d, 1);
      ASSERT_TRUE(e.empty()) << e;
      std::string err;
      auto src = tt::RecordingSource::open(d, &err);
      ASSERT_TRUE(src) << err;
      truth_.push_back(src->info().truth);
      t_ns_.push_back(src->info().t_ns);
      fs::remove(d / "truth.csv");
    }
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static fs::path dir_;
  static std::vector<std::vector<rec::TruthSample>> truth_;
  static std::vector<std::vector<std::int64_t>> t_ns_;
};
fs::path TruthSim::dir_;
std::vector<std::vector<rec::TruthSample>> TruthSim::truth_;
std::vector<std::vector<std::int64_t>> TruthSim::t_ns_;

struct ToolRun {
  int rc = -1;
  std::string out;
};

ToolRun run_tool(const std::string& args) {
  const std::string cmd = std::string(TACSE3_TRUTH_BIN) + " " + args + " 2>&1";
  ToolRun r;
  std::FILE* p = ::popen(cmd.c_str(), "r");
  if (p == nullptr) return r;
  char buf[512];
  while (std::fgets(buf, sizeof(buf), p) != nullptr) r.out += buf;
  const int status = ::pclose(p);
  r.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// The offset the program printed ("clock offset S s").
double printed_offset(const std::string& out) {
  const std::size_t k = out.find("clock offset ");
  if (k == std::string::npos) return std::nan("");
  return std::stod(out.substr(k + 13));
}

// How far the rebuilt truth is from the simulator's, over the frames.
struct Difference {
  double max_deg = 1e9, max_mm = 1e9;
  double rms_deg = 1e9, rms_mm = 1e9;
};

Difference truth_difference(const fs::path& rec_dir,
                            const std::vector<rec::TruthSample>& original) {
  std::string err;
  auto src = tt::RecordingSource::open(rec_dir, &err);
  EXPECT_TRUE(src) << err;
  Difference d;
  if (!src) return d;
  const auto& rebuilt = src->info().truth;
  EXPECT_EQ(rebuilt.size(), original.size());
  d = Difference{0, 0, 0, 0};
  for (std::size_t i = 0; i < rebuilt.size() && i < original.size(); ++i) {
    EXPECT_EQ(rebuilt[i].t_ns, original[i].t_ns);
    const dsp::Pose a = tt::to_pose(rebuilt[i]), b = tt::to_pose(original[i]);
    const double deg = tt::rotation_error_deg(a.q, b.q), mm = (a.p - b.p).norm() * 1e3;
    d.max_deg = std::max(d.max_deg, deg);
    d.max_mm = std::max(d.max_mm, mm);
    d.rms_deg += deg * deg;
    d.rms_mm += mm * mm;
  }
  d.rms_deg = std::sqrt(d.rms_deg / static_cast<double>(rebuilt.size()));
  d.rms_mm = std::sqrt(d.rms_mm / static_cast<double>(rebuilt.size()));
  std::printf(
      "%s: rebuilt truth: rotation max %.4f deg, RMS %.4f deg; translation max %.4f mm, "
      "RMS %.4f mm\n",
      rec_dir.filename().c_str(), d.max_deg, d.rms_deg, d.max_mm, d.rms_mm);
  return d;
}

// Each row is the difference of two logged poses (now and at the first frame), each with the
// arm's noise: RMS sqrt(2) x 0.05 mm from the positions, plus the orientation noise times the
// 0.16 m TCP lever. The rotation stays within 0.05 deg at every frame.
void expect_close(const Difference& d) {
  EXPECT_LT(d.max_deg, 0.05);
  EXPECT_LT(d.rms_deg, 0.025);
  EXPECT_LT(d.rms_mm, 0.08);
}

TEST_F(TruthSim, NoiselessLogRebuildsTheTruthExactly) {
  RigLog rig(7, 0.0);
  const fs::path log = dir_ / "rz-exact.csv";
  ASSERT_EQ(rig.write_gripper_log(truth_[0], t_ns_[0], kOffsetNs, log, false), "");
  const ToolRun r =
      run_tool("--recording " + (dir_ / "rz").string() + " --gripper-log " + log.string() +
               " --tcp-to-grasp \"" + rig.tcp_to_grasp_text() + "\" --clock-offset 6.437251");
  ASSERT_EQ(r.rc, 0) << r.out;
  // What is left is slerp of the 125 Hz log between the simulator's 120 Hz truth samples.
  const Difference d = truth_difference(dir_ / "rz", truth_[0]);
  EXPECT_LT(d.max_deg, 0.002);
  EXPECT_LT(d.max_mm, 0.001);
  fs::remove(dir_ / "rz" / "truth.csv");
}

// A board file holding `tcp_to_grasp_line` under [rig] (empty: no [rig] table).
fs::path write_board(const fs::path& file, const std::string& tcp_to_grasp_line) {
  std::ofstream o(file);
  o << "version = 1\n[sensors.left]\nbackend = \"sim\"\n";
  if (!tcp_to_grasp_line.empty()) o << "[rig]\ntcp_to_grasp = " << tcp_to_grasp_line << "\n";
  return file;
}

// "x y z qw qx qy qz" as a TOML array.
std::string toml_pose(std::string text) {
  for (std::size_t k = text.find(' '); k != std::string::npos; k = text.find(' ', k + 2)) {
    text.replace(k, 1, ", ");
  }
  return "[" + text + "]";
}

// --board's [rig] tcp_to_grasp stands in for --tcp-to-grasp, which wins when both are given; the
// summary says which was used. Noiseless log: the rebuilt truth is exact either way.
TEST_F(TruthSim, BoardFileGivesTheTcpToGrasp) {
  RigLog rig(7, 0.0);
  const fs::path log = dir_ / "rz-board.csv";
  ASSERT_EQ(rig.write_gripper_log(truth_[0], t_ns_[0], kOffsetNs, log, false), "");
  const fs::path good = write_board(dir_ / "good.toml", toml_pose(rig.tcp_to_grasp_text()));
  const fs::path other = write_board(dir_ / "other.toml", "[0, 0, 0.2, 1, 0, 0, 0]");
  const std::string args = "--recording " + (dir_ / "rz").string() + " --gripper-log " +
                           log.string() + " --clock-offset 6.437251";
  const ToolRun from_board = run_tool(args + " --board " + good.string());
  ASSERT_EQ(from_board.rc, 0) << from_board.out;
  EXPECT_NE(from_board.out.find("TCP to grasp from " + good.string() + " [rig] tcp_to_grasp"),
            std::string::npos)
      << from_board.out;
  Difference d = truth_difference(dir_ / "rz", truth_[0]);
  EXPECT_LT(d.max_deg, 0.002);
  EXPECT_LT(d.max_mm, 0.001);
  fs::remove(dir_ / "rz" / "truth.csv");
  const ToolRun both = run_tool(args + " --board " + other.string() + " --tcp-to-grasp \"" +
                                rig.tcp_to_grasp_text() + "\"");
  ASSERT_EQ(both.rc, 0) << both.out;
  EXPECT_NE(both.out.find("TCP to grasp from --tcp-to-grasp"), std::string::npos) << both.out;
  d = truth_difference(dir_ / "rz", truth_[0]);
  EXPECT_LT(d.max_deg, 0.002);
  EXPECT_LT(d.max_mm, 0.001);
  fs::remove(dir_ / "rz" / "truth.csv");
  // The other board's pose is not the rig's: the same run with it is off by centimetres.
  ASSERT_EQ(run_tool(args + " --board " + other.string()).rc, 0);
  d = truth_difference(dir_ / "rz", truth_[0]);
  EXPECT_GT(d.max_mm, 1.0);
  fs::remove(dir_ / "rz" / "truth.csv");
}

TEST_F(TruthSim, ExplicitOffsetRebuildsTheTruth) {
  for (std::size_t k = 0; k < truth_.size(); ++k) {
    const std::string name = tacse3::tools::truth_test::cases()[k].motion;
    RigLog rig(11 + k);
    const fs::path log = dir_ / (name + "-gripper.csv");
    ASSERT_EQ(rig.write_gripper_log(truth_[k], t_ns_[k], kOffsetNs, log, false), "");
    const fs::path out = dir_ / name / "truth.csv";
    const ToolRun r =
        run_tool("--recording " + (dir_ / name).string() + " --gripper-log " + log.string() +
                 " --tcp-to-grasp \"" + rig.tcp_to_grasp_text() + "\" --clock-offset 6.437251");
    ASSERT_EQ(r.rc, 0) << r.out;
    expect_close(truth_difference(dir_ / name, truth_[k]));
    fs::remove(out);
  }
}

std::string rec_arg(const fs::path& d) {
  return "--recording " + d.string();
}

TEST_F(TruthSim, RotationVectorLog) {
  RigLog rig(21);
  const fs::path log = dir_ / "rz-ur.csv";
  ASSERT_EQ(rig.write_gripper_log(truth_[0], t_ns_[0], kOffsetNs, log, true), "");
  const ToolRun r =
      run_tool(rec_arg(dir_ / "rz") + " --gripper-log " + log.string() + " --tcp-to-grasp \"" +
               rig.tcp_to_grasp_text() + "\" --clock-offset 6.437251");
  ASSERT_EQ(r.rc, 0) << r.out;
  expect_close(truth_difference(dir_ / "rz", truth_[0]));
  fs::remove(dir_ / "rz" / "truth.csv");
}

TEST_F(TruthSim, ObjectLogRig) {
  RigLog rig(31);
  const fs::path log = dir_ / "rx-object.csv", out = dir_ / "rx-truth.csv";
  ASSERT_EQ(rig.write_object_log(truth_[1], t_ns_[1], kOffsetNs, log), "");
  const ToolRun r =
      run_tool(rec_arg(dir_ / "rx") + " --object-log " + log.string() + " --gripper-pose \"" +
               rig.fixed_tcp_text() + "\" --tcp-to-grasp \"" + rig.tcp_to_grasp_text() +
               "\" --clock-offset 6.437251 --out " + out.string());
  ASSERT_EQ(r.rc, 0) << r.out;
  fs::copy_file(out, dir_ / "rx" / "truth.csv");
  expect_close(truth_difference(dir_ / "rx", truth_[1]));
  fs::remove(dir_ / "rx" / "truth.csv");
}

// The controller's candump -L log of the recording: tacse3-replay's frames (stamped with their
// sample time) arriving offset + latency + bus time later. Latency per cycle: 4 ms + an
// exponential tail (mean 0.7 ms, at most 3 ms); the StatusTiming frames report its median. Each
// frame of a cycle takes 0.13 ms on the bus (1 Mbit/s).
std::string write_controller_can_log(const fs::path& rec_dir, const fs::path& file) {
  std::string err;
  auto src = tt::RecordingSource::open(rec_dir, &err);
  if (!src) return err;
  const fs::path board = file.string() + ".board";
  tt::CanLogger can;
  if (err = can.open(board, dsp::FusionMethod::kJoint, tt::ProxyMode::kAuto); !err.empty()) {
    return err;
  }
  tt::ReplaySinks sinks;
  sinks.can = &can;
  const tt::ReplayRun run = tt::run_replay(*src, tt::ReplayOptions{}, sinks);
  if (!run.error.empty()) return run.error;
  if (err = can.close(); !err.empty()) return err;
  std::mt19937 rng(5);
  std::exponential_distribution<double> tail(1.0 / 0.7e-3);
  const double p50_s = 4e-3 + 0.7e-3 * std::log(2.0);
  std::ifstream in(board);
  std::string out, line;
  std::uint64_t group = ~0ull, base_us = 0;
  int in_group = 0;
  while (std::getline(in, line)) {
    proto::LogRecord r;
    if (proto::parse_candump_line(line, r) != proto::Status::kOk) return "bad board log line";
    if (r.time_us != group) {
      group = r.time_us;
      in_group = 0;
      const double latency_s = 4e-3 + std::min(tail(rng), 3e-3);
      base_us = r.time_us + static_cast<std::uint64_t>(kOffsetNs / 1000) +
                static_cast<std::uint64_t>(std::llround(latency_s * 1e6));
    }
    proto::Decoded d;
    if (proto::decode(r.frame, proto::IdLayout{}, d) == proto::Status::kOk) {
      if (auto* t = std::get_if<proto::TimingMsg>(&d.payload); t != nullptr) {
        t->latency_p50_s = p50_s;
        if (proto::encode(*t, proto::TxConfig{}, r.frame) != proto::Status::kOk) {
          return "cannot encode StatusTiming";
        }
      }
    }
    r.time_us = base_us + static_cast<std::uint64_t>(++in_group) * 130;
    char buf[proto::kCandumpLineMax + 2];
    const std::size_t n = proto::format_candump_line(r, buf, sizeof(buf));
    out += std::string(buf, n) + "\n";
  }
  fs::remove(board);
  return tacse3::fileio::write_file_atomically(file, out, &err) ? std::string() : err;
}

TEST_F(TruthSim, CanLogSyncRecoversTheOffsetWithinAMillisecond) {
  RigLog rig(41);
  const fs::path log = dir_ / "rz-can-gripper.csv", can = dir_ / "rz-controller.log";
  ASSERT_EQ(rig.write_gripper_log(truth_[0], t_ns_[0], kOffsetNs, log, false), "");
  ASSERT_EQ(write_controller_can_log(dir_ / "rz", can), "");
  const ToolRun r = run_tool(rec_arg(dir_ / "rz") + " --gripper-log " + log.string() +
                             " --tcp-to-grasp \"" + rig.tcp_to_grasp_text() + "\" --can-log " +
                             can.string() + " --out " + (dir_ / "rz-can-truth.csv").string());
  ASSERT_EQ(r.rc, 0) << r.out;
  const double err_ms = (printed_offset(r.out) - static_cast<double>(kOffsetNs) * 1e-9) * 1e3;
  std::printf("CAN-log sync: offset error %.3f ms\n%s", err_ms, r.out.c_str());
  EXPECT_LT(std::abs(err_ms), 1.0);
  EXPECT_NE(r.out.find("median LatencyP50 of the StatusTiming frames"), std::string::npos);
}

TEST_F(TruthSim, AutoSyncRecoversTheOffsetWithinFiveMilliseconds) {
  for (std::size_t k = 0; k < truth_.size(); ++k) {
    const std::string name = tacse3::tools::truth_test::cases()[k].motion;
    RigLog rig(51 + k);
    const fs::path log = dir_ / (name + "-auto-gripper.csv");
    ASSERT_EQ(rig.write_gripper_log(truth_[k], t_ns_[k], kOffsetNs, log, false), "");
    const ToolRun r =
        run_tool(rec_arg(dir_ / name) + " --gripper-log " + log.string() + " --tcp-to-grasp \"" +
                 rig.tcp_to_grasp_text() + "\" --clock-offset auto --out " +
                 (dir_ / (name + "-auto-truth.csv")).string());
    ASSERT_EQ(r.rc, 0) << r.out;
    const double err_ms = (printed_offset(r.out) - static_cast<double>(kOffsetNs) * 1e-9) * 1e3;
    std::printf("%s: auto sync: offset error %.3f ms\n%s", name.c_str(), err_ms, r.out.c_str());
    EXPECT_LT(std::abs(err_ms), 5.0);
  }
}

// Every refusal exits non-zero with the file or option named, and writes no truth.csv.
void expect_refused(const fs::path& rec_dir, const std::string& args, int rc,
                    const std::string& message) {
  const ToolRun r = run_tool(rec_arg(rec_dir) + " " + args);
  EXPECT_EQ(r.rc, rc) << args << "\n" << r.out;
  EXPECT_NE(r.out.find(message), std::string::npos) << args << "\n" << r.out;
  EXPECT_FALSE(fs::exists(rec_dir / "truth.csv")) << args;
}

TEST_F(TruthSim, BadInputIsRefusedAndWritesNothing) {
  const fs::path d = dir_ / "rz";
  RigLog rig(61);
  const fs::path good = dir_ / "bad-good.csv";
  ASSERT_EQ(rig.write_gripper_log(truth_[0], t_ns_[0], kOffsetNs, good, false), "");
  const std::string g = " --gripper-log " + good.string();
  // The log does not cover the recording at this offset.
  expect_refused(d, g + " --clock-offset 100", 1, good.string() + ": covers log time");
  // Not monotonic, not unit.
  std::ifstream in(good);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  const fs::path swapped = dir_ / "bad-swapped.csv", scaled = dir_ / "bad-scaled.csv";
  {
    std::ofstream o(swapped);
    for (std::size_t i = 0; i < lines.size(); ++i)
      o << lines[i == 5 ? 6 : (i == 6 ? 5 : i)] << "\n";
    std::ofstream o2(scaled);
    o2 << lines[0] << "\n" << lines[1] << "\n";
    o2 << "100.5,0.4,0.1,0.2,0.9,0.0,0.0,0.0\n";
  }
  expect_refused(d, " --gripper-log " + swapped.string() + " --clock-offset 6.437251", 1,
                 swapped.string() + " line 7: time");
  expect_refused(d, " --gripper-log " + scaled.string() + " --clock-offset 6.437251", 1,
                 scaled.string() + " line 3: quaternion is not unit (norm 0.900000)");
  // A still robot: nothing for auto to sync on.
  RigLog still(62);
  const fs::path quiet = dir_ / "bad-still.csv";
  ASSERT_EQ(still.write_gripper_log({rec::TruthSample{}}, t_ns_[0], kOffsetNs, quiet, false), "");
  expect_refused(d, " --gripper-log " + quiet.string() + " --clock-offset auto", 1,
                 quiet.string() + ": too little rotation to sync on");
  // Usage errors.
  expect_refused(d, " --clock-offset 0", 2, "give --gripper-log FILE");
  expect_refused(d, g, 2, "no clock sync");
  expect_refused(d, g + " --clock-offset 0 --can-log x.log", 2, "give one");
  expect_refused(d, g + " --clock-offset soon", 2, "--clock-offset: expected seconds or auto");
  expect_refused(d, g + " --clock-offset 0 --tcp-to-grasp \"0 0 0 1 0 0\"", 2, "--tcp-to-grasp");
  // A board file whose [rig] tcp_to_grasp is not a pose, or that has none.
  const fs::path bad = write_board(dir_ / "bad-board.toml", "[0, 0, 0.16, 0.9, 0, 0, 0]");
  expect_refused(d, g + " --clock-offset 6.437251 --board " + bad.string(), 1,
                 bad.string() +
                     ":5: key \"rig.tcp_to_grasp\" quaternion (qw, qx, qy, qz) is not "
                     "unit (norm 0.9");
  const fs::path none = write_board(dir_ / "none-board.toml", "");
  expect_refused(d, g + " --clock-offset 6.437251 --board " + none.string(), 1,
                 none.string() + ": no key \"rig.tcp_to_grasp\"");
  // An existing output is kept.
  const fs::path existing = dir_ / "bad-existing.csv";
  { std::ofstream(existing) << "keep\n"; }
  expect_refused(d, g + " --clock-offset 6.437251 --out " + existing.string(), 1,
                 existing.string() + ": exists; give --force to replace it");
  std::ifstream kept(existing);
  std::string first;
  std::getline(kept, first);
  EXPECT_EQ(first, "keep");
}

}  // namespace
