// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: the TOML calibration file: round trips, defaults, and errors naming key and file.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <future>
#include <iterator>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>

#include "tacse3/config/calibration_file.hpp"

namespace {

namespace cfg = tacse3::config;
namespace dsp = tacse3::dsp;

const std::string kHead = "format = \"tacse3-calibration\"\nversion = 1\n";

cfg::Status parse(const std::string& text, cfg::CalibrationSet* out) {
  return cfg::parse_calibration(text, "cal.toml", out);
}

// Parses `text` expecting an error that contains every fragment.
void expect_error(const std::string& text, std::initializer_list<std::string> fragments) {
  cfg::CalibrationSet set;
  set.sensor[0].c_velocity = 42.0;  // sentinel: must be untouched on error
  const cfg::Status s = parse(text, &set);
  ASSERT_FALSE(s.ok()) << text;
  for (const auto& f : fragments) {
    EXPECT_NE(s.message().find(f), std::string::npos)
        << "message: " << s.message() << "\nmissing: " << f;
  }
  EXPECT_EQ(set.sensor[0].c_velocity, 42.0);
}

cfg::CalibrationSet odd_set() {
  cfg::CalibrationSet s;
  for (auto& c : s.sensor) {
    c.pixel_pitch_m = 1.0e-4;
    c.shear_gain_d = 0.123456789012345;
    c.shear_gain_r = 0.25;
    c.shear_gain_k = 3.0;
    c.contact_tau_on = 0.0138;
    c.contact_tau_off = 0.00689;
    c.contact_min_area_cells = 7;
    c.velocity_proxy = dsp::VelocityProxy::kDisplacement;
    c.c_velocity = 0.007309;
    c.c_displacement = 1.015e-4;
    c.rotation_scale = {0.5, 1.0 / 3.0, 2.0};
    c.moving_average_length = 6;
  }
  s.sensor[1].c_velocity = 0.0081;  // a per-sensor difference goes to [right]
  s.sensor[1].translation_scale = {1.1, 0.9, 1.0};
  // The stick/slip detector's mode and thresholds round-trip too (one pad differs).
  s.sensor[1].velocity_proxy = dsp::VelocityProxy::kAuto;
  s.sensor[1].slip_relax_rate_on = 2.5;
  s.sensor[1].slip_on_frames = 6;
  s.sensor[1].stick_confirm_s = 0.75;
  s.sensor[1].max_mask_area_ratio = 2.25;
  s.sensor[1].release_load_rate = 6.5;
  s.paper[0].rotation_scale = {0.03, 0.025, 1.2};
  s.paper[1].rotation_scale = {0.03, 0.025, 1.2};
  s.paper[1].translation_scale = {1.5, 1.0, 1.0};
  s.meta.generator = "test \"quoted\" \\ back";
  s.meta.created = "2026-01-01T00:00:00Z";
  s.meta.note = "line1\nline2";
  s.meta.recordings = {"/a/b", "c d"};
  return s;
}

void expect_same(const dsp::Calibration& a, const dsp::Calibration& b) {
  EXPECT_EQ(a.pixel_pitch_m, b.pixel_pitch_m);
  EXPECT_EQ(a.pixel_aspect_y, b.pixel_aspect_y);
  EXPECT_EQ(a.normal_gain_density, b.normal_gain_density);
  EXPECT_EQ(a.normal_gain_divergence, b.normal_gain_divergence);
  EXPECT_EQ(a.shear_gain_d, b.shear_gain_d);
  EXPECT_EQ(a.shear_gain_r, b.shear_gain_r);
  EXPECT_EQ(a.shear_gain_k, b.shear_gain_k);
  EXPECT_EQ(a.contact_tau_on, b.contact_tau_on);
  EXPECT_EQ(a.contact_tau_off, b.contact_tau_off);
  EXPECT_EQ(a.contact_min_area_cells, b.contact_min_area_cells);
  EXPECT_EQ(a.height_gain_m, b.height_gain_m);
  EXPECT_EQ(a.height_max_m, b.height_max_m);
  EXPECT_EQ(a.velocity_proxy, b.velocity_proxy);
  EXPECT_EQ(a.c_velocity, b.c_velocity);
  EXPECT_EQ(a.c_displacement, b.c_displacement);
  EXPECT_EQ(a.slip_relax_rate_on, b.slip_relax_rate_on);
  EXPECT_EQ(a.slip_on_frames, b.slip_on_frames);
  EXPECT_EQ(a.slip_min_shift_m, b.slip_min_shift_m);
  EXPECT_EQ(a.slip_exit_fraction, b.slip_exit_fraction);
  EXPECT_EQ(a.stick_rest_speed_m_s, b.stick_rest_speed_m_s);
  EXPECT_EQ(a.stick_confirm_s, b.stick_confirm_s);
  EXPECT_EQ(a.slip_catchup_frames, b.slip_catchup_frames);
  EXPECT_EQ(a.slip_smoothing_s, b.slip_smoothing_s);
  EXPECT_EQ(a.release_load_rate, b.release_load_rate);
  EXPECT_EQ(a.max_mask_change, b.max_mask_change);
  EXPECT_EQ(a.max_mask_area_ratio, b.max_mask_area_ratio);
  EXPECT_EQ(a.rotation_scale, b.rotation_scale);
  EXPECT_EQ(a.displacement_rotation_ratio, b.displacement_rotation_ratio);
  EXPECT_EQ(a.translation_scale, b.translation_scale);
  EXPECT_EQ(a.moving_average_length, b.moving_average_length);
  EXPECT_EQ(a.solve_lambda_rel, b.solve_lambda_rel);
  EXPECT_EQ(a.solve_lever_floor_m, b.solve_lever_floor_m);
  EXPECT_EQ(a.solve_rcond_min, b.solve_rcond_min);
}

TEST(CalibrationFile, MinimalFileGivesThePipelineDefaults) {
  cfg::CalibrationSet set;
  set.sensor[0].c_velocity = 1.0;
  ASSERT_TRUE(parse(kHead, &set).ok());
  for (const auto& c : set.sensor) expect_same(c, dsp::Calibration{});
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(set.paper[i].rotation_scale, set.sensor[i].rotation_scale);
    EXPECT_EQ(set.paper[i].translation_scale, set.sensor[i].translation_scale);
  }
}

