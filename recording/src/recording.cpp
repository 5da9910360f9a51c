// SPDX-License-Identifier: Apache-2.0
// tacse3 recording: recording.json, frames.csv, truth.csv and sim_labels.csv reading and writing.
#include "tacse3/recording/recording.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string_view>
#include <system_error>

#include "tacse3/fileio/file_io.hpp"

namespace tacse3::recording {
namespace fs = std::filesystem;
namespace {

using Json = nlohmann::ordered_json;

constexpr const char* kFramesHeader = "index,t_ns";
constexpr const char* kTruthHeader = "t_ns,qw,qx,qy,qz,px,py,pz";
constexpr const char* kLabelsHeader =
    "index,t_ns,sensor,phase,in_contact,slipping,slip_fraction,area_mm2,centroid_u_mm,"
    "centroid_v_mm,peak_depth_mm";

Status err(const std::string& m) {
  return Status::error(m);
}

std::string json_type(const Json& j) {
  if (j.is_null()) return "null";
  if (j.is_boolean()) return "a boolean";
  if (j.is_number_integer() || j.is_number_unsigned()) return "an integer";
  if (j.is_number_float()) return "a number with a fraction";
  if (j.is_string()) return "a string";
  if (j.is_array()) return "an array";
  return "an object";
}

// --- recording.json --------------------------------------------------------------------------

Status get_key(const Json& obj, const char* parent, const char* key, const Json** out) {
  const auto it = obj.find(key);
  const std::string full = parent[0] ? std::string(parent) + "." + key : std::string(key);
  if (it == obj.end()) return err("recording.json: missing required key \"" + full + "\"");
  *out = &*it;
  return {};
}

Status get_positive_int(const Json& obj, const char* parent, const char* key, int* out) {
  const Json* v = nullptr;
  if (Status s = get_key(obj, parent, key, &v); !s) return s;
  const std::string full = parent[0] ? std::string(parent) + "." + key : std::string(key);
  if (!(v->is_number_integer() || v->is_number_unsigned())) {
    return err("recording.json: key \"" + full + "\" must be a positive integer, got " +
               json_type(*v));
  }
  const auto x = v->get<std::int64_t>();
  if (x <= 0 || x > 65535) {
    return err("recording.json: key \"" + full + "\" must be in [1, 65535], got " +
               std::to_string(x));
  }
  *out = static_cast<int>(x);
  return {};
}

Status get_positive_number(const Json& obj, const char* parent, const char* key, double* out) {
  const Json* v = nullptr;
  if (Status s = get_key(obj, parent, key, &v); !s) return s;
  const std::string full = parent[0] ? std::string(parent) + "." + key : std::string(key);
  if (!v->is_number()) {
    return err("recording.json: key \"" + full + "\" must be a number, got " + json_type(*v));
  }
  const double x = v->get<double>();
  if (!std::isfinite(x) || x <= 0.0) {
    return err("recording.json: key \"" + full + "\" must be a positive number, got " + v->dump());
  }
  *out = x;
  return {};
}

Status get_string(const Json& obj, const char* parent, const char* key, std::string* out) {
  const Json* v = nullptr;
  if (Status s = get_key(obj, parent, key, &v); !s) return s;
  const std::string full = parent[0] ? std::string(parent) + "." + key : std::string(key);
  if (!v->is_string()) {
    return err("recording.json: key \"" + full + "\" must be a string, got " + json_type(*v));
  }
  *out = v->get<std::string>();
  return {};
}

bool parse_sensor(std::string_view s, SensorId* out) {
  if (s == "left") {
    *out = SensorId::kLeft;
    return true;
  }
  if (s == "right") {
    *out = SensorId::kRight;
    return true;
  }
  return false;
}

Status parse_info(const std::string& text, RecordingInfo* info) {
  Json j;
  try {
    j = Json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    return err(std::string("recording.json: not valid JSON: ") + e.what());
  }
  if (!j.is_object())
    return err("recording.json: the top level must be an object, got " + json_type(j));
  std::string format;
  if (Status s = get_string(j, "", "format", &format); !s) return s;
  if (format != kFormatName) {
    return err("recording.json: key \"format\" must be \"" + std::string(kFormatName) +
               "\", got \"" + format + "\"");
  }
  const Json* version = nullptr;
  if (Status s = get_key(j, "", "version", &version); !s) return s;
  if (!(version->is_number_integer() || version->is_number_unsigned())) {
    return err("recording.json: key \"version\" must be an integer, got " + json_type(*version));
  }
  if (version->get<std::int64_t>() != kFormatVersion) {
    return err("recording.json: unsupported version " + version->dump() + " (this reader knows " +
               std::to_string(kFormatVersion) + ")");
  }
  if (Status s = get_positive_int(j, "", "width", &info->width); !s) return s;
  if (Status s = get_positive_int(j, "", "height", &info->height); !s) return s;
  if (Status s = get_positive_number(j, "", "fps", &info->fps); !s) return s;
  const Json* sensors = nullptr;
  if (Status s = get_key(j, "", "sensors", &sensors); !s) return s;
  if (!sensors->is_array()) {
    return err("recording.json: key \"sensors\" must be an array, got " + json_type(*sensors));
  }
  if (sensors->empty() || sensors->size() > 2) {
    return err("recording.json: key \"sensors\" must list one or two sensors, got " +
               std::to_string(sensors->size()));
  }
  info->sensors.clear();
  for (std::size_t k = 0; k < sensors->size(); ++k) {
    const Json& e = (*sensors)[k];
    SensorId id{};
    if (!e.is_string() || !parse_sensor(e.get<std::string>(), &id)) {
      return err("recording.json: key \"sensors[" + std::to_string(k) +
                 "]\" must be \"left\" or \"right\", got " + e.dump());
    }
    if (std::find(info->sensors.begin(), info->sensors.end(), id) != info->sensors.end()) {
      return err("recording.json: key \"sensors\" lists \"" + e.get<std::string>() + "\" twice");
    }
    info->sensors.push_back(id);
  }
  const Json* rig = nullptr;
  if (Status s = get_key(j, "", "rig", &rig); !s) return s;
  if (!rig->is_object())
    return err("recording.json: key \"rig\" must be an object, got " + json_type(*rig));
  if (Status s = get_positive_number(*rig, "rig", "pixel_pitch_mm", &info->rig.pixel_pitch_mm); !s)
    return s;
  if (Status s =
          get_positive_number(*rig, "rig", "finger_separation_mm", &info->rig.finger_separation_mm);
      !s) {
    return s;
  }
  if (Status s = get_string(*rig, "rig", "layout", &info->rig.layout); !s) return s;
  if (info->rig.layout != kLayoutMirrored) {
    return err("recording.json: key \"rig.layout\" must be \"mirrored\", got \"" +
               info->rig.layout + "\"");
  }
  info->extra_json = text;
  return {};
}

// --- CSV -----------------------------------------------------------------------------------

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ' || s.back() == '\t'))
    s.remove_suffix(1);
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  return s;
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    out.push_back(trim(line.substr(
        start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

bool parse_int(std::string_view s, std::int64_t* out) {
  if (s.empty()) return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), *out);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

bool parse_double(std::string_view s, double* out) {
  if (s.empty()) return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), *out);
  return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(*out);
}

bool parse_bool01(std::string_view s, bool* out) {
  if (s == "0" || s == "1") {
    *out = s == "1";
    return true;
  }
  return false;
}

// Reads <dir>/<name>, a regular file of at most max_bytes; a FIFO or a device is an error at once.
Status read_text(const fs::path& dir, const char* name, std::size_t max_bytes, std::string* out) {
  const std::string label = dir.string() + "/" + name;
  const fileio::ReadResult r = fileio::read_regular_file(dir / name, max_bytes, out);
  switch (r.error) {
    case fileio::ReadError::kNone:
      return {};
    case fileio::ReadError::kNotFound:
    case fileio::ReadError::kOpen:
      return err(label + ": cannot open" + fileio::os_error(r.os_errno));
    case fileio::ReadError::kNotRegular:
      return err(label + ": is " + r.kind +
                 ", not a regular file; replace it with the file the recording needs");
    case fileio::ReadError::kTooLarge:
      return err(label + ": larger than " + fileio::size_text(max_bytes) +
                 ", the reader's limit for this file (docs/recording-format.md)");
    case fileio::ReadError::kRead:
      break;
  }
  return err(label + ": read error" + fileio::os_error(r.os_errno));
}

// Calls row(line_no, fields) for each data row after checking the header. Blank lines are
// errors except at the very end of the file.
template <typename RowFn>
Status parse_csv(const std::string& text, const std::string& label, const char* header,
                 std::size_t nfields, RowFn row) {
  std::size_t pos = 0;
  int line_no = 0;
  bool header_seen = false;
  std::vector<int> blank_lines;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const std::string_view line = trim(std::string_view(text).substr(pos, end - pos));
    pos = end + 1;
    ++line_no;
    if (line.empty()) {
      blank_lines.push_back(line_no);
      continue;
    }
    if (!blank_lines.empty()) {
      return err(label + " line " + std::to_string(blank_lines.front()) +
                 ": empty line inside the file");
    }
    if (!header_seen) {
      if (line != header) {
        return err(label + " line 1: header must be \"" + std::string(header) + "\", got \"" +
                   std::string(line) + "\"");
      }
      header_seen = true;
      continue;
    }
    const auto fields = split(line);
    if (fields.size() != nfields) {
      return err(label + " line " + std::to_string(line_no) + ": expected " +
                 std::to_string(nfields) + " fields, got " + std::to_string(fields.size()));
    }
    if (Status s = row(line_no, fields); !s) return s;
  }
  if (!header_seen)
    return err(label + ": empty file (missing header \"" + std::string(header) + "\")");
  return {};
}

std::string at_line(const std::string& label, int line_no) {
  return label + " line " + std::to_string(line_no) + ": ";
}

// A time stamp more than kMaxSpanNs after the file's first one (1e6 s) is refused.
Status check_span(const std::string& label, int ln, std::int64_t first, std::int64_t t) {
  if (clamped_difference(t, first) <= kMaxSpanNs) return {};
  return err(at_line(label, ln) + "t_ns " + std::to_string(t) + " is more than 1e6 s after the " +
             "first row's " + std::to_string(first) + " (a recording spans at most 1e6 s)");
}

Status parse_frames(const std::string& text, std::vector<std::int64_t>* t_ns) {
  const std::string label = "frames.csv";
  return parse_csv(text, label, kFramesHeader, 2, [&](int ln, const auto& f) -> Status {
    std::int64_t index = 0, t = 0;
    if (!parse_int(f[0], &index))
      return err(at_line(label, ln) + "index \"" + std::string(f[0]) + "\" is not an integer");
    if (!parse_int(f[1], &t))
      return err(at_line(label, ln) + "t_ns \"" + std::string(f[1]) + "\" is not an integer");
    const auto expected = static_cast<std::int64_t>(t_ns->size());
    if (index != expected) {
      return err(at_line(label, ln) + "index " + std::to_string(index) + " where " +
                 std::to_string(expected) + " was expected (indices count 0, 1, 2, ...)");
    }
    if (!t_ns->empty() && t <= t_ns->back()) {
      return err(at_line(label, ln) + "t_ns " + std::to_string(t) +
                 " is not after the previous row's " + std::to_string(t_ns->back()));
    }
    if (!t_ns->empty()) {
      if (Status s = check_span(label, ln, t_ns->front(), t); !s) return s;
    }
    t_ns->push_back(t);
    return {};
  });
}

constexpr const char* kTruthNames[] = {"t_ns", "qw", "qx", "qy", "qz", "px", "py", "pz"};

Status parse_truth(const std::string& text, std::vector<TruthSample>* out) {
  const std::string label = "truth.csv";
  return parse_csv(text, label, kTruthHeader, 8, [&](int ln, const auto& f) -> Status {
    TruthSample s;
    if (!parse_int(f[0], &s.t_ns))
      return err(at_line(label, ln) + "t_ns \"" + std::string(f[0]) + "\" is not an integer");
    double* dst[] = {&s.qw, &s.qx, &s.qy, &s.qz, &s.px, &s.py, &s.pz};
    for (std::size_t k = 0; k < 7; ++k) {
      if (!parse_double(f[k + 1], dst[k])) {
        return err(at_line(label, ln) + kTruthNames[k + 1] + " \"" + std::string(f[k + 1]) +
                   "\" is not a finite number");
      }
    }
    const double norm = std::sqrt(s.qw * s.qw + s.qx * s.qx + s.qy * s.qy + s.qz * s.qz);
    if (std::abs(norm - 1.0) > 1e-3) {
      return err(at_line(label, ln) + "quaternion is not unit (norm " + std::to_string(norm) + ")");
    }
    if (!out->empty() && s.t_ns <= out->back().t_ns) {
      return err(at_line(label, ln) + "t_ns " + std::to_string(s.t_ns) +
                 " is not after the previous row's " + std::to_string(out->back().t_ns));
    }
    if (!out->empty()) {
      if (Status st = check_span(label, ln, out->front().t_ns, s.t_ns); !st) return st;
    }
    out->push_back(s);
    return {};
  });
}

Status parse_labels(const std::string& text, std::vector<SimLabel>* out) {
  const std::string label = "sim_labels.csv";
  return parse_csv(text, label, kLabelsHeader, 11, [&](int ln, const auto& f) -> Status {
    SimLabel l;
    if (!parse_int(f[0], &l.index)) return err(at_line(label, ln) + "index is not an integer");
    if (!parse_int(f[1], &l.t_ns)) return err(at_line(label, ln) + "t_ns is not an integer");
    if (!parse_sensor(f[2], &l.sensor))
      return err(at_line(label, ln) + "sensor must be left or right");
    l.phase = std::string(f[3]);
    if (l.phase.empty()) return err(at_line(label, ln) + "phase is empty");
    if (!parse_bool01(f[4], &l.in_contact))
      return err(at_line(label, ln) + "in_contact must be 0 or 1");
    if (!parse_bool01(f[5], &l.slipping))
      return err(at_line(label, ln) + "slipping must be 0 or 1");
    double* dst[] = {&l.slip_fraction, &l.area_mm2, &l.centroid_u_mm, &l.centroid_v_mm,
                     &l.peak_depth_mm};
    for (std::size_t k = 0; k < 5; ++k) {
      if (!parse_double(f[k + 6], dst[k])) {
        return err(at_line(label, ln) + "field " + std::to_string(k + 7) +
                   " is not a finite number");
      }
    }
    out->push_back(l);
    return {};
  });
}

std::string csv_bool(bool b) {
  return b ? "1" : "0";
}

}  // namespace

