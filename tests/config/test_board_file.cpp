// SPDX-License-Identifier: Apache-2.0
// config tests: board files (the shipped ones and bad ones) and their resolution by name.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "tacse3/config/board_file.hpp"
#include "tacse3/config/listen_address.hpp"

namespace fs = std::filesystem;
using namespace tacse3;
using namespace tacse3::config;

namespace {

const char* kMinimal = "version = 1\n[sensors.left]\nbackend = \"sim\"\n";

// Parses text that must fail; returns the message.
std::string error_of(const std::string& text) {
  BoardConfig b;
  b.name = "untouched";
  std::string e;
  EXPECT_FALSE(parse_board(text, "test.toml", &b, &e)) << text;
  EXPECT_EQ(b.name, "untouched") << "a failed parse must leave the output unchanged";
  return e;
}

fs::path scratch_dir() {
  const fs::path d = fs::temp_directory_path() / ("tacse3-fw-board-" + std::to_string(getpid()));
  fs::create_directories(d);
  return d;
}

}  // namespace

TEST(Board, ShippedBoardsLoad) {
  for (const char* name : {"sim", "rpi4-uvc", "rpi5-libcamera"}) {
    BoardConfig b;
    std::string e;
    ASSERT_TRUE(load_board(fs::path(TACSE3_SOURCE_BOARDS_DIR) / name / "board.toml", &b, &e)) << e;
    EXPECT_EQ(b.name, name);
    EXPECT_EQ(b.sensor_count(), 2);
    // Left pad R = I, right pad mirrored diag(1, -1, -1) (the paper's sign matrix).
    EXPECT_EQ(b.sensors[0].rotation[1][1], 1.0);
    EXPECT_EQ(b.sensors[1].rotation[1][1], -1.0);
    EXPECT_EQ(b.sensors[1].rotation[2][2], -1.0);
  }
  BoardConfig uvc;
  std::string e;
  ASSERT_TRUE(load_board(fs::path(TACSE3_SOURCE_BOARDS_DIR) / "rpi4-uvc/board.toml", &uvc, &e));
  EXPECT_EQ(uvc.sensors[0].backend, CameraBackend::kV4l2);
  EXPECT_EQ(uvc.sensors[1].device, "/dev/tacse3-right");
  EXPECT_EQ(uvc.can.bitrate, 500000);
  EXPECT_EQ(uvc.can.mode, protocol::FrameMode::kClassic);
  EXPECT_EQ(uvc.gpio.lines.line(GpioLine::kTareButton).offset, 27);
  EXPECT_TRUE(uvc.gpio.lines.line(GpioLine::kTareButton).active_low);
  BoardConfig pi5;
  ASSERT_TRUE(
      load_board(fs::path(TACSE3_SOURCE_BOARDS_DIR) / "rpi5-libcamera/board.toml", &pi5, &e));
  EXPECT_EQ(pi5.can.mode, protocol::FrameMode::kFd);
  EXPECT_EQ(pi5.can.data_bitrate, 2000000);
  EXPECT_EQ(pi5.sensors[0].backend, CameraBackend::kLibcamera);
  EXPECT_EQ(pi5.gpio.lines.line(GpioLine::kStatusLed).name, "GPIO17");
  // Four cores: the pads' capture threads on 1 and 2, the DSP thread on 3.
  for (const BoardConfig* b : {&uvc, &pi5}) {
    EXPECT_EQ(b->realtime.pad_cpus, (std::array<int, 2>{1, 2}));
    EXPECT_EQ(b->realtime.dsp_cpu, 3);
  }
}