TEST(CalibrationFile, RoundTripIsExact) {
  const cfg::CalibrationSet in = odd_set();
  std::string text, err;
  ASSERT_TRUE(cfg::format_calibration(in, &text, &err)) << err;
  cfg::CalibrationSet out;
  const cfg::Status s = parse(text, &out);
  ASSERT_TRUE(s.ok()) << s.message() << "\n" << text;
  for (std::size_t i = 0; i < 2; ++i) {
    expect_same(in.sensor[i], out.sensor[i]);
    EXPECT_EQ(in.paper[i].rotation_scale, out.paper[i].rotation_scale);
    EXPECT_EQ(in.paper[i].translation_scale, out.paper[i].translation_scale);
  }
  EXPECT_EQ(out.meta.generator, in.meta.generator);
  EXPECT_EQ(out.meta.note, in.meta.note);
  EXPECT_EQ(out.meta.recordings, in.meta.recordings);
  // Shared values are written once in [sensor], differing ones per sensor.
  EXPECT_NE(text.find("[sensor]\npixel_pitch_m = 1e-04\n"), std::string::npos) << text;
  EXPECT_NE(text.find("[right]\nvelocity_proxy = \"auto\"\nc_velocity = 0.0081\n"
                      "slip_relax_rate_on = 2.5\nslip_on_frames = 6\nstick_confirm_s = 0.75\n"
                      "release_load_rate = 6.5\nmax_mask_area_ratio = 2.25\ntranslation_scale = "
                      "[1.1, 0.9, 1.0]"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("velocity_proxy = \"displacement\""), std::string::npos);
  // Formatting what was parsed gives the same text (stable files for version control).
  std::string again;
  ASSERT_TRUE(cfg::format_calibration(out, &again, &err));
  EXPECT_EQ(again, text);
}

TEST(CalibrationFile, SaveAndLoadThroughTheDisk) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("tacse3_test_calibration_file_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto file = dir / "cal.toml";
  const cfg::CalibrationSet in = odd_set();
  ASSERT_TRUE(cfg::save_calibration(file, in).ok());
  EXPECT_FALSE(std::filesystem::exists(dir / "cal.toml.tmp"));
  cfg::CalibrationSet out;
  const cfg::Status s = cfg::load_calibration(file, &out);
  ASSERT_TRUE(s.ok()) << s.message();
  expect_same(out.sensor[1], in.sensor[1]);
  const cfg::Status missing = cfg::load_calibration(dir / "nope.toml", &out);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.message().find("nope.toml: no such file"), std::string::npos);
  const cfg::Status isdir = cfg::load_calibration(dir, &out);
  ASSERT_FALSE(isdir.ok());
  EXPECT_NE(isdir.message().find("is a directory"), std::string::npos);
  std::filesystem::remove_all(dir);
}