const char* to_string(SensorId s) noexcept {
  return s == SensorId::kLeft ? "left" : "right";
}

fs::path frame_relative_path(SensorId sensor, std::int64_t index) {
  char name[32];
  std::snprintf(name, sizeof name, "%06" PRId64 ".png", index);
  return fs::path(to_string(sensor)) / name;
}

// --- writer --------------------------------------------------------------------------------

Result<std::unique_ptr<RecordingWriter>> RecordingWriter::open(const fs::path& dir,
                                                               const RecordingInfo& info,
                                                               const WriterOptions& options) {
  if (info.width <= 0 || info.height <= 0 || !(info.fps > 0.0) || !std::isfinite(info.fps)) {
    return err("recording writer: width, height and fps must be positive");
  }
  if (info.sensors.empty() || info.sensors.size() > 2 ||
      (info.sensors.size() == 2 && info.sensors[0] == info.sensors[1])) {
    return err("recording writer: sensors must list one or two distinct sensors");
  }
  if (!(info.rig.pixel_pitch_mm > 0.0) || !(info.rig.finger_separation_mm > 0.0) ||
      !std::isfinite(info.rig.pixel_pitch_mm) || !std::isfinite(info.rig.finger_separation_mm)) {
    return err(
        "recording writer: rig.pixel_pitch_mm and rig.finger_separation_mm must be positive");
  }
  if (info.rig.layout != kLayoutMirrored)
    return err("recording writer: rig.layout must be \"mirrored\"");
  if (options.png_compression < 0 || options.png_compression > 9) {
    return err("recording writer: PNG compression level must be in [0, 9]");
  }
  Json j;
  j["format"] = kFormatName;
  j["version"] = kFormatVersion;
  j["width"] = info.width;
  j["height"] = info.height;
  j["fps"] = info.fps;
  j["sensors"] = Json::array();
  for (SensorId s : info.sensors) j["sensors"].push_back(to_string(s));
  j["rig"] = {{"pixel_pitch_mm", info.rig.pixel_pitch_mm},
              {"finger_separation_mm", info.rig.finger_separation_mm},
              {"layout", info.rig.layout}};
  if (!info.extra_json.empty()) {
    Json extra;
    try {
      extra = Json::parse(info.extra_json);
    } catch (const nlohmann::json::parse_error& e) {
      return err(std::string("recording writer: extra_json is not valid JSON: ") + e.what());
    }
    if (!extra.is_object()) return err("recording writer: extra_json must be a JSON object");
    for (auto it = extra.begin(); it != extra.end(); ++it) {
      if (j.contains(it.key())) {
        return err("recording writer: extra_json may not redefine the format key \"" + it.key() +
                   "\"");
      }
      j[it.key()] = it.value();
    }
  }

  std::error_code ec;
  if (fs::exists(dir, ec)) {
    if (!fs::is_directory(dir, ec)) return err(dir.string() + ": exists and is not a directory");
    const bool empty = fs::is_empty(dir, ec);
    if (!empty && !options.overwrite) {
      const std::string or_option =
          options.overwrite_option.empty()
              ? std::string()
              : " (or pass " + options.overwrite_option + " to replace the recording in it)";
      return err(dir.string() + ": directory is not empty; give a new or empty directory" +
                 or_option);
    }
    if (!empty) {
      // Remove only what a recording consists of; anything else in the directory stays.
      for (const char* f : {"recording.json", "frames.csv", "truth.csv", "sim_labels.csv"}) {
        fs::remove(dir / f, ec);
      }
      for (const char* sub : {"left", "right"}) {
        const fs::path d = dir / sub;
        if (!fs::is_directory(d, ec)) continue;
        for (const auto& e : fs::directory_iterator(d, ec)) {
          if (e.path().extension() == ".png") fs::remove(e.path(), ec);
        }
        fs::remove(d, ec);  // only succeeds when now empty
      }
    }
  }
  fs::create_directories(dir, ec);
  if (ec) return err(dir.string() + ": cannot create directory: " + ec.message());
  for (SensorId s : info.sensors) {
    fs::create_directories(dir / to_string(s), ec);
    if (ec)
      return err((dir / to_string(s)).string() + ": cannot create directory: " + ec.message());
  }
  {
    std::ofstream out(dir / "recording.json", std::ios::binary | std::ios::trunc);
    out << j.dump(2) << '\n';
    out.close();
    if (!out) return err((dir / "recording.json").string() + ": write failed");
  }
  std::unique_ptr<RecordingWriter> w(new RecordingWriter());
  w->dir_ = dir;
  w->info_ = info;
  w->options_ = options;
  w->frames_csv_ = std::fopen((dir / "frames.csv").c_str(), "wb");
  if (!w->frames_csv_)
    return err((dir / "frames.csv").string() + ": cannot create: " + std::strerror(errno));
  // Unbuffered: a recording cut short (disk full, power loss) lists every frame written so far.
  std::setvbuf(w->frames_csv_, nullptr, _IONBF, 0);
  const std::string header = std::string(kFramesHeader) + "\n";
  if (std::fwrite(header.data(), 1, header.size(), w->frames_csv_) != header.size())
    return err((dir / "frames.csv").string() + ": write failed: " + std::strerror(errno));
  w->frames_csv_bytes_ = static_cast<long>(header.size());
  return w;
}