TEST(Board, MissingTablesTakeTheDocumentedDefaults) {
  BoardConfig b;
  std::string e;
  ASSERT_TRUE(parse_board(kMinimal, "min.toml", &b, &e)) << e;
  EXPECT_TRUE(b.sensors[0].enabled);
  EXPECT_FALSE(b.sensors[1].enabled);
  EXPECT_EQ(b.sensors[0].fps, 120);
  EXPECT_EQ(b.sensors[0].buffer_count, 4);
  EXPECT_DOUBLE_EQ(b.pipeline.finger_separation_m, 0.040);
  EXPECT_EQ(b.pipeline.pair_tolerance_us, 2000);
  EXPECT_EQ(b.pipeline.stale_ms, 50);
  EXPECT_EQ(b.pipeline.lost_ms, 500);
  EXPECT_EQ(b.can.backend, CanBackend::kSocketCan);
  EXPECT_EQ(b.can.interface, "can0");
  EXPECT_EQ(b.can.node_id, 1);
  EXPECT_EQ(b.can.tx_queue, 64);
  EXPECT_EQ(b.gpio.backend, GpioBackendKind::kNull);
  EXPECT_EQ(b.realtime.dsp_cpu, 3);
  EXPECT_EQ(b.realtime.dsp_priority, 80);
  EXPECT_EQ(b.sim.motion, "rz");
  EXPECT_TRUE(b.sim.repeat);
  // A right pad without a rotation gets the mirrored mount.
  ASSERT_TRUE(parse_board("version = 1\n[sensors.right]\nbackend = \"sim\"\n", "r.toml", &b, &e));
  EXPECT_EQ(b.sensors[1].rotation[1][1], -1.0);
  EXPECT_EQ(b.sensors[1].rotation[2][2], -1.0);
}

TEST(Board, MissingKeysAreNamed) {
  EXPECT_NE(
      error_of("[sensors.left]\nbackend = \"sim\"\n").find("missing required key \"version\""),
      std::string::npos);
  EXPECT_NE(error_of("version = 1\n[sensors.left]\nfps = 120\n").find("sensors.left.backend"),
            std::string::npos);
  EXPECT_NE(error_of("version = 1\nname = \"x\"\n").find("no sensor"), std::string::npos);
  const std::string dev = error_of("version = 1\n[sensors.left]\nbackend = \"v4l2\"\n");
  EXPECT_NE(dev.find("sensors.left.device"), std::string::npos) << dev;
}

TEST(Board, UnknownKeysAreErrorsWithTheirLine) {
  const std::string top =
      error_of("version = 1\nnmae = \"typo\"\n[sensors.left]\nbackend = \"sim\"\n");
  EXPECT_NE(top.find("unknown key \"nmae\""), std::string::npos) << top;
  EXPECT_NE(top.find("test.toml:2"), std::string::npos) << top;
  const std::string nested =
      error_of("version = 1\n[sensors.left]\nbackend = \"sim\"\ndevcie = \"x\"\n");
  EXPECT_NE(nested.find("unknown key \"sensors.left.devcie\""), std::string::npos) << nested;
  EXPECT_NE(nested.find("allowed here"), std::string::npos) << nested;
  const std::string gpio =
      error_of(std::string(kMinimal) + "[gpio.status_led]\noffset = 1\nbias = \"pull-up\"\n");
  EXPECT_NE(gpio.find("gpio.status_led.bias"), std::string::npos) << gpio;
  EXPECT_NE(error_of(std::string(kMinimal) + "[sensors.middle]\nbackend = \"sim\"\n")
                .find("sensors.middle"),
            std::string::npos);
}

TEST(Board, WrongTypesAreNamed) {
  const std::string fps =
      error_of("version = 1\n[sensors.left]\nbackend = \"sim\"\nfps = \"120\"\n");
  EXPECT_NE(fps.find("key \"sensors.left.fps\" must be an integer, got a string"),
            std::string::npos)
      << fps;
  const std::string ext = error_of(std::string(kMinimal) + "[can]\nextended_ids = 1\n");
  EXPECT_NE(ext.find("can.extended_ids"), std::string::npos) << ext;
  const std::string w =
      error_of(std::string(kMinimal) + "[pipeline]\nfinger_separation_m = \"40mm\"\n");
  EXPECT_NE(w.find("pipeline.finger_separation_m\" must be a number"), std::string::npos) << w;
  const std::string sens = error_of("version = 1\nsensors = 2\n");
  EXPECT_NE(sens.find("\"sensors\" must be a table"), std::string::npos) << sens;
  const std::string be = error_of("version = 1\n[sensors.left]\nbackend = \"usb\"\n");
  EXPECT_NE(be.find("sim | replay | v4l2 | libcamera"), std::string::npos) << be;
}