namespace fs = std::filesystem;

// A fresh scratch folder per test, removed at the end.
struct Scratch {
  explicit Scratch(const std::string& name)
      : dir(fs::temp_directory_path() /
            ("tacse3_test_calibration_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Scratch() {
    std::error_code ec;
    fs::permissions(dir, fs::perms::owner_all, fs::perm_options::add, ec);
    fs::remove_all(dir, ec);
  }
  fs::path dir;
};

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// load_calibration in a thread, given 5 s. Should it block on the FIFO (the defect), opening the
// FIFO for writing releases it, so the test fails instead of hanging.
cfg::Status load_with_deadline(const fs::path& file) {
  cfg::CalibrationSet out;
  auto done = std::async(std::launch::async, [&] { return cfg::load_calibration(file, &out); });
  if (done.wait_for(std::chrono::seconds(5)) != std::future_status::ready) {
    const int fd = ::open(file.c_str(), O_WRONLY | O_NONBLOCK);
    if (fd >= 0) ::close(fd);
    ADD_FAILURE() << file << ": load_calibration blocked";
  }
  return done.get();
}

TEST(CalibrationFile, LoadRefusesAFifoOrADeviceAtOnce) {
  const Scratch s("load_fifo");
  const fs::path fifo = s.dir / "cal.toml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const cfg::Status f = load_with_deadline(fifo);
  ASSERT_FALSE(f.ok());
  EXPECT_NE(f.message().find(fifo.string() + ": is a FIFO, expected a calibration file"),
            std::string::npos)
      << f.message();
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(fifo)));
  const cfg::Status d = load_with_deadline("/dev/null");
  ASSERT_FALSE(d.ok());
  EXPECT_NE(d.message().find("/dev/null: is a character device"), std::string::npos) << d.message();
  // A sparse file just over the bound is refused by its size, without reading it.
  const fs::path big = s.dir / "big.toml";
  std::ofstream(big) << kHead;
  fs::resize_file(big, cfg::kMaxCalibrationBytes + 1);
  const cfg::Status b = load_with_deadline(big);
  ASSERT_FALSE(b.ok());
  EXPECT_NE(b.message().find("big.toml: file is larger than 1 MiB"), std::string::npos)
      << b.message();
}