RecordingWriter::~RecordingWriter() {
  for (std::FILE* f : {frames_csv_, truth_csv_, labels_csv_}) {
    if (f) std::fclose(f);
  }
}

Status RecordingWriter::check_image(std::size_t slot, const ImageView& im) const {
  if (slot >= info_.sensors.size()) return err("recording writer: sensor slot out of range");
  if (im.width != info_.width || im.height != info_.height) {
    return err("recording writer: image is " + std::to_string(im.width) + "x" +
               std::to_string(im.height) + ", the recording is " + std::to_string(info_.width) +
               "x" + std::to_string(info_.height));
  }
  if (im.channels != 1 && im.channels != 3)
    return err("recording writer: images must have 1 or 3 channels");
  return {};
}

Status RecordingWriter::write_image(std::size_t slot, std::int64_t index, const ImageView& image) {
  if (finished_) return err("recording writer: already finished");
  if (Status s = check_image(slot, image); !s) return s;
  if (index < 0) return err("recording writer: negative frame index");
  {
    std::lock_guard<std::mutex> lock(mutex_);
    int& ch = slot_channels_[slot];
    if (ch == 0) ch = image.channels;
    if (ch != image.channels)
      return err("recording writer: a sensor's frames must all be grey or all RGB");
  }
  return write_png(dir_ / frame_relative_path(info_.sensors[slot], index), image,
                   options_.png_compression);
}