TEST(Board, OutOfRangeValuesAreNamed) {
  const std::string node = error_of(std::string(kMinimal) + "[can]\nnode_id = 64\n");
  EXPECT_NE(node.find("key \"can.node_id\" must be in [1, 63], got 64"), std::string::npos) << node;
  EXPECT_NE(error_of(std::string(kMinimal) + "[can]\nrate_divider = 0\n").find("can.rate_divider"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kMinimal) + "[pipeline]\nfinger_separation_m = 0.3\n")
                .find("pipeline.finger_separation_m"),
            std::string::npos);
  EXPECT_NE(error_of("version = 1\n[sensors.left]\nbackend = \"sim\"\nwidth = 640\n")
                .find("sensors.left.width"),
            std::string::npos);
  const std::string lost =
      error_of(std::string(kMinimal) + "[pipeline]\nstale_ms = 100\nlost_ms = 50\n");
  EXPECT_NE(lost.find("pipeline.lost_ms"), std::string::npos) << lost;
  EXPECT_NE(error_of(std::string(kMinimal) + "[realtime]\ndsp_priority = 100\n")
                .find("realtime.dsp_priority"),
            std::string::npos);
  const std::string rot = error_of(
      "version = 1\n[sensors.left]\nbackend = \"sim\"\nrotation = [[1,0,0],[0,1,0],[0,0,-1]]\n");
  EXPECT_NE(rot.find("sensors.left.rotation\" must be a rotation matrix"), std::string::npos)
      << rot;
  const std::string ver = error_of("version = 2\n[sensors.left]\nbackend = \"sim\"\n");
  EXPECT_NE(ver.find("schema version 1"), std::string::npos) << ver;
  const std::string syn = error_of("version = 1\n[sensors.left\n");
  EXPECT_NE(syn.find("test.toml:2"), std::string::npos) << syn;
  EXPECT_NE(syn.find("TOML syntax error"), std::string::npos) << syn;
}

// A [sim] object the simulator has no preset for is refused by the parse (and so by --check),
// not later by the run.
TEST(Board, SimObjectMustBeASimulatorPreset) {
  const std::string e = error_of(std::string(kMinimal) + "[sim]\nobject = \"banana\"\n");
  EXPECT_NE(e.find("test.toml:5"), std::string::npos) << e;
  EXPECT_NE(e.find("key \"sim.object\" must be one of sphere | large-sphere"), std::string::npos)
      << e;
  EXPECT_NE(e.find("got \"banana\""), std::string::npos) << e;
  BoardConfig b;
  std::string err;
  ASSERT_TRUE(
      parse_board(std::string(kMinimal) + "[sim]\nobject = \"screwdriver\"\n", "t.toml", &b, &err))
      << err;
  EXPECT_EQ(b.sim.object, "screwdriver");
}

TEST(Board, ResolvesNamesInTheDocumentedOrder) {
  const fs::path dir = scratch_dir();
  fs::create_directories(dir / "env/mine");
  std::ofstream(dir / "env/mine/board.toml") << kMinimal;
  std::string e;
  // The source tree is the last resort.
  unsetenv("TACSE3_BOARD_DIR");
  EXPECT_EQ(resolve_board("sim", "", TACSE3_SOURCE_BOARDS_DIR, &e),
            (fs::path(TACSE3_SOURCE_BOARDS_DIR) / "sim/board.toml").lexically_normal());
  // $TACSE3_BOARD_DIR comes first.
  setenv("TACSE3_BOARD_DIR", (dir / "env").c_str(), 1);
  EXPECT_EQ(resolve_board("mine", "", TACSE3_SOURCE_BOARDS_DIR, &e), (dir / "env/mine/board.toml"));
  // <exe_dir>/../share/tacse3/boards.
  fs::create_directories(dir / "prefix/share/tacse3/boards/pkg");
  fs::create_directories(dir / "prefix/bin");
  std::ofstream(dir / "prefix/share/tacse3/boards/pkg/board.toml") << kMinimal;
  EXPECT_EQ(resolve_board("pkg", dir / "prefix/bin", "", &e),
            (dir / "prefix/share/tacse3/boards/pkg/board.toml").lexically_normal());
  // A path is used as is.
  EXPECT_EQ(resolve_board((dir / "env/mine/board.toml").string(), "", "", &e),
            dir / "env/mine/board.toml");
  EXPECT_TRUE(resolve_board("nope", "", TACSE3_SOURCE_BOARDS_DIR, &e).empty());
  EXPECT_NE(e.find("board \"nope\" not found"), std::string::npos) << e;
  EXPECT_NE(e.find("/etc/tacse3/boards/nope/board.toml"), std::string::npos) << e;
  EXPECT_TRUE(resolve_board("./missing.toml", "", "", &e).empty());
  unsetenv("TACSE3_BOARD_DIR");
  fs::remove_all(dir);
}

