// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: the replay engine on a tiny simulated recording: truth, CSV, fields, CAN, errors.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "tacse3/protocol/protocol.hpp"
#include "tacse3/tools/bench.hpp"
#include "tacse3/tools/can_log.hpp"
#include "tacse3/tools/field_dump.hpp"
#include "tacse3/tools/npy.hpp"
#include "tacse3/tools/replay.hpp"
#include "tacse3/tools/source.hpp"

namespace {

namespace fs = std::filesystem;
namespace tt = tacse3::tools;
namespace dsp = tacse3::dsp;
namespace rec = tacse3::recording;

// A short stick-regime grasp: sphere, 3 degrees about z (≈ 1 s, 126 frame pairs, grey).
tt::SimCase tiny_case() {
  tt::SimCase c;
  c.object = "sphere";
  c.motion = "rz";
  c.magnitude = 3.0;
  c.approach_s = 0.05;
  c.grasp_s = 0.25;
  c.settle_s = 0.05;
  c.hold_s = 0.15;
  return c;
}

class ReplayTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("tacse3_test_replay_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const std::string e = tt::write_case_recording(tiny_case(), dir_ / "rec", 1);
    ASSERT_TRUE(e.empty()) << e;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static fs::path dir_;
};
fs::path ReplayTest::dir_;

std::vector<std::string> lines_of(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

TEST_F(ReplayTest, DisplacementProxyFollowsTheStickRotation) {
  std::string err;
  auto src = tt::RecordingSource::open(dir_ / "rec", &err);
  ASSERT_TRUE(src) << err;
  ASSERT_TRUE(src->info().has_truth());
  tt::ReplayOptions o;
  o.mode = tt::ProxyMode::kDisplacement;
  const tt::ReplayRun run = tt::run_replay(*src, o, {});
  ASSERT_TRUE(run.error.empty()) << run.error;
  ASSERT_EQ(run.frames.size(), src->info().frame_count());
  const tt::RunSummary s = tt::summarize(src->info(), run.frames, o.sensors);
  ASSERT_TRUE(s.has_truth);
  EXPECT_NEAR(s.errors.true_rotation_deg, 3.0, 1e-9);
  // Uncalibrated defaults, exact-kinematics proxy: the rotation about z is seen with the right
  // sign and the right order of size (the calibrated accuracy is tests/tools/test_accuracy.cpp).
  EXPECT_GT(s.errors.final_rotation_vector_deg.z(), 1.0);
  EXPECT_LT(s.errors.final_rotation_vector_deg.z(), 9.0);
  EXPECT_LT(s.errors.final_rotation_error_deg, 6.0);
  EXPECT_LT(s.errors.final_translation_error_mm, 2.0);
  EXPECT_GT(s.valid_fraction, 0.3);
  // The summary's confidence: the frames with a valid estimate at or above the threshold, and
  // their median (tests/tools/test_confidence.cpp checks the values themselves).
  std::vector<double> conf;
  std::size_t confident = 0;
  for (const auto& f : run.frames) {
    if (!f.estimate_valid) continue;
    conf.push_back(f.confidence);
    confident += f.confidence >= dsp::kConfidenceThreshold ? 1 : 0;
  }
  ASSERT_FALSE(conf.empty());
  std::sort(conf.begin(), conf.end());
  EXPECT_DOUBLE_EQ(s.confident_fraction, static_cast<double>(confident) / run.frames.size());
  EXPECT_DOUBLE_EQ(s.confidence_median, conf[conf.size() / 2]);
  EXPECT_GT(s.confident_fraction, 0.0);
  // Nothing before contact: the first rows are exactly at rest.
  EXPECT_EQ(run.frames.front().twist.norm(), 0.0);
  EXPECT_FALSE(run.frames.front().valid[0]);
}

TEST_F(ReplayTest, CsvHasTheDocumentedHeaderAndOneRowPerFrame) {
  std::string err;
  auto src = tt::RecordingSource::open(dir_ / "rec", &err);
  ASSERT_TRUE(src) << err;
  const fs::path csv = dir_ / "out.csv";
  std::FILE* f = std::fopen(csv.c_str(), "w");
  ASSERT_NE(f, nullptr);
  tt::ReplaySinks sinks;
  sinks.csv = f;
  const tt::ReplayRun run = tt::run_replay(*src, tt::ReplayOptions{}, sinks);
  std::fclose(f);
  ASSERT_TRUE(run.error.empty()) << run.error;
  const auto lines = lines_of(csv);
  ASSERT_EQ(lines.size(), src->info().frame_count() + 1);
  EXPECT_EQ(lines[0], "t_ns,wx,wy,wz,vx,vy,vz,qw,qx,qy,qz,px,py,pz,valid_left,valid_right");
  for (std::size_t i = 1; i < lines.size(); ++i) {
    std::stringstream ss(lines[i]);
    std::vector<double> v;
    for (std::string cell; std::getline(ss, cell, ',');) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 16u) << lines[i];
    EXPECT_EQ(static_cast<std::int64_t>(v[0]), src->info().t_ns[i - 1]);
    EXPECT_NEAR(std::sqrt(v[7] * v[7] + v[8] * v[8] + v[9] * v[9] + v[10] * v[10]), 1.0, 1e-9);
    EXPECT_TRUE(v[14] == 0.0 || v[14] == 1.0);
    EXPECT_TRUE(v[15] == 0.0 || v[15] == 1.0);
  }
}

// Reads a .npy header: returns the dict text and the data offset.
std::string npy_dict(const fs::path& p, std::size_t* offset) {
  std::ifstream in(p, std::ios::binary);
  char pre[10];
  in.read(pre, 10);
  EXPECT_EQ(std::string(pre, 6), std::string("\x93NUMPY", 6));
  const std::size_t len = static_cast<unsigned char>(pre[8]) |
                          (static_cast<std::size_t>(static_cast<unsigned char>(pre[9])) << 8);
  std::string dict(len, '\0');
  in.read(dict.data(), static_cast<std::streamsize>(len));
  *offset = 10 + len;
  return dict;
}

TEST(Npy, HeaderIsAlignedAndDescribesTheShape) {
  const std::string h = tt::npy_header("<f4", {3, 30, 40, 2});
  EXPECT_EQ(h.size() % 64, 0u);
  EXPECT_NE(h.find("{'descr': '<f4', 'fortran_order': False, 'shape': (3, 30, 40, 2), }"),
            std::string::npos);
  EXPECT_EQ(h.back(), '\n');
  EXPECT_NE(tt::npy_header("<i8", {5}).find("'shape': (5,)"), std::string::npos);
}

TEST(Npy, WriterChecksTheRecordCount) {
  const fs::path p =
      fs::temp_directory_path() / ("tacse3_test_npy_" + std::to_string(::getpid()) + ".npy");
  tt::NpyWriter w;
  ASSERT_TRUE(w.open(p, "<f4", 4, 2, {3}).empty());
  const float rec[3] = {1.0f, 2.0f, 3.0f};
  ASSERT_TRUE(w.append(rec).empty());
  const std::string e = w.close();
  EXPECT_NE(e.find("1 records written, 2 declared"), std::string::npos) << e;
  EXPECT_EQ(fs::file_size(p), 128u + 12u);
  fs::remove(p);
}

TEST_F(ReplayTest, DumpFieldsWritesNumpyFilesWithTheDocumentedShapes) {
  std::string err;
  auto src = tt::RecordingSource::open(dir_ / "rec", &err);
  ASSERT_TRUE(src) << err;
  const auto n = static_cast<std::int64_t>(src->info().frame_count());
  tt::FieldDumper dump;
  const fs::path out = dir_ / "fields";
  ASSERT_TRUE(dump.open(out, n, {true, true}, 0.1).empty());
  tt::ReplaySinks sinks;
  sinks.dump = &dump;
  const tt::ReplayRun run = tt::run_replay(*src, tt::ReplayOptions{}, sinks);
  ASSERT_TRUE(run.error.empty()) << run.error;
  ASSERT_TRUE(dump.close().empty());
  ASSERT_TRUE(fs::exists(out / "index.json"));
  std::size_t off = 0;
  const std::string t = npy_dict(out / "t_ns.npy", &off);
  EXPECT_NE(t.find("'shape': (" + std::to_string(n) + ",)"), std::string::npos) << t;
  for (const auto& name : tt::FieldDumper::field_names()) {
    for (const char* s : {"left", "right"}) {
      const fs::path p = out / s / (name + ".npy");
      ASSERT_TRUE(fs::exists(p)) << p;
      const std::string d = npy_dict(p, &off);
      EXPECT_NE(d.find("'shape': (" + std::to_string(n) + ", 30, 40"), std::string::npos) << d;
    }
  }
  // The contact mask is 0/1 and not empty once the pads have closed; t_ns are the frame times.
  std::ifstream mask(out / "left" / "mask.npy", std::ios::binary);
  npy_dict(out / "left" / "mask.npy", &off);
  mask.seekg(static_cast<std::streamoff>(off));
  std::vector<char> m(static_cast<std::size_t>(n) * 1200);
  mask.read(m.data(), static_cast<std::streamsize>(m.size()));
  std::size_t ones = 0;
  for (char c : m) {
    ASSERT_TRUE(c == 0 || c == 1);
    ones += c == 1 ? 1 : 0;
  }
  EXPECT_GT(ones, 100u);
  std::ifstream tf(out / "t_ns.npy", std::ios::binary);
  npy_dict(out / "t_ns.npy", &off);
  tf.seekg(static_cast<std::streamoff>(off));
  std::vector<std::int64_t> times(static_cast<std::size_t>(n));
  tf.read(reinterpret_cast<char*>(times.data()), static_cast<std::streamsize>(n * 8));
  EXPECT_EQ(times, src->info().t_ns);
}

TEST_F(ReplayTest, CanLogDecodesBackToTheReplayedCycles) {
  ASSERT_TRUE(tt::can_log_available());
  std::string err;
  auto src = tt::RecordingSource::open(dir_ / "rec", &err);
  ASSERT_TRUE(src) << err;
  tt::CanLogger can;
  const fs::path log = dir_ / "can.log";
  ASSERT_TRUE(can.open(log, dsp::FusionMethod::kJoint, tt::ProxyMode::kAuto).empty());
  tt::ReplaySinks sinks;
  sinks.can = &can;
  const tt::ReplayRun run = tt::run_replay(*src, tt::ReplayOptions{}, sinks);
  ASSERT_TRUE(run.error.empty()) << run.error;
  ASSERT_TRUE(can.close().empty());
  namespace proto = tacse3::protocol;
  std::size_t cycles = 0, status = 0;
  for (const auto& line : lines_of(log)) {
    proto::LogRecord r;
    ASSERT_EQ(proto::parse_candump_line(line, r), proto::Status::kOk) << line;
    proto::Decoded d;
    ASSERT_EQ(proto::decode(r.frame, proto::IdLayout{}, d), proto::Status::kOk) << line;
    if (d.message == proto::MessageId::kStatus) ++status;
    if (d.message == proto::MessageId::kTimestamp) ++cycles;
    if (d.message == proto::MessageId::kTwistAngular) {
      const auto& a = std::get<proto::AngularMsg>(d.payload);
      const std::size_t i = cycles - 1;
      ASSERT_LT(i, run.frames.size());
      EXPECT_NEAR(a.angular.z, run.frames[i].twist[2], 1e-3) << "cycle " << i;
    }
  }
  EXPECT_EQ(cycles, run.frames.size());
  // 10 Hz periodic status over ≈ 0.9 s of recording, plus change-triggered ones (contact).
  EXPECT_GE(status, 9u);
  EXPECT_LE(status, 20u);
}

TEST_F(ReplayTest, SetupTakesPitchAndSeparationFromTheRig) {
  std::string err;
  auto src = tt::RecordingSource::open(dir_ / "rec", &err);
  ASSERT_TRUE(src) << err;
  tt::ReplayOptions o;
  o.calibration.sensor[0].pixel_pitch_m = 0.05e-3;
  o.calibration.sensor[0].c_velocity = 0.01;
  o.calibration.sensor[0].c_displacement = 1e-4;
  tt::EngineSetup s;
  ASSERT_TRUE(tt::make_setup(src->info(), o, &s).empty());
  EXPECT_DOUBLE_EQ(s.cal[0].pixel_pitch_m, 0.1e-3);
  EXPECT_DOUBLE_EQ(s.cal[0].c_velocity, 0.02);  // gains scale with the pitch (0.05 -> 0.1 mm)
  EXPECT_DOUBLE_EQ(s.cal[0].c_displacement, 2e-4);
  EXPECT_DOUBLE_EQ(s.dual.finger_separation_m, src->info().finger_separation_mm * 1e-3);
  EXPECT_NEAR(s.dual.nominal_frame_period_s, 1.0 / 120.0, 1e-6);
  EXPECT_EQ(s.cal[0].velocity_proxy, tt::pipeline_proxy(tt::ProxyMode::kAuto));
  EXPECT_TRUE(s.use[0] && s.use[1]);
  o.sensors = tt::SensorChoice::kRight;
  ASSERT_TRUE(tt::make_setup(src->info(), o, &s).empty());
  EXPECT_FALSE(s.use[0]);
  EXPECT_TRUE(s.use[1]);
}

TEST(ReplayOptions, ParsersAndTheModeMapping) {
  tt::ProxyMode m{};
  EXPECT_TRUE(tt::parse_mode("auto", &m));
  EXPECT_EQ(m, tt::ProxyMode::kAuto);
  EXPECT_TRUE(tt::parse_mode("displacement", &m));
  EXPECT_EQ(tt::pipeline_proxy(m), dsp::VelocityProxy::kDisplacement);
  EXPECT_EQ(tt::pipeline_proxy(tt::ProxyMode::kVelocity), dsp::VelocityProxy::kVelocity);
  EXPECT_FALSE(tt::parse_mode("fast", &m));
  dsp::FusionMethod f{};
  EXPECT_TRUE(tt::parse_method("paper", &f));
  EXPECT_EQ(f, dsp::FusionMethod::kPaper);
  EXPECT_FALSE(tt::parse_method("Joint", &f));
  tt::SensorChoice s{};
  EXPECT_TRUE(tt::parse_sensors("left", &s));
  EXPECT_EQ(s, tt::SensorChoice::kLeft);
}

TEST(ReplayErrors, MissingDirectoryIsNamed) {
  std::string err;
  EXPECT_FALSE(tt::RecordingSource::open("/nonexistent/tacse3_rec", &err));
  EXPECT_NE(err.find("/nonexistent/tacse3_rec"), std::string::npos) << err;
}

TEST(ReplayErrors, WrongFrameSizeIsAClearError) {
  const fs::path dir =
      fs::temp_directory_path() / ("tacse3_test_replay_small_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  rec::RecordingInfo info;
  info.width = 32;
  info.height = 24;
  rec::WriterOptions wo;
  wo.overwrite = true;
  auto w = rec::RecordingWriter::open(dir, info, wo);
  ASSERT_TRUE(w) << w.status().message();
  std::vector<std::uint8_t> px(32 * 24, 100);
  const rec::ImageView im{px.data(), 32, 24, 1};
  const rec::ImageView ims[2] = {im, im};
  ASSERT_TRUE(w.value()->write_frame(0, ims));
  ASSERT_TRUE(w.value()->finish());
  std::string err;
  EXPECT_FALSE(tt::RecordingSource::open(dir, &err));
  EXPECT_NE(err.find("recording.json: frames are 32x24"), std::string::npos) << err;
  EXPECT_NE(err.find("320x240"), std::string::npos) << err;
  fs::remove_all(dir);
}

TEST_F(ReplayTest, MissingSensorAndCorruptPngAreNamed) {
  const fs::path one = dir_ / "left_only";
  tt::SimCase c = tiny_case();
  c.hold_s = 0.0;
  c.grasp_s = 0.1;
  ASSERT_TRUE(tt::write_case_recording(c, one, 1, tt::SensorChoice::kLeft).empty());
  std::string err;
  auto src = tt::RecordingSource::open(one, &err);
  ASSERT_TRUE(src) << err;
  tt::ReplayOptions o;
  o.sensors = tt::SensorChoice::kRight;
  const tt::ReplayRun bad = tt::run_replay(*src, o, {});
  EXPECT_NE(bad.error.find("recording.json: --sensors right, but the recording has no right"),
            std::string::npos)
      << bad.error;
  o.sensors = tt::SensorChoice::kBoth;  // both = what the recording has
  EXPECT_TRUE(tt::run_replay(*src, o, {}).error.empty());
  // Corrupt the body of one PNG (the header stays valid, so open() accepts the directory).
  const fs::path png = one / "left" / "000005.png";
  {
    std::fstream f(png, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(60);
    const std::string junk(200, '\x5a');
    f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
  }
  auto src2 = tt::RecordingSource::open(one, &err);
  ASSERT_TRUE(src2) << err;
  const tt::ReplayRun r = tt::run_replay(*src2, tt::ReplayOptions{}, {});
  EXPECT_NE(r.error.find("left/000005.png"), std::string::npos) << r.error;
}

}  // namespace