Status RecordingWriter::append_frame_time(std::int64_t index, std::int64_t t_ns) {
  if (finished_) return err("recording writer: already finished");
  if (index != frames_) {
    return err("recording writer: frame index " + std::to_string(index) + " where " +
               std::to_string(frames_) + " was expected");
  }
  if (frames_ > 0 && t_ns <= last_t_ns_)
    return err("recording writer: t_ns must increase strictly");
  char row[48];
  const int n = std::snprintf(row, sizeof row, "%" PRId64 ",%" PRId64 "\n", index, t_ns);
  if (std::fwrite(row, 1, static_cast<std::size_t>(n), frames_csv_) !=
      static_cast<std::size_t>(n)) {
    const int e = errno;
    // A partial row would make the whole file unreadable: cut back to the last complete one.
    std::clearerr(frames_csv_);
    if (::ftruncate(::fileno(frames_csv_), frames_csv_bytes_) == 0)
      std::fseek(frames_csv_, frames_csv_bytes_, SEEK_SET);
    return err((dir_ / "frames.csv").string() + ": write failed: " + std::strerror(e));
  }
  frames_csv_bytes_ += n;
  last_t_ns_ = t_ns;
  ++frames_;
  return {};
}

Status RecordingWriter::write_frame(std::int64_t t_ns, std::span<const ImageView> images,
                                    std::int64_t* index) {
  if (images.size() != info_.sensors.size()) {
    return err("recording writer: write_frame needs one image per recorded sensor");
  }
  if (frames_ > 0 && t_ns <= last_t_ns_)
    return err("recording writer: t_ns must increase strictly");
  // The PNGs first, the frames.csv row after them: frames.csv never lists a frame whose PNGs are
  // incomplete, and the PNGs of a frame that failed are removed, so that a recording cut short
  // (disk full) stays readable up to its last complete frame.
  const std::int64_t i = frames_;
  for (std::size_t k = 0; k < images.size(); ++k) {
    if (Status s = write_image(k, i, images[k]); !s) {
      remove_pngs(i, k + 1);
      return s;
    }
  }
  if (Status s = append_frame_time(i, t_ns); !s) {
    remove_pngs(i, images.size());
    return s;
  }
  if (index) *index = i;
  return {};
}