// toml++ 3.3 reaches an "unreachable" branch (undefined behaviour; the sanitizer build aborts)
// on a non-ASCII character where it tests for whitespace; such text is refused before it.
TEST(Board, NonAsciiOutsideStringsIsRefusedBeforeToml) {
  const std::string key = error_of("version = 1\n\xc3\xa9 = 1\n");
  EXPECT_NE(key.find("test.toml:2:1: TOML syntax error: a non-ASCII character outside a string"),
            std::string::npos)
      << key;
  const std::string after = error_of("version = 1 \xc2\xa7\n");
  EXPECT_NE(after.find("test.toml:1:13:"), std::string::npos) << after;
  // After a line-ending backslash in a multi-line string toml++ tests the next line's first
  // character for whitespace too.
  const std::string ml = error_of("version = 1\nname = \"\"\"\\\n  \xc2\xa7\"\"\"\n");
  EXPECT_NE(ml.find("test.toml:3:3:"), std::string::npos) << ml;
  // So does a backslash followed directly by a non-ASCII character (fuzz_board found this one).
  const std::string esc = error_of("name = \"\"\"\\\xc2\xa7\n\"\"\"\nv = 1\n");
  EXPECT_NE(esc.find("test.toml:1:12: TOML syntax error: a non-ASCII character after a backslash"),
            std::string::npos)
      << esc;
  const std::string esc1 = error_of("version = 1\nname = \"\\\xc3\xa9\"\n");
  EXPECT_NE(esc1.find("test.toml:2:10:"), std::string::npos) << esc1;
  // ... and one after the blanks that follow a backslash, on the same line.
  const std::string blank = error_of("name = \"\"\"\\ \xc5\x82'''';\nv = 1\n");
  EXPECT_NE(
      blank.find("test.toml:1:13: TOML syntax error: a non-ASCII character after a backslash"),
      std::string::npos)
      << blank;
  // A syntax error before a non-ASCII character in what would be a string (fuzz_board).
  const std::string after_error = error_of(
      "lr  =-9_99\"99\xca\x89"
      "ec9 \x01");
  EXPECT_NE(after_error.find("test.toml:1:"), std::string::npos) << after_error;
  EXPECT_NE(after_error.find("TOML syntax error"), std::string::npos) << after_error;
  // Strings and comments may hold any UTF-8, as TOML allows.
  BoardConfig b;
  std::string e;
  EXPECT_TRUE(parse_board(
      std::string("# caf\xc3\xa9 \xef\xbb\xbe\n") + kMinimal + "\n[sim]\nobject = \"sphere\"\n",
      "test.toml", &b, &e))
      << e;
  EXPECT_TRUE(parse_board(std::string("name = \"Cam\xc3\xa9ra \\\" \xc2\xa7\"\n") + kMinimal,
                          "test.toml", &b, &e))
      << e;
  EXPECT_EQ(b.name, "Cam\xc3\xa9ra \" \xc2\xa7");
}

// A board path that is not a regular file is named as what it is, read not at all (a FIFO would
// block, /dev/zero never ends), and a file over 1 MiB is refused before it is read.
TEST(Board, LoadRefusesWhatIsNotABoardFile) {
  const fs::path dir = scratch_dir();
  ASSERT_EQ(mkfifo((dir / "fifo").c_str(), 0600), 0);
  {
    std::ofstream big(dir / "big.toml");
    big << std::string(kMaxBoardBytes + 1, '#');
  }
  BoardConfig b;
  std::string e;
  EXPECT_FALSE(load_board(dir / "fifo", &b, &e));
  EXPECT_EQ(e, (dir / "fifo").string() + ": is a FIFO, expected a board file (a regular file)");
  EXPECT_FALSE(load_board(dir, &b, &e));
  EXPECT_NE(e.find("is a directory, expected a board file"), std::string::npos) << e;
  EXPECT_FALSE(load_board("/dev/zero", &b, &e));
  EXPECT_NE(e.find("/dev/zero: is a character device"), std::string::npos) << e;
  EXPECT_FALSE(load_board(dir / "big.toml", &b, &e));
  EXPECT_NE(e.find("larger than 1 MiB; not a board file"), std::string::npos) << e;
  EXPECT_FALSE(load_board(dir / "absent.toml", &b, &e));
  EXPECT_NE(e.find("absent.toml: board file not found"), std::string::npos) << e;
  // resolve_board passes a path that exists on, so the message above is the one users see.
  EXPECT_EQ(resolve_board((dir / "fifo").string(), "", "", &e), dir / "fifo");
  fs::remove_all(dir);
}