TEST(CalibrationFile, SaveReplacesOnlyARegularFileAndKeepsItsMode) {
  const Scratch s("save_regular");
  const fs::path file = s.dir / "cal.toml";
  std::ofstream(file) << "original\n";
  fs::permissions(file, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  ASSERT_TRUE(cfg::save_calibration(file, odd_set()).ok());
  cfg::CalibrationSet back;
  const cfg::Status l = cfg::load_calibration(file, &back);
  ASSERT_TRUE(l.ok()) << l.message();
  expect_same(back.sensor[1], odd_set().sensor[1]);
  EXPECT_EQ(fs::status(file).permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  // The temporary file went into place: nothing else is left in the folder.
  EXPECT_EQ(std::distance(fs::directory_iterator(s.dir), fs::directory_iterator()), 1);
}

TEST(CalibrationFile, SaveRefusesSymlinksFifosDirectoriesAndDevices) {
  const Scratch s("save_refused");
  const fs::path real = s.dir / "real.toml";
  std::ofstream(real) << "original\n";
  const fs::path link = s.dir / "link.toml";
  fs::create_symlink(real, link);
  const fs::path fifo = s.dir / "fifo.toml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const fs::path dir = s.dir / "dir.toml";
  fs::create_directory(dir);
  const std::pair<fs::path, const char*> cases[] = {
      {link, "is a symbolic link"}, {fifo, "is a FIFO"}, {dir, "is a directory"}};
  for (const auto& [target, kind] : cases) {
    const cfg::Status st = cfg::save_calibration(target, odd_set());
    ASSERT_FALSE(st.ok()) << target;
    EXPECT_NE(st.message().find(target.string() + ": " + kind + "; refusing to replace it"),
              std::string::npos)
        << st.message();
  }
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(read_text(real), "original\n");
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(fifo)));
  EXPECT_TRUE(fs::is_directory(fs::symlink_status(dir)));
  EXPECT_EQ(std::distance(fs::directory_iterator(s.dir), fs::directory_iterator()), 4);
  // /dev/null only through the check that save_calibration makes first: never written to.
  const cfg::Status null = cfg::check_calibration_output("/dev/null");
  ASSERT_FALSE(null.ok());
  EXPECT_NE(null.message().find("/dev/null: is a character device; refusing to replace it"),
            std::string::npos)
      << null.message();
  EXPECT_FALSE(cfg::save_calibration("/dev/null", odd_set()).ok());
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
}

TEST(CalibrationFile, OutputCheckNamesAMissingOrUnwritableDirectory) {
  const Scratch s("save_dir");
  const fs::path missing = s.dir / "no-such-dir" / "cal.toml";
  const cfg::Status m = cfg::check_calibration_output(missing);
  ASSERT_FALSE(m.ok());
  EXPECT_NE(
      m.message().find("the directory " + (s.dir / "no-such-dir").string() + " does not exist"),
      std::string::npos)
      << m.message();
  EXPECT_FALSE(cfg::save_calibration(missing, odd_set()).ok());
  EXPECT_TRUE(cfg::check_calibration_output(s.dir / "new.toml").ok());
  EXPECT_FALSE(cfg::check_calibration_output("").ok());
  // Root writes anywhere, so the permission case runs only for other users.
  if (::geteuid() != 0) {
    const fs::path ro = s.dir / "ro";
    fs::create_directory(ro);
    fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec);
    const cfg::Status r = cfg::check_calibration_output(ro / "cal.toml");
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.message().find("cannot write in the directory " + ro.string()), std::string::npos)
        << r.message();
    fs::permissions(ro, fs::perms::owner_all);
  }
}

TEST(CalibrationFile, OverridesAndPaperScales) {
  cfg::CalibrationSet set;
  ASSERT_TRUE(parse(kHead + "[sensor]\nc_velocity = 0.01\nrotation_scale = [2, 2, 2]\n"
                            "[right]\nc_velocity = 0.02\n"
                            "[paper]\nrotation_scale = [0.03, 0.04, 1]\n"
                            "[paper.left]\ntranslation_scale = [1.5, 1, 1]\n",
                    &set)
                  .ok());
  EXPECT_EQ(set.sensor[0].c_velocity, 0.01);
  EXPECT_EQ(set.sensor[1].c_velocity, 0.02);
  const auto joint = set.for_method(dsp::FusionMethod::kJoint);
  const auto paper = set.for_method(dsp::FusionMethod::kPaper);
  EXPECT_EQ(joint[0].rotation_scale, (std::array<double, 3>{2, 2, 2}));
  EXPECT_EQ(paper[0].rotation_scale, (std::array<double, 3>{0.03, 0.04, 1}));
  EXPECT_EQ(paper[1].rotation_scale, (std::array<double, 3>{0.03, 0.04, 1}));
  EXPECT_EQ(paper[0].translation_scale, (std::array<double, 3>{1.5, 1, 1}));
  EXPECT_EQ(paper[1].translation_scale, (std::array<double, 3>{1, 1, 1}));
  EXPECT_EQ(paper[1].c_velocity, 0.02);  // only the scales differ between methods
}