void RecordingWriter::remove_pngs(std::int64_t index, std::size_t slots) {
  std::error_code ec;
  for (std::size_t k = 0; k < slots && k < info_.sensors.size(); ++k)
    fs::remove(dir_ / frame_relative_path(info_.sensors[k], index), ec);
}

Status RecordingWriter::append_truth(const TruthSample& s) {
  if (finished_) return err("recording writer: already finished");
  const double v[] = {s.qw, s.qx, s.qy, s.qz, s.px, s.py, s.pz};
  for (double x : v) {
    if (!std::isfinite(x)) return err("recording writer: truth sample is not finite");
  }
  if (truth_rows_ > 0 && s.t_ns <= last_truth_t_ns_) {
    return err("recording writer: truth t_ns must increase strictly");
  }
  if (!truth_csv_) {
    truth_csv_ = std::fopen((dir_ / "truth.csv").c_str(), "wb");
    if (!truth_csv_)
      return err((dir_ / "truth.csv").string() + ": cannot create: " + std::strerror(errno));
    std::fprintf(truth_csv_, "%s\n", kTruthHeader);
  }
  if (std::fprintf(truth_csv_, "%" PRId64 ",%.12f,%.12f,%.12f,%.12f,%.12f,%.12f,%.12f\n", s.t_ns,
                   s.qw, s.qx, s.qy, s.qz, s.px, s.py, s.pz) < 0) {
    return err((dir_ / "truth.csv").string() + ": write failed: " + std::strerror(errno));
  }
  last_truth_t_ns_ = s.t_ns;
  ++truth_rows_;
  return {};
}