TEST(Board, RecordDirIsAnAbsolutePath) {
  BoardConfig b;
  std::string e;
  ASSERT_TRUE(parse_board(kMinimal, "test.toml", &b, &e)) << e;
  EXPECT_EQ(b.record.dir, "") << "no [record]: START_RECORDING is refused";
  ASSERT_TRUE(parse_board(std::string(kMinimal) + "[record]\ndir = \"/srv/tacse3/rec\"\n",
                          "test.toml", &b, &e))
      << e;
  EXPECT_EQ(b.record.dir, "/srv/tacse3/rec");
  const std::string rel = error_of(std::string(kMinimal) + "[record]\ndir = \"rec\"\n");
  EXPECT_NE(rel.find("test.toml:5: key \"record.dir\" must be an absolute path, got \"rec\""),
            std::string::npos)
      << rel;
  const std::string typo = error_of(std::string(kMinimal) + "[record]\ndirectory = \"/x\"\n");
  EXPECT_NE(typo.find("unknown key \"record.directory\""), std::string::npos) << typo;
  const std::string type = error_of(std::string(kMinimal) + "[record]\ndir = 1\n");
  EXPECT_NE(type.find("key \"record.dir\" must be a string"), std::string::npos) << type;
}

// [sim] plan: a relative path is the board file's folder's; it needs realtime.
TEST(Board, SimPlanIsResolvedFromTheBoardFilesFolder) {
  BoardConfig b;
  std::string e;
  ASSERT_TRUE(parse_board(kMinimal, "/etc/b/board.toml", &b, &e)) << e;
  EXPECT_EQ(b.sim.plan, "") << "no plan: the [sim] scenario plays";
  ASSERT_TRUE(parse_board(std::string(kMinimal) + "[sim]\nplan = \"plan.csv\"\n",
                          "/etc/b/board.toml", &b, &e))
      << e;
  EXPECT_EQ(b.sim.plan, "/etc/b/plan.csv");
  ASSERT_TRUE(parse_board(std::string(kMinimal) + "[sim]\nplan = \"/srv/p.csv\"\n",
                          "/etc/b/board.toml", &b, &e))
      << e;
  EXPECT_EQ(b.sim.plan, "/srv/p.csv");
  EXPECT_NE(describe(b).find("sim: sphere, seed 1, plan /srv/p.csv (one motion per recording)"),
            std::string::npos)
      << describe(b);
  const std::string empty = error_of(std::string(kMinimal) + "[sim]\nplan = \"\"\n");
  EXPECT_NE(empty.find("test.toml:5: key \"sim.plan\" must name a plan CSV file"),
            std::string::npos)
      << empty;
  const std::string fast =
      error_of(std::string(kMinimal) + "[sim]\nplan = \"p.csv\"\nrealtime = false\n");
  EXPECT_NE(fast.find("test.toml:6: key \"sim.realtime\" must be true with sim.plan"),
            std::string::npos)
      << fast;
}