TEST(CalibrationFile, HeaderErrors) {
  expect_error("version = 1\n", {"cal.toml", "missing required key \"format\""});
  expect_error("format = \"tacse3-recording\"\nversion = 1\n",
               {"cal.toml:1:", "\"format\" must be \"tacse3-calibration\"", "tacse3-recording"});
  expect_error("format = \"tacse3-calibration\"\n", {"missing required key \"version\""});
  expect_error("format = \"tacse3-calibration\"\nversion = 2\n",
               {"cal.toml:2:", "version 2 is not supported", "knows version 1"});
  expect_error("format = \"tacse3-calibration\"\nversion = \"1\"\n",
               {"\"version\" must be an integer, got a string"});
  expect_error(kHead + "[sensor\n", {"cal.toml:3:", "TOML syntax error"});
  expect_error(kHead + "colour = 3\n", {"cal.toml:3:", "unknown key \"colour\"", "[sensor]"});
  expect_error(kHead + "sensor = 3\n", {"key \"sensor\" must be a table, got an integer"});
}

TEST(CalibrationFile, TyposAreErrorsNamingTheKey) {
  expect_error(kHead + "[sensor]\nc_velocty = 0.01\n",
               {"cal.toml:4:", "unknown key \"sensor.c_velocty\"", "c_velocity"});
  expect_error(kHead + "[left]\nshear_gain_x = 1\n", {"unknown key \"left.shear_gain_x\""});
  expect_error(kHead + "[paper]\nc_velocity = 1\n", {"unknown key \"paper.c_velocity\""});
  expect_error(kHead + "[paper.left]\nrotation_scale = [1, 1, 1]\nextra = 1\n",
               {"unknown key \"paper.left.extra\""});
  expect_error(kHead + "[meta]\nauthor = \"me\"\n", {"unknown key \"meta.author\""});
}

TEST(CalibrationFile, ValuesAreValidatedNamingTheKey) {
  expect_error(kHead + "[sensor]\nc_velocity = 0\n",
               {"cal.toml:4:", "key \"sensor.c_velocity\" must be in (0.0, 100.0], got 0.0"});
  expect_error(kHead + "[sensor]\nc_velocity = 101\n", {"\"sensor.c_velocity\"", "got 101"});
  expect_error(kHead + "[left]\npixel_pitch_m = 0.1\n", {"\"left.pixel_pitch_m\" must be in"});
  expect_error(kHead + "[right]\nc_displacement = nan\n", {"\"right.c_displacement\"", "got nan"});
  expect_error(kHead + "[right]\nheight_gain_m = inf\n", {"\"right.height_gain_m\"", "got inf"});
  expect_error(kHead + "[sensor]\nc_velocity = \"fast\"\n",
               {"\"sensor.c_velocity\" must be a number, got a string"});
  expect_error(kHead + "[sensor]\ncontact_min_area_cells = 2.5\n",
               {"\"sensor.contact_min_area_cells\" must be an integer, got a float"});
  expect_error(kHead + "[sensor]\ncontact_min_area_cells = 0\n",
               {"\"sensor.contact_min_area_cells\" must be an integer in [1, 1200], got 0"});
  expect_error(kHead + "[sensor]\nmoving_average_length = 33\n",
               {"\"sensor.moving_average_length\"", "[1, 32]"});
  expect_error(kHead + "[sensor]\nsolve_rcond_min = 1\n", {"\"sensor.solve_rcond_min\"", "1.0)"});
  expect_error(kHead + "[left]\nrelease_load_rate = 0\n",
               {"\"left.release_load_rate\" must be in (0.0, 10000.0], got 0.0"});
  expect_error(kHead + "[sensor]\nrotation_scale = [1, 1]\n",
               {"\"sensor.rotation_scale\" must have 3 elements"});
  expect_error(kHead + "[sensor]\nrotation_scale = [1, -1, 1]\n",
               {"\"sensor.rotation_scale\" element 1 must be in [0.0, 100.0], got -1.0"});
  expect_error(kHead + "[sensor]\nrotation_scale = 1\n",
               {"\"sensor.rotation_scale\" must be an array of 3 numbers, got an integer"});
  expect_error(kHead + "[sensor]\nvelocity_proxy = \"fast\"\n",
               {"\"sensor.velocity_proxy\" must be one of velocity, displacement", "\"fast\""});
  expect_error(kHead + "[paper]\nrotation_scale = [1, 1, 1000]\n",
               {"\"paper.rotation_scale\" element 2"});
  expect_error(kHead + "[meta]\nrecordings = [1]\n",
               {"\"meta.recordings\" must hold only strings"});
}

