// SPDX-License-Identifier: Apache-2.0
// tacse3-truth: a calibration fitted on rebuilt truth evaluates like one fitted on the
// simulator's own truth (label "slow": two calibration fits).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "tacse3/tools/calibrate.hpp"
#include "tacse3/tools/replay.hpp"
#include "tacse3/tools/source.hpp"
#include "truth_rig.hpp"

namespace {

namespace fs = std::filesystem;
namespace tt = tacse3::tools;
using tacse3::tools::truth_test::RigLog;

// Mean tracking rotation RMS (deg) of a calibration over the recordings, against their
// simulator truth.
double evaluate(const std::vector<tt::FrameSource*>& sources,
                const tacse3::config::CalibrationSet& cal) {
  double sum = 0.0;
  for (tt::FrameSource* s : sources) {
    tt::ReplayOptions o;
    o.calibration = cal;
    const tt::ReplayRun run = tt::run_replay(*s, o, {});
    EXPECT_TRUE(run.error.empty()) << run.error;
    const tt::RunSummary sum_one = tt::summarize(s->info(), run.frames, o.sensors);
    EXPECT_TRUE(sum_one.tracking.valid);
    sum += sum_one.tracking.rotation_rms_deg;
  }
  return sum / static_cast<double>(sources.size());
}

TEST(TruthCalibration, RebuiltTruthCalibratesLikeTheOriginal) {
  const fs::path dir =
      fs::temp_directory_path() / ("tacse3_test_truth_cal_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::vector<std::unique_ptr<tt::RecordingSource>> original, rebuilt;
  const auto cases = tacse3::tools::truth_test::cases();
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const fs::path d = dir / cases[k].motion;
    ASSERT_EQ(tt::write_case_recording(cases[k], d, 1), "");
    std::string err;
    original.push_back(tt::RecordingSource::open(d, &err));
    ASSERT_TRUE(original.back()) << err;
    const auto& info = original.back()->info();
    RigLog rig(71 + static_cast<unsigned>(k));
    const fs::path log = dir / (cases[k].motion + "-gripper.csv");
    ASSERT_EQ(rig.write_gripper_log(info.truth, info.t_ns, 2'500'000'000, log, false), "");
    fs::remove(d / "truth.csv");
    const std::string cmd = std::string(TACSE3_TRUTH_BIN) + " -q --recording " + d.string() +
                            " --gripper-log " + log.string() + " --tcp-to-grasp \"" +
                            rig.tcp_to_grasp_text() + "\" --clock-offset 2.5";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    rebuilt.push_back(tt::RecordingSource::open(d, &err));
    ASSERT_TRUE(rebuilt.back()) << err;
  }
  std::vector<tt::FrameSource*> orig_src, rebuilt_src;
  for (auto& s : original) orig_src.push_back(s.get());
  for (auto& s : rebuilt) rebuilt_src.push_back(s.get());
  tt::CalibrateOptions opt;
  opt.jobs = 2;
  tt::CalibrateReport from_original, from_rebuilt;
  ASSERT_EQ(tt::calibrate(orig_src, opt, &from_original), "");
  ASSERT_EQ(tt::calibrate(rebuilt_src, opt, &from_rebuilt), "");
  const double e_original = evaluate(orig_src, from_original.calibration);
  const double e_rebuilt = evaluate(orig_src, from_rebuilt.calibration);
  std::printf(
      "tracking rotation RMS against the simulator truth: calibrated on it %.4f deg, on "
      "the rebuilt truth %.4f deg (ratio %.3f)\n",
      e_original, e_rebuilt, e_rebuilt / e_original);
  EXPECT_LT(std::abs(e_rebuilt - e_original), 0.1 * e_original);
  fs::remove_all(dir);
}

}  // namespace
