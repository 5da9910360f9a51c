// SPDX-License-Identifier: Apache-2.0
// firmware tests: the daemon's calibration loading and the pipeline configuration it makes.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <string>

#include "tacse3/config/board_file.hpp"
#include "tacse3/firmware/daemon.hpp"

namespace fs = std::filesystem;
using namespace tacse3;
using namespace tacse3::firmware;
using config::BoardConfig;
using config::load_board;

namespace {

fs::path scratch_dir() {
  const fs::path d = fs::temp_directory_path() / ("tacse3-fw-cal-" + std::to_string(getpid()));
  fs::create_directories(d);
  return d;
}

}  // namespace

TEST(Calibration, BadFilesAreRejectedWithFileAndKey) {
  const fs::path dir = scratch_dir();
  const fs::path bad = dir / "bad.toml";
  std::ofstream(bad)
      << "format = \"tacse3-calibration\"\nversion = 1\n[sensor]\ncontact_tau_on = -1.0\n";
  CalibrationSource c;
  std::string e;
  EXPECT_FALSE(load_calibration_source(bad.string(), &c, &e));
  EXPECT_NE(e.find(bad.string()), std::string::npos) << e;
  EXPECT_NE(e.find("sensor.contact_tau_on"), std::string::npos) << e;
  EXPECT_FALSE(load_calibration_source((dir / "absent.toml").string(), &c, &e));
  EXPECT_NE(e.find("absent.toml"), std::string::npos) << e;
  // A FIFO is refused at once (it blocked the daemon's SIGHUP reload, so that it ignored
  // SIGTERM). Without a writer it cannot release a blocked open: a hang here is the defect.
  const fs::path fifo = dir / "fifo.toml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_FALSE(load_calibration_source(fifo.string(), &c, &e));
  EXPECT_NE(e.find(fifo.string() + ": is a FIFO"), std::string::npos) << e;
  // The fitted simulator calibration loads and makes a valid pipeline configuration.
  ASSERT_TRUE(load_calibration_source(TACSE3_SIM_CALIBRATION, &c, &e)) << e;
  BoardConfig b;
  ASSERT_TRUE(load_board(fs::path(TACSE3_SOURCE_BOARDS_DIR) / "sim/board.toml", &b, &e)) << e;
  dsp::DualConfig dual;
  std::array<dsp::Calibration, 2> cal;
  ASSERT_TRUE(make_pipeline_config(b, c, &dual, &cal, &e)) << e;
  EXPECT_DOUBLE_EQ(dual.finger_separation_m, 0.040);
  EXPECT_DOUBLE_EQ(cal[0].pixel_pitch_m, 1e-4);
  // velocity_proxy = "auto" keeps the file's proxy (velocity) until dsp has its own auto mode.
  EXPECT_EQ(dual.fusion.extrinsics[1].R_GS(1, 1), -1.0);
  fs::remove_all(dir);
}

TEST(Calibration, TheSimBoardDefaultsToTheSimulatorsCalibration) {
  std::string e;
  BoardConfig sim, uvc;
  ASSERT_TRUE(load_board(fs::path(TACSE3_SOURCE_BOARDS_DIR) / "sim/board.toml", &sim, &e)) << e;
  ASSERT_TRUE(load_board(fs::path(TACSE3_SOURCE_BOARDS_DIR) / "rpi4-uvc/board.toml", &uvc, &e))
      << e;
  EXPECT_TRUE(simulated_board(sim));
  EXPECT_FALSE(simulated_board(uvc));
  // No installed copy beside a scratch "bin": the source tree's file.
  const fs::path dir = scratch_dir();
  EXPECT_EQ(default_calibration(sim, dir / "bin", TACSE3_SIM_CALIBRATION),
            fs::path(TACSE3_SIM_CALIBRATION));
  // A camera board gets no default: the simulator's pads are not its pads.
  EXPECT_TRUE(default_calibration(uvc, dir / "bin", TACSE3_SIM_CALIBRATION).empty());
  // A simulated board with one pad switched to a camera is not simulated either.
  BoardConfig mixed = sim;
  mixed.sensors[1].backend = config::CameraBackend::kV4l2;
  EXPECT_FALSE(simulated_board(mixed));
  fs::remove_all(dir);
}

TEST(Calibration, OnlyAFileWithSensorKeysIsFitted) {
  const fs::path dir = scratch_dir();
  CalibrationSource c;
  std::string e;
  ASSERT_TRUE(load_calibration_source("", &c, &e)) << e;
  EXPECT_FALSE(c.fitted());  // built-in defaults
  const fs::path header = dir / "header.toml";
  std::ofstream(header) << "format = \"tacse3-calibration\"\nversion = 1\n";
  ASSERT_TRUE(load_calibration_source(header.string(), &c, &e)) << e;
  EXPECT_FALSE(c.fitted());  // the package's /etc/tacse3/calibration.toml
  ASSERT_TRUE(load_calibration_source(TACSE3_SIM_CALIBRATION, &c, &e)) << e;
  EXPECT_TRUE(c.fitted());
  fs::remove_all(dir);
}