// [rig] tcp_to_grasp: a pose read with its quaternion normalised; absent means not given.
TEST(Board, RigTcpToGraspIsReadAndNormalised) {
  BoardConfig b;
  std::string e;
  ASSERT_TRUE(parse_board(kMinimal, "test.toml", &b, &e)) << e;
  EXPECT_FALSE(b.rig.has_tcp_to_grasp);
  ASSERT_TRUE(parse_board(
      std::string(kMinimal) + "[rig]\ntcp_to_grasp = [0.01, -0.02, 0.16, 0.7075, 0, 0, 0.7075]\n",
      "test.toml", &b, &e))
      << e;
  ASSERT_TRUE(b.rig.has_tcp_to_grasp);
  EXPECT_DOUBLE_EQ(b.rig.tcp_to_grasp[0], 0.01);
  EXPECT_DOUBLE_EQ(b.rig.tcp_to_grasp[1], -0.02);
  EXPECT_DOUBLE_EQ(b.rig.tcp_to_grasp[2], 0.16);
  // Norm 1.00056 (within 1e-3): normalised to cos(45 deg), sin(45 deg) about z.
  EXPECT_NEAR(b.rig.tcp_to_grasp[3], std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(b.rig.tcp_to_grasp[6], std::sqrt(0.5), 1e-12);
  EXPECT_EQ(b.rig.tcp_to_grasp[4], 0.0);
}

TEST(Board, BadRigTcpToGraspIsNamed) {
  const std::string rig = std::string(kMinimal) + "[rig]\ntcp_to_grasp = ";
  const std::string norm = error_of(rig + "[0, 0, 0.1, 1, 0, 0.1, 0]\n");
  EXPECT_NE(norm.find("test.toml:5: key \"rig.tcp_to_grasp\" quaternion (qw, qx, qy, qz) is not "
                      "unit (norm 1.00499"),
            std::string::npos)
      << norm;
  const std::string six = error_of(rig + "[0, 0, 0, 1, 0, 0]\n");
  EXPECT_NE(six.find("key \"rig.tcp_to_grasp\" must be [x, y, z, qw, qx, qy, qz] (metres, unit "
                     "quaternion), got 6 elements"),
            std::string::npos)
      << six;
  const std::string inf = error_of(rig + "[0, inf, 0, 1, 0, 0, 0]\n");
  EXPECT_NE(inf.find("key \"rig.tcp_to_grasp\" element 1 must be a finite number"),
            std::string::npos)
      << inf;
  const std::string str = error_of(rig + "[0, \"a\", 0, 1, 0, 0, 0]\n");
  EXPECT_NE(str.find("element 1 must be a finite number"), std::string::npos) << str;
  const std::string key = error_of(std::string(kMinimal) + "[rig]\ntcp = 1\n");
  EXPECT_NE(key.find("unknown key \"rig.tcp\" (allowed here: tcp_to_grasp)"), std::string::npos)
      << key;
}

TEST(Board, ViewerListenIsOffByDefaultAndChecked) {
  BoardConfig b;
  std::string e;
  ASSERT_TRUE(parse_board(kMinimal, "test.toml", &b, &e)) << e;
  EXPECT_EQ(b.viewer.listen, "") << "no [viewer]: no web view";
  ASSERT_TRUE(
      parse_board(std::string(kMinimal) + "[viewer]\nlisten = \"8080\"\n", "test.toml", &b, &e))
      << e;
  EXPECT_EQ(b.viewer.listen, "8080");
  const std::string port = error_of(std::string(kMinimal) + "[viewer]\nlisten = \"1.2.3.4:0\"\n");
  EXPECT_NE(port.find("test.toml:5: key \"viewer.listen\": \"1.2.3.4:0\": the port must be"),
            std::string::npos)
      << port;
  const std::string addr = error_of(std::string(kMinimal) + "[viewer]\nlisten = \"board:80\"\n");
  EXPECT_NE(addr.find("the address must be an IPv4 address"), std::string::npos) << addr;
}

// [realtime] pad_cpus: [left, right], -1 (the default) leaves a pad's thread unpinned.
TEST(Board, PadCpusArePairsOfCpuNumbers) {
  BoardConfig b;
  std::string e;
  ASSERT_TRUE(parse_board(kMinimal, "test.toml", &b, &e)) << e;
  EXPECT_EQ(b.realtime.pad_cpus, (std::array<int, 2>{-1, -1}));
  ASSERT_TRUE(
      parse_board(std::string(kMinimal) + "[realtime]\npad_cpus = [0, -1]\n", "test.toml", &b, &e))
      << e;
  EXPECT_EQ(b.realtime.pad_cpus, (std::array<int, 2>{0, -1}));
  EXPECT_NE(describe(b).find("pad cpus 0, -1"), std::string::npos) << describe(b);
  const std::string one = error_of(std::string(kMinimal) + "[realtime]\npad_cpus = [2]\n");
  EXPECT_NE(one.find("test.toml:5: key \"realtime.pad_cpus\" must be [left, right], two "
                     "integers, got 1 elements"),
            std::string::npos)
      << one;
  const std::string range = error_of(std::string(kMinimal) + "[realtime]\npad_cpus = [1, -2]\n");
  EXPECT_NE(range.find("key \"realtime.pad_cpus\" element 1 must be an integer in [-1, 1023]"),
            std::string::npos)
      << range;
  const std::string type = error_of(std::string(kMinimal) + "[realtime]\npad_cpus = 2\n");
  EXPECT_NE(type.find("realtime.pad_cpus\" must be [left, right]"), std::string::npos) << type;
  const std::string real = error_of(std::string(kMinimal) + "[realtime]\npad_cpus = [1.0, 2]\n");
  EXPECT_NE(real.find("element 0 must be an integer"), std::string::npos) << real;
}

// phase_us: a replay pad's delay, for the replay backend only.
TEST(Board, PhaseIsForReplayPadsOnly) {
  BoardConfig b;
  std::string e;
  ASSERT_TRUE(
      parse_board("version = 1\n[sensors.right]\nbackend = \"replay\"\ndevice = \"r\"\n"
                  "phase_us = 1500\n",
                  "test.toml", &b, &e))
      << e;
  EXPECT_EQ(b.sensors[1].phase_us, 1500);
  const std::string sim = error_of(std::string(kMinimal) + "phase_us = 10\n");
  EXPECT_NE(sim.find("key \"sensors.left.phase_us\" is for backend \"replay\" only"),
            std::string::npos)
      << sim;
  const std::string neg = error_of(
      "version = 1\n[sensors.left]\nbackend = \"replay\"\ndevice = \"r\"\nphase_us = -1\n");
  EXPECT_NE(neg.find("sensors.left.phase_us\" must be in [0, 1000000]"), std::string::npos) << neg;
}

TEST(Board, ViewerControlsAreOffByDefault) {
  BoardConfig b;
  std::string e;
  ASSERT_TRUE(
      parse_board(std::string(kMinimal) + "[viewer]\nlisten = \"8080\"\n", "test.toml", &b, &e))
      << e;
  EXPECT_FALSE(b.viewer.controls);
  ASSERT_TRUE(parse_board(std::string(kMinimal) + "[viewer]\nlisten = \"8080\"\ncontrols = true\n",
                          "test.toml", &b, &e))
      << e;
  EXPECT_TRUE(b.viewer.controls);
  EXPECT_NE(describe(b).find("http on 8080, controls on"), std::string::npos) << describe(b);
  ASSERT_TRUE(
      parse_board(std::string(kMinimal) + "[viewer]\ncontrols = true\n", "test.toml", &b, &e))
      << "controls without listen: --http gives the address; " << e;
  EXPECT_EQ(b.viewer.listen, "");
  EXPECT_TRUE(b.viewer.controls);
  EXPECT_NE(describe(b).find("viewer: off, controls on"), std::string::npos) << describe(b);
  const std::string type = error_of(std::string(kMinimal) + "[viewer]\ncontrols = \"yes\"\n");
  EXPECT_NE(type.find("viewer.controls"), std::string::npos) << type;
}

TEST(ListenAddress, PortAloneBindsToLocalhost) {
  struct Case {
    const char* text;
    bool ok;
    const char* host;
    int port;
  };
  for (const Case& c :
       {Case{"8080", true, "127.0.0.1", 8080}, Case{"0.0.0.0:80", true, "0.0.0.0", 80},
        Case{"localhost:65535", true, "127.0.0.1", 65535},
        Case{"192.168.1.20:8080", true, "192.168.1.20", 8080}, Case{"", false, "", 0},
        Case{"0", false, "", 0}, Case{"65536", false, "", 0}, Case{"80x", false, "", 0},
        Case{":80", false, "", 0}, Case{"1.2.3:80", false, "", 0}, Case{"1.2.3.4:", false, "", 0},
        Case{"-1", false, "", 0}, Case{"[::1]:80", false, "", 0}}) {
    ListenAddress a;
    std::string e;
    EXPECT_EQ(parse_listen_address(c.text, &a, &e), c.ok) << c.text;
    if (c.ok) {
      EXPECT_EQ(a.host, c.host) << c.text;
      EXPECT_EQ(a.port, c.port) << c.text;
    } else {
      EXPECT_FALSE(e.empty()) << c.text;
    }
  }
}