TEST(CalibrationFile, CrossFieldRulesNameBothKeys) {
  expect_error(
      kHead + "[left]\ncontact_tau_on = 0.01\ncontact_tau_off = 0.02\n",
      {"cal.toml", "\"left.contact_tau_off\" (0.02) must not exceed", "left.contact_tau_on"});
  expect_error(kHead + "[right]\nslip_smoothing_s = 0.5\nrelease_load_rate = 2.5\n",
               {"\"right.release_load_rate\" (2.5) must be below 1 / \"right.slip_smoothing_s\"",
                "or 1e4 (off)"});
  // Merged: [sensor] sets the smoothing, [left] a rate above its ceiling.
  expect_error(kHead + "[sensor]\nslip_smoothing_s = 0.5\n[left]\nrelease_load_rate = 2.5\n",
               {"\"left.release_load_rate\" (2.5) must be below 1 / \"left.slip_smoothing_s\""});
  // Merged values count: [sensor] sets τ_off high, [right] lowers τ_on below it.
  expect_error(kHead + "[sensor]\ncontact_tau_off = 0.015\n[right]\ncontact_tau_on = 0.012\n",
               {"\"right.contact_tau_off\""});
}

TEST(CalibrationFile, FormatRefusesAnInvalidSet) {
  cfg::CalibrationSet s;
  s.sensor[1].c_velocity = -1.0;
  std::string text, err;
  EXPECT_FALSE(cfg::format_calibration(s, &text, &err));
  EXPECT_NE(err.find("right.c_velocity"), std::string::npos) << err;
  const cfg::Status v = cfg::validate(s, "x.toml");
  EXPECT_FALSE(v.ok());
  EXPECT_NE(v.message().find("x.toml"), std::string::npos);
}

TEST(CalibrationFile, EveryPrefixAndByteFlipFailsCleanly) {
  // A half-written or corrupted file is an error (or, for some prefixes, a valid subset); never
  // a crash, and the output is only written on success.
  std::string text, err;
  ASSERT_TRUE(cfg::format_calibration(odd_set(), &text, &err));
  for (std::size_t n = 0; n < text.size(); n += 7) {
    cfg::CalibrationSet set;
    const cfg::Status s = parse(text.substr(0, n), &set);
    if (!s.ok()) {
      EXPECT_NE(s.message().find("cal.toml"), std::string::npos) << s.message();
    }
  }
  // Every single-bit flip of every byte (toml++'s internal asserts must not abort on these).
  for (std::size_t i = 0; i < text.size(); ++i) {
    for (int bit = 0; bit < 8; ++bit) {
      std::string t = text;
      t[i] = static_cast<char>(t[i] ^ (1 << bit));
      cfg::CalibrationSet set;
      const cfg::Status s = parse(t, &set);
      if (!s.ok()) {
        EXPECT_FALSE(s.message().empty());
      }
    }
  }
}