Status RecordingWriter::append_sim_label(const SimLabel& l) {
  if (finished_) return err("recording writer: already finished");
  if (l.phase.empty() || l.phase.find_first_of(",\n\r") != std::string::npos) {
    return err("recording writer: label phase must be a non-empty word");
  }
  if (!labels_csv_) {
    labels_csv_ = std::fopen((dir_ / "sim_labels.csv").c_str(), "wb");
    if (!labels_csv_) {
      return err((dir_ / "sim_labels.csv").string() + ": cannot create: " + std::strerror(errno));
    }
    std::fprintf(labels_csv_, "%s\n", kLabelsHeader);
  }
  if (std::fprintf(labels_csv_, "%" PRId64 ",%" PRId64 ",%s,%s,%s,%s,%.4f,%.4f,%.4f,%.4f,%.6f\n",
                   l.index, l.t_ns, to_string(l.sensor), l.phase.c_str(),
                   csv_bool(l.in_contact).c_str(), csv_bool(l.slipping).c_str(), l.slip_fraction,
                   l.area_mm2, l.centroid_u_mm, l.centroid_v_mm, l.peak_depth_mm) < 0) {
    return err((dir_ / "sim_labels.csv").string() + ": write failed: " + std::strerror(errno));
  }
  return {};
}

