// SPDX-License-Identifier: Apache-2.0
// tacse3 fuzz: the recording reader (recording/recording.cpp): recording.json and the three
// CSVs. The input is split at lines "%%" into recording.json, frames.csv, truth.csv and
// sim_labels.csv (a part not present: the file is absent) and written to a scratch recording
// with an empty PNG per listed frame (PNG decoding is fuzz_png's). A recording it opens keeps the
// format's promises: frames, strictly increasing times, truth in time order.
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

#include "tacse3/recording/recording.hpp"

namespace fs = std::filesystem;
namespace tr = tacse3::recording;

namespace {

constexpr std::size_t kMaxFrames = 64;  // PNG placeholders per sensor
constexpr const char* kFiles[] = {"recording.json", "frames.csv", "truth.csv", "sim_labels.csv"};

const fs::path& scratch_dir() {
  static const fs::path d = [] {
    fs::path p = fs::temp_directory_path() / ("tacse3-fuzz-rec-" + std::to_string(getpid()));
    fs::remove_all(p);
    fs::create_directories(p / "left");
    fs::create_directories(p / "right");
    for (const char* side : {"left", "right"}) {
      const auto sensor = side[0] == 'l' ? tr::SensorId::kLeft : tr::SensorId::kRight;
      for (std::size_t i = 0; i < kMaxFrames; ++i) {
        std::FILE* f = std::fopen((p / tr::frame_relative_path(sensor, i)).c_str(), "wb");
        if (f == nullptr || std::fclose(f) != 0) __builtin_trap();
      }
    }
    return p;
  }();
  return d;
}

// Keeps the first `frames` placeholders of each sensor and moves the rest aside, so the reader's
// PNG count matches when frames.csv lists that many. Only the ones that change are renamed.
void keep_pngs(const fs::path& dir, std::size_t frames) {
  static std::size_t present = kMaxFrames;
  const std::size_t lo = std::min(present, frames), hi = std::max(present, frames);
  present = frames;
  for (const char* side : {"left", "right"}) {
    const auto sensor = side[0] == 'l' ? tr::SensorId::kLeft : tr::SensorId::kRight;
    for (std::size_t i = lo; i < hi; ++i) {
      const fs::path png = dir / tr::frame_relative_path(sensor, i);
      fs::path aside = png;
      aside.replace_extension(".off");
      std::error_code ec;
      if (i < frames) {
        fs::rename(aside, png, ec);
      } else {
        fs::rename(png, aside, ec);
      }
    }
  }
}

void write_part(const fs::path& file, std::string_view text) {
  std::FILE* f = std::fopen(file.c_str(), "wb");
  if (f == nullptr || std::fwrite(text.data(), 1, text.size(), f) != text.size() ||
      std::fclose(f) != 0) {
    __builtin_trap();
  }
}

// frames.csv: a header line, then one line per frame.
std::size_t data_lines(std::string_view text) {
  std::size_t lines = 0;
  for (std::size_t at = 0; at < text.size();) {
    std::size_t end = text.find('\n', at);
    if (end == std::string_view::npos) end = text.size();
    if (end > at) ++lines;
    at = end + 1;
  }
  return lines > 0 ? lines - 1 : 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fs::path& dir = scratch_dir();
  std::string_view rest(reinterpret_cast<const char*>(data), size);
  std::size_t frames_listed = 0;
  for (std::size_t part = 0; part < 4; ++part) {
    const fs::path file = dir / kFiles[part];
    std::error_code ec;
    fs::remove(file, ec);
    if (rest.data() == nullptr) continue;
    const std::size_t cut = rest.find("\n%%\n");
    const std::string_view text = rest.substr(0, cut);
    write_part(file, text);
    if (part == 1) frames_listed = data_lines(text);
    rest = cut == std::string_view::npos ? std::string_view() : rest.substr(cut + 4);
  }
  keep_pngs(dir, std::min(frames_listed, kMaxFrames));
  tr::ReaderOptions opt;
  opt.check_png_headers = false;
  auto r = tr::RecordingReader::open(dir, opt);
  if (!r) {
    if (r.status().message().empty()) __builtin_trap();
    return 0;
  }
  const tr::RecordingReader& rec = r.value();
  if (rec.frame_count() == 0 || rec.sensor_count() == 0 || rec.sensor_count() > 2) __builtin_trap();
  if (!std::is_sorted(rec.times_ns().begin(), rec.times_ns().end()) ||
      std::adjacent_find(rec.times_ns().begin(), rec.times_ns().end()) != rec.times_ns().end()) {
    __builtin_trap();
  }
  for (std::size_t i = 1; i < rec.truth().size(); ++i) {
    if (rec.truth()[i].t_ns <= rec.truth()[i - 1].t_ns) __builtin_trap();
  }
  return 0;
}