TEST(CalibrationFile, EveryCalibrationFieldHasAKey) {
  // If dsp::Calibration gains a field, the file must learn it (this list is the file's).
  const auto keys = cfg::sensor_keys();
  EXPECT_EQ(keys.size(), 34u);
  EXPECT_EQ(keys.front(), "pixel_pitch_m");
  EXPECT_EQ(std::count(keys.begin(), keys.end(), "velocity_proxy"), 1);
  // The eight thresholds of the stick/slip detector (VelocityProxy::kAuto).
  for (const char* k :
       {"slip_relax_rate_on", "slip_on_frames", "slip_min_shift_m", "slip_exit_fraction",
        "stick_rest_speed_m_s", "stick_confirm_s", "slip_catchup_frames", "slip_smoothing_s"}) {
    EXPECT_EQ(std::count(keys.begin(), keys.end(), k), 1) << k;
  }
}

}  // namespace

namespace {

// config::Status and protocol::Status share one convention: `!s` is a failure, no bool.
static_assert(!std::is_constructible_v<bool, cfg::Status>);
static_assert(!std::is_convertible_v<cfg::Status, bool>);

TEST(CalibrationStatus, NotIsFailure) {
  EXPECT_FALSE(!cfg::Status());
  EXPECT_TRUE(!cfg::Status::error("x.toml: bad"));
}

TEST(CalibrationFitted, OnlyFilesWithSensorKeysAreFitted) {
  cfg::CalibrationSet set;
  EXPECT_FALSE(set.fitted);  // built-in defaults
  ASSERT_TRUE(parse(kHead, &set).ok());
  EXPECT_FALSE(set.fitted);  // the header alone (the package's /etc/tacse3/calibration.toml)
  ASSERT_TRUE(parse(kHead + "[meta]\nnote = \"x\"\n", &set).ok());
  EXPECT_FALSE(set.fitted);
  ASSERT_TRUE(parse(kHead + "[sensor]\nc_velocity = 0.01\n", &set).ok());
  EXPECT_TRUE(set.fitted);
  cfg::CalibrationSet right;
  ASSERT_TRUE(parse(kHead + "[right]\nc_velocity = 0.01\n", &right).ok());
  EXPECT_TRUE(right.fitted);
}

TEST(CalibrationFitted, WrittenSetsReadBackFitted) {
  // format_calibration writes every key, so whatever a tool saves counts as fitted.
  std::string text, error;
  ASSERT_TRUE(cfg::format_calibration(cfg::CalibrationSet{}, &text, &error)) << error;
  cfg::CalibrationSet set;
  ASSERT_TRUE(parse(text, &set).ok());
  EXPECT_TRUE(set.fitted);
}

TEST(SimCalibration, InstalledCopyFirstThenTheSourceTree) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / ("tacse3_simcal_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "bin");
  fs::create_directories(root / "share" / "tacse3");
  const fs::path source = root / "source.toml";
  std::ofstream(source) << kHead;
  EXPECT_EQ(cfg::find_sim_calibration(root / "bin", source), source);
  EXPECT_EQ(cfg::find_sim_calibration({}, source), source);
  EXPECT_TRUE(cfg::find_sim_calibration(root / "bin", root / "absent.toml").empty());
  const fs::path installed = root / "share" / "tacse3" / "sim-calibration.toml";
  std::ofstream(installed) << kHead;
  EXPECT_EQ(cfg::find_sim_calibration(root / "bin", source), installed);
  fs::remove_all(root);
}

}  // namespace
// The calibration reader refuses, before toml++ sees it, the text that reaches undefined
// behaviour in toml++ 3.3 (the same check as the board reader; tests/config/test_board_file.cpp).
TEST(CalibrationFile, NonAsciiOutsideStringsIsRefusedBeforeToml) {
  expect_error(kHead + "[left]\n\xef\xbb\xbe = 1\n",
               {"cal.toml:4:1: TOML syntax error: a non-ASCII character outside a string"});
  cfg::CalibrationSet set;
  EXPECT_TRUE(parse("# \xc2\xb1 0.5 \xc2\xb0\n" + kHead, &set).ok());
}