Status RecordingWriter::finish() {
  if (finished_) return {};
  finished_ = true;
  Status result;
  for (auto [f, name] : {std::pair{&frames_csv_, "frames.csv"}, std::pair{&truth_csv_, "truth.csv"},
                         std::pair{&labels_csv_, "sim_labels.csv"}}) {
    if (*f) {
      const bool bad = std::ferror(*f) != 0;
      if (std::fclose(*f) != 0 || bad) {
        if (result) result = err((dir_ / name).string() + ": write failed");
      }
      *f = nullptr;
    }
  }
  if (!result) return result;
  std::error_code ec;
  for (std::size_t slot = 0; slot < info_.sensors.size(); ++slot) {
    for (std::int64_t i = 0; i < frames_; ++i) {
      const fs::path p = dir_ / frame_relative_path(info_.sensors[slot], i);
      if (!fs::is_regular_file(p, ec))
        return err(p.string() + ": missing (frame " + std::to_string(i) + ")");
    }
  }
  return {};
}

// --- reader --------------------------------------------------------------------------------

Result<RecordingReader> RecordingReader::open(const fs::path& dir,
                                              const ReaderOptions& options) noexcept {
  try {
    return open_impl(dir, options);
  } catch (const std::bad_alloc&) {
    return err(dir.string() + ": out of memory while reading the recording");
  } catch (const std::exception& e) {
    return err(dir.string() + ": " + e.what());
  }
}

