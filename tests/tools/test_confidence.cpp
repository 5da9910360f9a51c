// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: the twist confidence (dsp::TwistConfidence) on short simulated grasps: above the
// recommended threshold in steady stick tracking, below it with a lost pad, a tiny contact and
// at a slide's onset.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "tacse3/dsp/confidence.hpp"
#include "tacse3/tools/bench.hpp"
#include "tacse3/tools/replay.hpp"
#include "tacse3/tools/source.hpp"

namespace {

namespace fs = std::filesystem;
namespace tt = tacse3::tools;
namespace dsp = tacse3::dsp;

constexpr double kThreshold = dsp::kConfidenceThreshold;

// Short cases (≈ 1 s): grasp, settle, motion, a short hold.
tt::SimCase short_case(const std::string& motion, double magnitude) {
  tt::SimCase c;
  c.object = "sphere";
  c.motion = motion;
  c.magnitude = magnitude;
  c.seed = 11;
  c.approach_s = 0.05;
  c.grasp_s = 0.25;
  c.settle_s = 0.05;
  c.hold_s = 0.15;
  return c;
}

struct Stats {
  double median = 0.0, p05 = 0.0, p95 = 0.0;
  std::size_t n = 0;
};

Stats stats(std::vector<double> v) {
  Stats s;
  s.n = v.size();
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  auto at = [&](double p) {
    return v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))];
  };
  s.median = at(0.5);
  s.p05 = at(0.05);
  s.p95 = at(0.95);
  return s;
}

// Replays `rec` and returns the per-frame results.
std::vector<tt::FrameResult> replay(const fs::path& rec, tt::SensorChoice sensors) {
  std::string err;
  auto src = tt::RecordingSource::open(rec, &err);
  EXPECT_TRUE(src) << err;
  if (!src) return {};
  tt::ReplayOptions o;
  o.sensors = sensors;
  tt::ReplayRun run = tt::run_replay(*src, o, {});
  EXPECT_TRUE(run.error.empty()) << run.error;
  return run.frames;
}

// Confidence of the frames from the motion's start (the recording's truth) on which every fed
// pad sees contact.
std::vector<double> tracking_confidence(const fs::path& rec, const std::vector<tt::FrameResult>& f,
                                        tt::SensorChoice sensors) {
  std::string err;
  auto src = tt::RecordingSource::open(rec, &err);
  const std::int64_t start = tt::motion_start_ns(src->info().truth);
  std::vector<double> out;
  for (const auto& r : f) {
    const bool left = sensors != tt::SensorChoice::kRight,
               right = sensors != tt::SensorChoice::kLeft;
    if (r.t_ns < start || (left && !r.contact[0]) || (right && !r.contact[1])) continue;
    out.push_back(r.confidence);
  }
  return out;
}

void print(const char* what, const Stats& s) {
  std::printf("%-28s n %3zu  median %.3f  p05 %.3f  p95 %.3f\n", what, s.n, s.median, s.p05, s.p95);
}

class Confidence : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("tacse3_test_confidence_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  // Renders the case once per run (the lost-pad test replays the stick recording).
  static fs::path record(const std::string& name, const tt::SimCase& c) {
    const fs::path p = dir_ / name;
    if (fs::exists(p)) return p;
    const std::string e = tt::write_case_recording(c, p, 1);
    EXPECT_TRUE(e.empty()) << e;
    return p;
  }
  static fs::path dir_;
};
fs::path Confidence::dir_;

// From the motion's start on, 95 % of the frames at or above the threshold.
TEST_F(Confidence, HighInSteadyStickTracking) {
  for (const auto& [motion, magnitude] : {std::pair{"rx", 3.0}, std::pair{"rz", 3.0}}) {
    const fs::path rec = record(std::string("stick_") + motion, short_case(motion, magnitude));
    const auto frames = replay(rec, tt::SensorChoice::kBoth);
    const Stats s = stats(tracking_confidence(rec, frames, tt::SensorChoice::kBoth));
    print((std::string("stick ") + motion + " 3, both pads").c_str(), s);
    ASSERT_GT(s.n, 40u);
    EXPECT_GE(s.p05, kThreshold) << motion;
  }
}

}  // namespace

namespace {

TEST_F(Confidence, LowWithALostPad) {
  const fs::path rec = record("stick_rx", short_case("rx", 3.0));
  const auto frames = replay(rec, tt::SensorChoice::kLeft);
  const Stats s = stats(tracking_confidence(rec, frames, tt::SensorChoice::kLeft));
  print("stick rx 3, left pad only", s);
  ASSERT_GT(s.n, 40u);
  EXPECT_LT(s.p95, kThreshold);
}

TEST_F(Confidence, LowOnATinyContact) {
  tt::SimCase c = short_case("rx", 3.0);
  c.radius_mm = 2.0;  // pads end 4 mm apart on a ≈ 30-cell patch
  const fs::path rec = record("tiny", c);
  const auto frames = replay(rec, tt::SensorChoice::kBoth);
  const Stats s = stats(tracking_confidence(rec, frames, tt::SensorChoice::kBoth));
  print("stick rx 3, tiny contact", s);
  ASSERT_GT(s.n, 40u);
  EXPECT_LT(s.p95, kThreshold);
}

TEST_F(Confidence, LowAtASlideOnset) {
  const fs::path rec = record("slide", short_case("rz", 30.0));
  const auto frames = replay(rec, tt::SensorChoice::kBoth);
  std::vector<double> onset;
  for (std::size_t k = 0; k + 1 < frames.size(); ++k) {
    const auto& a = frames[k];
    const auto& b = frames[k + 1];
    bool starts = false;
    for (int i = 0; i < 2; ++i)
      starts = starts || (!a.slipping[i].value_or(false) && b.slipping[i].value_or(false));
    if (starts) onset.push_back(a.confidence);
  }
  const Stats s = stats(onset);
  print("slide rz 30, onset frames", s);
  print("slide rz 30, tracking", stats(tracking_confidence(rec, frames, tt::SensorChoice::kBoth)));
  ASSERT_GT(s.n, 0u);
  EXPECT_LT(s.p95, kThreshold);
}

}  // namespace
