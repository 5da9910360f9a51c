// SPDX-License-Identifier: Apache-2.0
// Tests of the recording format: round trip, and a clear error for every kind of bad input.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <future>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "tacse3/recording/recording.hpp"

namespace tacse3::recording {
namespace {
namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    static int counter = 0;
    path_ = fs::temp_directory_path() /
            ("tacse3_rec_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

Image random_image(int w, int h, int channels, unsigned seed) {
  Image im{w, h, channels, {}};
  im.pixels.resize(static_cast<std::size_t>(w) * h * channels);
  std::mt19937 rng(seed);
  for (auto& p : im.pixels) p = static_cast<std::uint8_t>(rng() & 0xFF);
  return im;
}

RecordingInfo small_info(int channels_unused = 3) {
  (void)channels_unused;
  RecordingInfo info;
  info.width = 32;
  info.height = 24;
  info.fps = 120.0;
  info.rig.pixel_pitch_mm = 0.1;
  info.rig.finger_separation_mm = 38.0;
  return info;
}

// Writes a valid 3-frame recording and returns the images written, [frame][slot].
std::vector<std::vector<Image>> write_valid(const fs::path& dir, int channels = 3,
                                            RecordingInfo info = small_info()) {
  auto w = RecordingWriter::open(dir, info);
  EXPECT_TRUE(w) << w.status().message();
  std::vector<std::vector<Image>> frames;
  for (int i = 0; i < 3; ++i) {
    std::vector<Image> ims;
    std::vector<ImageView> views;
    for (std::size_t s = 0; s < info.sensors.size(); ++s) {
      ims.push_back(
          random_image(info.width, info.height, channels, static_cast<unsigned>(10 * i + s)));
    }
    for (const auto& im : ims) views.push_back(view(im));
    std::int64_t index = -1;
    EXPECT_TRUE(w.value()->write_frame(1000 + i * 8333333LL, views, &index));
    EXPECT_EQ(index, i);
    TruthSample t;
    t.t_ns = 1000 + i * 8333333LL;
    t.qw = std::cos(0.01 * i);
    t.qz = std::sin(0.01 * i);
    t.px = 1e-4 * i;
    EXPECT_TRUE(w.value()->append_truth(t));
    frames.push_back(std::move(ims));
  }
  EXPECT_TRUE(w.value()->finish());
  return frames;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_file(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::trunc);
  out << text;
}

void replace_in(const fs::path& p, const std::string& from, const std::string& to) {
  std::string s = read_file(p);
  const auto pos = s.find(from);
  ASSERT_NE(pos, std::string::npos) << from;
  s.replace(pos, from.size(), to);
  write_file(p, s);
}

// Opening must fail with a message that contains every fragment.
void expect_error(const fs::path& dir, std::initializer_list<const char*> fragments) {
  auto r = RecordingReader::open(dir);
  ASSERT_FALSE(r) << "opened a bad recording";
  for (const char* f : fragments) {
    EXPECT_NE(r.status().message().find(f), std::string::npos)
        << "message \"" << r.status().message() << "\" lacks \"" << f << "\"";
  }
}

TEST(Recording, RoundTripIsPixelExact) {
  for (int channels : {3, 1}) {
    TempDir tmp;
    const auto written = write_valid(tmp.path(), channels);
    auto r = RecordingReader::open(tmp.path());
    ASSERT_TRUE(r) << r.status().message();
    const RecordingReader& rec = r.value();
    EXPECT_EQ(rec.info().width, 32);
    EXPECT_EQ(rec.info().height, 24);
    EXPECT_DOUBLE_EQ(rec.info().fps, 120.0);
    EXPECT_DOUBLE_EQ(rec.info().rig.pixel_pitch_mm, 0.1);
    EXPECT_DOUBLE_EQ(rec.info().rig.finger_separation_mm, 38.0);
    EXPECT_EQ(rec.info().rig.layout, "mirrored");
    ASSERT_EQ(rec.sensor_count(), 2u);
    EXPECT_EQ(rec.slot_of(SensorId::kLeft), 0);
    EXPECT_EQ(rec.slot_of(SensorId::kRight), 1);
    EXPECT_EQ(rec.channels(), channels);
    ASSERT_EQ(rec.frame_count(), 3u);
    ASSERT_TRUE(rec.has_truth());
    ASSERT_EQ(rec.truth().size(), 3u);
    RecordingReader::Frame frame;
    for (std::size_t i = 0; i < 3; ++i) {
      ASSERT_TRUE(rec.read_frame(i, &frame));
      EXPECT_EQ(frame.index, static_cast<std::int64_t>(i));
      EXPECT_EQ(frame.t_ns, 1000 + static_cast<std::int64_t>(i) * 8333333);
      for (std::size_t s = 0; s < 2; ++s) {
        EXPECT_EQ(frame.images[s].channels, channels);
        EXPECT_EQ(frame.images[s].pixels, written[i][s].pixels) << "frame " << i << " slot " << s;
      }
      ASSERT_NE(frame.truth, nullptr);
      EXPECT_NEAR(frame.truth->qw, std::cos(0.01 * i), 1e-12);
      EXPECT_NEAR(frame.truth->qz, std::sin(0.01 * i), 1e-12);
      EXPECT_NEAR(frame.truth->px, 1e-4 * i, 1e-12);
    }
    EXPECT_FALSE(rec.has_sim_labels());
  }
}

TEST(Recording, OneSensorExtraKeysAndLabels) {
  TempDir tmp;
  RecordingInfo info = small_info();
  info.sensors = {SensorId::kRight};
  info.extra_json = R"({"sim": {"object": "sphere", "seed": 3}})";
  write_valid(tmp.path(), 3, info);
  {
    auto w = RecordingWriter::open(tmp.path(), info);
    EXPECT_FALSE(w);  // not empty
    EXPECT_NE(w.status().message().find("not empty"), std::string::npos);
  }
  // Labels are an optional simulator extension.
  SimLabel l;
  l.index = 0;
  l.t_ns = 1000;
  l.sensor = SensorId::kRight;
  l.phase = "motion";
  l.in_contact = true;
  l.slipping = true;
  l.slip_fraction = 0.75;
  l.area_mm2 = 123.5;
  std::ofstream(tmp.path() / "sim_labels.csv")
      << "index,t_ns,sensor,phase,in_contact,slipping,slip_fraction,area_mm2,centroid_u_mm,"
         "centroid_v_mm,peak_depth_mm\n0,1000,right,motion,1,1,0.75,123.5,0.1,-0.2,1.0\n";
  auto r = RecordingReader::open(tmp.path());
  ASSERT_TRUE(r) << r.status().message();
  EXPECT_EQ(r.value().sensor_count(), 1u);
  EXPECT_EQ(r.value().slot_of(SensorId::kLeft), -1);
  EXPECT_EQ(r.value().slot_of(SensorId::kRight), 0);
  EXPECT_NE(r.value().info().extra_json.find("\"sim\""), std::string::npos);
  ASSERT_TRUE(r.value().has_sim_labels());
  ASSERT_EQ(r.value().sim_labels().size(), 1u);
  EXPECT_EQ(r.value().sim_labels()[0].phase, "motion");
  EXPECT_TRUE(r.value().sim_labels()[0].slipping);
  EXPECT_DOUBLE_EQ(r.value().sim_labels()[0].slip_fraction, 0.75);
  EXPECT_DOUBLE_EQ(r.value().sim_labels()[0].centroid_v_mm, -0.2);
  // Unknown keys anywhere are ignored.
  replace_in(tmp.path() / "recording.json", "\"fps\"", "\"future_key\": [1, 2], \"fps\"");
  replace_in(tmp.path() / "recording.json", "\"layout\"", "\"future\": {\"a\": 1}, \"layout\"");
  EXPECT_TRUE(RecordingReader::open(tmp.path()));
  // The writer refuses to let extra keys redefine the format.
  TempDir tmp2;
  info.extra_json = R"({"fps": 60})";
  EXPECT_FALSE(RecordingWriter::open(tmp2.path(), info));
}

TEST(Recording, OverwriteReplacesOnlyRecordingFiles) {
  TempDir tmp;
  write_valid(tmp.path());
  write_file(tmp.path() / "notes.txt", "keep me");
  WriterOptions opt;
  opt.overwrite = true;
  RecordingInfo info = small_info();
  info.sensors = {SensorId::kLeft};
  auto w = RecordingWriter::open(tmp.path(), info, opt);
  ASSERT_TRUE(w) << w.status().message();
  const Image im = random_image(32, 24, 3, 99);
  const ImageView v = view(im);
  ASSERT_TRUE(w.value()->write_frame(5, std::span<const ImageView>(&v, 1)));
  ASSERT_TRUE(w.value()->finish());
  auto r = RecordingReader::open(tmp.path());
  ASSERT_TRUE(r) << r.status().message();
  EXPECT_EQ(r.value().frame_count(), 1u);
  EXPECT_FALSE(r.value().has_truth());
  EXPECT_FALSE(fs::exists(tmp.path() / "right"));
  EXPECT_EQ(read_file(tmp.path() / "notes.txt"), "keep me");
}

TEST(Recording, MissingOrWrongJsonKeysAreNamed) {
  struct Case {
    const char* from;
    const char* to;
    std::initializer_list<const char*> fragments;
  };
  const Case cases[] = {
      {"\"width\": 32,", "", {"recording.json", "missing required key \"width\""}},
      {"\"fps\": 120.0,", "", {"missing required key \"fps\""}},
      {"\"format\": \"tacse3-recording\",", "", {"missing required key \"format\""}},
      {"\"pixel_pitch_mm\": 0.1,", "", {"missing required key \"rig.pixel_pitch_mm\""}},
      {"\"layout\": \"mirrored\"", "\"other\": 1", {"missing required key \"rig.layout\""}},
      {"\"width\": 32",
       "\"width\": \"32\"",
       {"key \"width\" must be a positive integer", "string"}},
      {"\"width\": 32", "\"width\": 32.5", {"key \"width\" must be a positive integer"}},
      {"\"height\": 24", "\"height\": -24", {"key \"height\" must be in [1, 65535]"}},
      {"\"fps\": 120.0", "\"fps\": 0", {"key \"fps\" must be a positive number"}},
      {"\"fps\": 120.0", "\"fps\": [120]", {"key \"fps\" must be a number", "array"}},
      {"\"version\": 1", "\"version\": 2", {"unsupported version 2"}},
      {"\"tacse3-recording\"", "\"other-format\"", {"key \"format\" must be \"tacse3-recording\""}},
      {"\"mirrored\"", "\"parallel\"", {"key \"rig.layout\" must be \"mirrored\""}},
      {"\"right\"", "\"middle\"", {"key \"sensors[1]\" must be \"left\" or \"right\""}},
      {"\"right\"", "\"left\"", {"lists \"left\" twice"}},
      {"\"finger_separation_mm\": 38.0",
       "\"finger_separation_mm\": null",
       {"key \"rig.finger_separation_mm\" must be a number", "null"}},
      {"\"rig\": {", "\"rig\": 5, \"x\": {", {"key \"rig\" must be an object"}},
      {"{", "{,", {"recording.json: not valid JSON"}},
  };
  for (const Case& c : cases) {
    TempDir tmp;
    write_valid(tmp.path());
    replace_in(tmp.path() / "recording.json", c.from, c.to);
    SCOPED_TRACE(std::string(c.from) + " -> " + c.to);
    expect_error(tmp.path(), c.fragments);
  }
  TempDir tmp;
  write_valid(tmp.path());
  fs::remove(tmp.path() / "recording.json");
  expect_error(tmp.path(), {"recording.json: missing"});
}

TEST(Recording, BadPngFilesAreNamed) {
  {  // a missing frame
    TempDir tmp;
    write_valid(tmp.path());
    fs::remove(tmp.path() / "left" / "000001.png");
    expect_error(tmp.path(), {"left/000001.png", "missing"});
  }
  {  // an extra frame: count mismatch
    TempDir tmp;
    write_valid(tmp.path());
    fs::copy_file(tmp.path() / "right" / "000000.png", tmp.path() / "right" / "000003.png");
    expect_error(tmp.path(), {"right/", "frame count mismatch", "4 PNG files", "3 frames"});
  }
  {  // wrong size
    TempDir tmp;
    write_valid(tmp.path());
    const Image im = random_image(30, 24, 3, 5);
    ASSERT_TRUE(write_png(tmp.path() / "right" / "000002.png", view(im), 1));
    expect_error(tmp.path(), {"right/000002.png", "30x24", "32x24"});
  }
  {  // a header that claims 30720x65280 (found by fuzz_png): refused before any allocation
    TempDir tmp;
    fs::create_directories(tmp.path());
    const fs::path p = tmp.path() / "huge.png";
    const unsigned char bytes[] = {0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00,
                                   0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00, 0x78, 0x00,
                                   0x00, 0x00, 0xff, 0x00, 0x08, 0x02, 0x00, 0x00, 0x00};
    write_file(p, std::string(reinterpret_cast<const char*>(bytes), sizeof(bytes)));
    Image im;
    const Status s = read_png(p, &im);
    ASSERT_FALSE(s);
    EXPECT_NE(s.message().find("huge.png: PNG is larger than 4096 pixels on a side"),
              std::string::npos)
        << s.message();
    EXPECT_TRUE(im.pixels.empty());
  }
  {  // 16-bit and RGBA PNGs, written by hand-made headers
    for (int which = 0; which < 2; ++which) {
      TempDir tmp;
      write_valid(tmp.path());
      const fs::path p = tmp.path() / "left" / "000000.png";
      std::string bytes = read_file(p);
      if (which == 0) bytes[24] = 16;  // bit depth
      if (which == 1) bytes[25] = 6;   // colour type RGBA
      write_file(p, bytes);
      expect_error(tmp.path(), {"left/000000.png", "8-bit RGB or 8-bit grey",
                                which == 0 ? "bit depth 16" : "colour type 6"});
    }
  }
  {  // not a PNG at all
    TempDir tmp;
    write_valid(tmp.path());
    write_file(tmp.path() / "left" / "000002.png", "hello, this is not a png file at all!");
    expect_error(tmp.path(), {"left/000002.png", "not a PNG file"});
  }
  {  // grey and RGB mixed within one recording
    TempDir tmp;
    write_valid(tmp.path());
    const Image im = random_image(32, 24, 1, 5);
    ASSERT_TRUE(write_png(tmp.path() / "left" / "000001.png", view(im), 1));
    expect_error(tmp.path(), {"left/000001.png", "grey", "RGB"});
  }
  {  // a sensor directory missing
    TempDir tmp;
    write_valid(tmp.path());
    fs::remove_all(tmp.path() / "right");
    expect_error(tmp.path(), {"right/", "missing directory"});
  }
  {  // a corrupt PNG body is caught when the frame is decoded
    TempDir tmp;
    write_valid(tmp.path());
    const fs::path p = tmp.path() / "left" / "000001.png";
    std::string bytes = read_file(p);
    for (std::size_t k = 60; k < bytes.size() - 20; ++k)
      bytes[k] = static_cast<char>(bytes[k] ^ 0x5A);
    write_file(p, bytes);
    auto r = RecordingReader::open(tmp.path());
    ASSERT_TRUE(r) << r.status().message();
    Image im;
    const Status s = r.value().read_image(0, 1, &im);
    EXPECT_FALSE(s);
    EXPECT_NE(s.message().find("left/000001.png"), std::string::npos) << s.message();
  }
}

TEST(Recording, BadCsvRowsAreNamedWithTheirLine) {
  struct Case {
    const char* file;
    const char* from;
    const char* to;
    std::initializer_list<const char*> fragments;
  };
  const Case cases[] = {
      {"frames.csv", "index,t_ns", "idx,t", {"frames.csv line 1", "header must be \"index,t_ns\""}},
      {"frames.csv", "1,8334333", "1,8334333,7", {"frames.csv line 3", "expected 2 fields, got 3"}},
      {"frames.csv", "1,8334333", "1,abc", {"frames.csv line 3", "t_ns \"abc\" is not an integer"}},
      {"frames.csv",
       "1,8334333",
       "2,8334333",
       {"frames.csv line 3", "index 2 where 1 was expected"}},
      {"frames.csv", "1,8334333", "1,1000", {"frames.csv line 3", "is not after the previous row"}},
      {"frames.csv", "2,16667666\n", "", {"left/", "frame count mismatch"}},
      {"frames.csv", "1,8334333\n", "\n1,8334333\n", {"frames.csv line 3", "empty line"}},
      // Spans over kMaxSpanNs (1e6 s), one far enough apart that the difference overflows int64.
      {"frames.csv",
       "0,1000\n",
       "0,-9223372036854775807\n",
       {"frames.csv line 3", "more than 1e6 s after the first row's -9223372036854775807"}},
      {"frames.csv",
       "2,16667666",
       "2,1000000000001001",
       {"frames.csv line 4", "a recording spans at most 1e6 s"}},
      {"truth.csv",
       "\n16667666,",
       "\n1000000000001001,",
       {"truth.csv line 4", "a recording spans at most 1e6 s"}},
      {"truth.csv", "t_ns,qw", "t,qw", {"truth.csv line 1", "header must be"}},
      {"truth.csv", "8334333,", "8334333,x", {"truth.csv line 3", "qw \"x", "not a finite number"}},
      {"truth.csv", "8334333,", "8334333,1,", {"truth.csv line 3", "expected 8 fields, got 9"}},
      {"truth.csv", "8334333,", "8334333,nan,", {"truth.csv line 3"}},
      {"truth.csv",
       "\n8334333,0.99",
       "\n8334333,0.5",
       {"truth.csv line 3", "quaternion is not unit"}},
      {"truth.csv", "\n8334333,", "\n999,", {"truth.csv line 3", "is not after the previous row"}},
  };
  for (const Case& c : cases) {
    TempDir tmp;
    write_valid(tmp.path());
    SCOPED_TRACE(std::string(c.file) + ": " + c.from + " -> " + c.to);
    replace_in(tmp.path() / c.file, c.from, c.to);
    expect_error(tmp.path(), c.fragments);
  }
  TempDir tmp;
  write_valid(tmp.path());
  write_file(tmp.path() / "frames.csv", "");
  expect_error(tmp.path(), {"frames.csv", "empty file"});
  write_file(tmp.path() / "frames.csv", "index,t_ns\n");
  expect_error(tmp.path(), {"frames.csv: no frames"});
  fs::remove(tmp.path() / "frames.csv");
  expect_error(tmp.path(), {"frames.csv: missing"});
}

// RecordingReader::open in a thread, given 5 s. Should it block on a FIFO (the defect), opening
// the FIFOs for writing releases it, so the test fails instead of hanging.
Status open_with_deadline(const fs::path& dir, const std::vector<fs::path>& fifos) {
  auto done = std::async(std::launch::async, [&] { return RecordingReader::open(dir).status(); });
  if (done.wait_for(std::chrono::seconds(5)) != std::future_status::ready) {
    for (const auto& f : fifos) {
      const int fd = ::open(f.c_str(), O_WRONLY | O_NONBLOCK);
      if (fd >= 0) ::close(fd);
    }
    ADD_FAILURE() << dir << ": RecordingReader::open blocked";
  }
  return done.get();
}

// The replay users' arithmetic on time stamps: exact in range, clamped where int64 would overflow
// (UB that UBSan reports in the host-sanitize build).
TEST(Recording, ClampedTimeArithmeticNeverOverflows) {
  EXPECT_EQ(clamped_difference(5, -3), 8);
  EXPECT_EQ(clamped_difference(INT64_MAX, -1), INT64_MAX);
  EXPECT_EQ(clamped_difference(INT64_MIN, 1), INT64_MIN);
  EXPECT_EQ(clamped_difference(INT64_MAX, INT64_MIN), INT64_MAX);
  EXPECT_EQ(clamped_sum(INT64_MAX - 1, 5), INT64_MAX);
  EXPECT_EQ(clamped_sum(INT64_MIN + 1, -5), INT64_MIN);
  EXPECT_EQ(clamped_sum(-4, 6), 2);
}

// A span of exactly kMaxSpanNs is accepted; the bound is inclusive.
TEST(Recording, ASpanOfTheBoundIsAccepted) {
  TempDir tmp;
  write_valid(tmp.path());
  replace_in(tmp.path() / "frames.csv", "2,16667666", "2,1000000000001000");
  auto r = RecordingReader::open(tmp.path());
  ASSERT_TRUE(r) << r.status().message();
  EXPECT_EQ(r.value().t_ns(2) - r.value().t_ns(0), kMaxSpanNs);
}

TEST(Recording, TextFilesThatAreNotRegularFilesAreNamedAtOnce) {
  for (const char* name : {"recording.json", "frames.csv", "truth.csv", "sim_labels.csv"}) {
    SCOPED_TRACE(name);
    TempDir tmp;
    write_valid(tmp.path());
    const fs::path file = tmp.path() / name;
    fs::remove(file);
    ASSERT_EQ(::mkfifo(file.c_str(), 0600), 0);
    const Status s = open_with_deadline(tmp.path(), {file});
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.message().find(file.string() + ": is a FIFO, not a regular file"),
              std::string::npos)
        << s.message();
    EXPECT_TRUE(fs::is_fifo(fs::symlink_status(file)));
    // A device behind a symlink (frames.csv -> /dev/zero was the reported case; /dev/null here
    // so that a reader without the check reads nothing rather than forever).
    fs::remove(file);
    fs::create_symlink("/dev/null", file);
    const Status d = open_with_deadline(tmp.path(), {});
    ASSERT_FALSE(d.ok());
    EXPECT_NE(d.message().find(file.string() + ": is a character device"), std::string::npos)
        << d.message();
  }
}

TEST(Recording, TextFilesOverTheirSizeBoundAreRefused) {
  struct Case {
    const char* name;
    std::size_t bound;
    const char* fragment;
  };
  const Case cases[] = {{"recording.json", kMaxJsonBytes, "recording.json: larger than 1 MiB"},
                        {"frames.csv", kMaxCsvBytes, "frames.csv: larger than 64 MiB"},
                        {"truth.csv", kMaxCsvBytes, "truth.csv: larger than 64 MiB"},
                        {"sim_labels.csv", kMaxCsvBytes, "sim_labels.csv: larger than 64 MiB"}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    TempDir tmp;
    write_valid(tmp.path());
    // Sparse: the size is refused from fstat, nothing is read or stored.
    const fs::path file = tmp.path() / c.name;
    if (!fs::exists(file)) write_file(file, "");
    fs::resize_file(file, c.bound + 1);
    expect_error(tmp.path(), {c.fragment});
  }
}

TEST(Recording, CrlfAndNoTrailingNewlineAreAccepted) {
  TempDir tmp;
  write_valid(tmp.path());
  std::string frames = read_file(tmp.path() / "frames.csv");
  std::string crlf;
  for (char ch : frames) {
    if (ch == '\n') crlf += '\r';
    crlf += ch;
  }
  crlf.pop_back();
  crlf.pop_back();  // drop the final "\r\n"
  write_file(tmp.path() / "frames.csv", crlf);
  auto r = RecordingReader::open(tmp.path());
  ASSERT_TRUE(r) << r.status().message();
  EXPECT_EQ(r.value().frame_count(), 3u);
}

// A write error part-way (here /dev/full in place of frame 2's right PNG: ENOSPC, as a full
// disk): the message names the cause, frames.csv already lists the frames before it (written as
// it goes, not at finish()), and the frame that failed leaves no PNG, so that the recording, never
// finished, reads up to its last complete frame.
TEST(Recording, AWriterCutShortLeavesAReadableRecording) {
  TempDir tmp;
  RecordingInfo info = small_info();
  ASSERT_EQ(info.sensors.size(), 2u);
  auto w = RecordingWriter::open(tmp.path(), info);
  ASSERT_TRUE(w) << w.status().message();
  std::vector<Image> ims;
  for (unsigned s = 0; s < 2; ++s) ims.push_back(random_image(info.width, info.height, 3, s));
  const std::vector<ImageView> views{view(ims[0]), view(ims[1])};
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(w.value()->write_frame(1000 + i * 1000, views));
  fs::create_symlink("/dev/full", tmp.path() / "right/000002.png");
  const Status st = w.value()->write_frame(3000, views);
  ASSERT_FALSE(st);
  EXPECT_NE(st.message().find("right/000002.png: write failed: No space left on device"),
            std::string::npos)
      << st.message();
  EXPECT_FALSE(fs::exists(tmp.path() / "left/000002.png"));
  EXPECT_FALSE(fs::is_symlink(tmp.path() / "right/000002.png"));
  EXPECT_EQ(read_file(tmp.path() / "frames.csv"), "index,t_ns\n0,1000\n1,2000\n");
  auto r = RecordingReader::open(tmp.path());
  ASSERT_TRUE(r) << r.status().message();
  EXPECT_EQ(r.value().frame_count(), 2u);
}

TEST(Recording, WriterRejectsInconsistentFrames) {
  TempDir tmp;
  auto w = RecordingWriter::open(tmp.path(), small_info());
  ASSERT_TRUE(w);
  const Image a = random_image(32, 24, 3, 1), b = random_image(16, 24, 3, 2);
  const ImageView good[2] = {view(a), view(a)};
  const ImageView bad[2] = {view(a), view(b)};
  EXPECT_FALSE(w.value()->write_frame(0, bad));
  EXPECT_TRUE(w.value()->write_frame(10, good));
  EXPECT_FALSE(w.value()->write_frame(10, good));  // t_ns must increase
  EXPECT_FALSE(w.value()->append_frame_time(5, 20));
  EXPECT_TRUE(w.value()->write_image(0, 1, view(a)));  // right frame 1 never written
  EXPECT_TRUE(w.value()->append_frame_time(1, 20));
  const Status s = w.value()->finish();
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("right/000001.png"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace tacse3::recording