Result<RecordingReader> RecordingReader::open_impl(const fs::path& dir,
                                                   const ReaderOptions& options) {
  RecordingReader r;
  r.dir_ = dir;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return err(dir.string() + ": not a directory");
  const std::string where = dir.string() + "/";
  std::string text;
  if (!fs::exists(dir / "recording.json", ec)) return err(where + "recording.json: missing");
  if (Status s = read_text(dir, "recording.json", kMaxJsonBytes, &text); !s) return s;
  if (Status s = parse_info(text, &r.info_); !s) return err(where + s.message());

  if (!fs::exists(dir / "frames.csv", ec)) return err(where + "frames.csv: missing");
  if (Status s = read_text(dir, "frames.csv", kMaxCsvBytes, &text); !s) return s;
  if (Status s = parse_frames(text, &r.t_ns_); !s) return err(where + s.message());
  if (r.t_ns_.empty()) return err(where + "frames.csv: no frames");

  const std::size_t n = r.t_ns_.size();
  for (std::size_t slot = 0; slot < r.info_.sensors.size(); ++slot) {
    const char* sname = to_string(r.info_.sensors[slot]);
    const fs::path sdir = dir / sname;
    if (!fs::is_directory(sdir, ec)) return err(where + sname + "/: missing directory");
    std::size_t pngs = 0;
    for (const auto& e : fs::directory_iterator(sdir, ec)) {
      if (e.path().extension() == ".png") ++pngs;
    }
    if (ec) return err(where + sname + "/: cannot list: " + ec.message());
    for (std::size_t i = 0; i < n; ++i) {
      const fs::path p =
          dir / frame_relative_path(r.info_.sensors[slot], static_cast<std::int64_t>(i));
      if (!fs::is_regular_file(p, ec)) {
        return err(p.string() + ": missing (frames.csv lists " + std::to_string(n) + " frames)");
      }
      if (!options.check_png_headers) continue;
      PngHeader h;
      if (Status s = read_png_header(p, &h); !s) return s;
      if (h.width != r.info_.width || h.height != r.info_.height) {
        return err(p.string() + ": PNG is " + std::to_string(h.width) + "x" +
                   std::to_string(h.height) + ", recording.json says " +
                   std::to_string(r.info_.width) + "x" + std::to_string(r.info_.height));
      }
      if (h.bit_depth != 8 || (h.colour_type != 0 && h.colour_type != 2)) {
        return err(p.string() + ": PNG must be 8-bit RGB or 8-bit grey, got bit depth " +
                   std::to_string(h.bit_depth) + ", colour type " + std::to_string(h.colour_type));
      }
      const int ch = h.colour_type == 0 ? 1 : 3;
      if (r.channels_ == 0) r.channels_ = ch;
      if (ch != r.channels_) {
        return err(p.string() + ": PNG is " + (ch == 1 ? "grey" : "RGB") +
                   " but earlier frames are " + (r.channels_ == 1 ? "grey" : "RGB"));
      }
    }
    if (pngs != n) {
      return err(where + sname + "/: frame count mismatch: " + std::to_string(pngs) +
                 " PNG files, frames.csv lists " + std::to_string(n) + " frames");
    }
  }

  if (fs::exists(dir / "truth.csv", ec)) {
    if (Status s = read_text(dir, "truth.csv", kMaxCsvBytes, &text); !s) return s;
    if (Status s = parse_truth(text, &r.truth_); !s) return err(where + s.message());
    r.has_truth_ = true;
  }
  if (fs::exists(dir / "sim_labels.csv", ec)) {
    if (Status s = read_text(dir, "sim_labels.csv", kMaxCsvBytes, &text); !s) return s;
    if (Status s = parse_labels(text, &r.labels_); !s) return err(where + s.message());
    r.has_labels_ = true;
  }
  return r;
}

int RecordingReader::slot_of(SensorId s) const noexcept {
  for (std::size_t k = 0; k < info_.sensors.size(); ++k) {
    if (info_.sensors[k] == s) return static_cast<int>(k);
  }
  return -1;
}

const TruthSample* RecordingReader::truth_at(std::int64_t t) const noexcept {
  const auto it = std::lower_bound(truth_.begin(), truth_.end(), t,
                                   [](const TruthSample& s, std::int64_t v) { return s.t_ns < v; });
  return it != truth_.end() && it->t_ns == t ? &*it : nullptr;
}

fs::path RecordingReader::frame_path(std::size_t slot, std::size_t index) const {
  return dir_ / frame_relative_path(info_.sensors[slot], static_cast<std::int64_t>(index));
}

Status RecordingReader::read_image(std::size_t slot, std::size_t index, Image* out) const {
  if (slot >= info_.sensors.size()) return err("recording reader: sensor slot out of range");
  if (index >= t_ns_.size()) return err("recording reader: frame index out of range");
  const fs::path p = frame_path(slot, index);
  if (Status s = read_png(p, out); !s) return s;
  if (out->width != info_.width || out->height != info_.height) {
    return err(p.string() + ": PNG is " + std::to_string(out->width) + "x" +
               std::to_string(out->height) + ", recording.json says " +
               std::to_string(info_.width) + "x" + std::to_string(info_.height));
  }
  return {};
}

Status RecordingReader::read_frame(std::size_t index, Frame* out) const {
  if (index >= t_ns_.size()) return err("recording reader: frame index out of range");
  out->index = static_cast<std::int64_t>(index);
  out->t_ns = t_ns_[index];
  for (std::size_t slot = 0; slot < info_.sensors.size(); ++slot) {
    if (Status s = read_image(slot, index, &out->images[slot]); !s) return s;
  }
  out->truth = truth_at(out->t_ns);
  return {};
}

}  // namespace tacse3::recording
