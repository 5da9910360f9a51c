// SPDX-License-Identifier: Apache-2.0
// tacse3 recording: read and write recording directories (docs/recording-format.md).
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace tacse3::recording {

inline constexpr const char* kFormatName = "tacse3-recording";
inline constexpr int kFormatVersion = 1;
inline constexpr const char* kLayoutMirrored = "mirrored";

// Largest text files the reader accepts. recording.json is a few KiB. A CSV of 64 MiB holds about
// 3 M frames.csv rows (7 h at 120 Hz), 550 k truth.csv rows (75 min) or 900 k sim_labels.csv
// rows: beyond any recording so far, while /dev/zero or a runaway file cannot exhaust memory.
inline constexpr std::size_t kMaxJsonBytes = std::size_t{1} << 20;
inline constexpr std::size_t kMaxCsvBytes = std::size_t{64} << 20;

// The longest span of a recording's time stamps, first row to last, in frames.csv and truth.csv:
// 1e6 s, far beyond any grasp and far below int64's 9.2e9 s, so that differences of time stamps
// and the replay camera's loop offsets stay representable. The reader refuses a longer span.
inline constexpr std::int64_t kMaxSpanNs = 1'000'000'000'000'000;

// later - earlier, clamped to int64's range: the span check itself must not overflow.
constexpr std::int64_t clamped_difference(std::int64_t later, std::int64_t earlier) noexcept {
  constexpr std::int64_t kMax = INT64_MAX, kMin = INT64_MIN;
  if (earlier < 0 && later > kMax + earlier) return kMax;
  if (earlier > 0 && later < kMin + earlier) return kMin;
  return later - earlier;
}

// a + b, clamped to int64's range.
constexpr std::int64_t clamped_sum(std::int64_t a, std::int64_t b) noexcept {
  if (b > 0 && a > INT64_MAX - b) return INT64_MAX;
  if (b < 0 && a < INT64_MIN - b) return INT64_MIN;
  return a + b;
}

// Success, or a message that names the file and the key or line at fault. No API of this
// library throws.
class Status {
 public:
  Status() = default;
  static Status error(std::string message) { return Status(std::move(message)); }
  bool ok() const noexcept { return message_.empty(); }
  explicit operator bool() const noexcept { return ok(); }
  const std::string& message() const noexcept { return message_; }

 private:
  explicit Status(std::string m)
      : message_(m.empty() ? std::string("unknown error") : std::move(m)) {}
  std::string message_;
};

// A value or an error Status (C++20 has no std::expected).
template <typename T>
class Result {
 public:
  Result(T value) : v_(std::move(value)) {}       // NOLINT(google-explicit-constructor)
  Result(Status error) : v_(std::move(error)) {}  // NOLINT(google-explicit-constructor)
  bool ok() const noexcept { return v_.index() == 0; }
  explicit operator bool() const noexcept { return ok(); }
  T& value() & { return std::get<0>(v_); }
  T&& value() && { return std::get<0>(std::move(v_)); }
  const T& value() const& { return std::get<0>(v_); }
  // The error; an ok Status when the result holds a value.
  Status status() const { return ok() ? Status() : std::get<1>(v_); }

 private:
  std::variant<T, Status> v_;
};

enum class SensorId : std::uint8_t { kLeft = 0, kRight = 1 };
const char* to_string(SensorId s) noexcept;

struct RigInfo {
  double pixel_pitch_mm = 0.1;
  double finger_separation_mm = 40.0;
  std::string layout = kLayoutMirrored;
};

struct RecordingInfo {
  int width = 320;
  int height = 240;
  double fps = 120.0;
  std::vector<SensorId> sensors{SensorId::kLeft, SensorId::kRight};  // order = slot order
  RigInfo rig;
  // Writer: a JSON object whose keys are added to recording.json (e.g. the simulator's "sim"
  // block); it may not redefine a format key. Reader: the full text of recording.json, so tools
  // can read keys this library does not know.
  std::string extra_json;
};

// truth.csv row: the object's pose in G relative to the first frame (unit quaternion, metres).
struct TruthSample {
  std::int64_t t_ns = 0;
  double qw = 1.0, qx = 0.0, qy = 0.0, qz = 0.0;
  double px = 0.0, py = 0.0, pz = 0.0;
};

// sim_labels.csv row (simulator extension, optional): per frame and sensor contact labels.
struct SimLabel {
  std::int64_t index = 0;
  std::int64_t t_ns = 0;
  SensorId sensor = SensorId::kLeft;
  std::string phase;  // approach | grasp | settle | motion | hold | release
  bool in_contact = false;
  bool slipping = false;
  double slip_fraction = 0.0;
  double area_mm2 = 0.0;
  double centroid_u_mm = 0.0;
  double centroid_v_mm = 0.0;
  double peak_depth_mm = 0.0;
};

// An 8-bit image, tightly packed rows; channels 1 (grey) or 3 (RGB).
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<std::uint8_t> pixels;
};

struct ImageView {
  const std::uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  int channels = 0;  // 1 or 3
  std::size_t size() const noexcept {
    return static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
           static_cast<std::size_t>(channels);
  }
};

inline ImageView view(const Image& im) noexcept {
  return {im.pixels.data(), im.width, im.height, im.channels};
}

// PNG helpers (libspng). Only 8-bit grey (colour type 0) and 8-bit RGB (colour type 2) are
// accepted; anything else is an error naming the file.
struct PngHeader {
  int width = 0;
  int height = 0;
  int bit_depth = 0;
  int colour_type = 0;
};
Status read_png_header(const std::filesystem::path& file, PngHeader* out);
// Largest PNG side read_png decodes: far above any tactile camera, and it bounds the buffer a
// header can ask for (8-bit RGB: 48 MiB).
inline constexpr int kMaxPngSide = 4096;
Status read_png(const std::filesystem::path& file, Image* out);  // reuses out->pixels
Status write_png(const std::filesystem::path& file, const ImageView& image, int compression_level);

// "left/000042.png"-style relative path of a frame.
std::filesystem::path frame_relative_path(SensorId sensor, std::int64_t index);

struct WriterOptions {
  int png_compression = 1;  // zlib level 0..9 (1: fast; frames are noisy and barely compress)
  bool overwrite = false;   // replace the recording files in an existing directory
  // The caller's option that sets overwrite ("--overwrite"), named when a directory is refused;
  // empty: the caller has none, and the message asks for another directory only.
  std::string overwrite_option;
};

// Writes a recording directory. recording.json is written by open(); frames.csv, truth.csv and
// sim_labels.csv are streamed; finish() flushes them and checks that every frame has a PNG for
// every sensor. write_image() may be called concurrently for different sensor slots.
class RecordingWriter {
 public:
  static Result<std::unique_ptr<RecordingWriter>> open(const std::filesystem::path& dir,
                                                       const RecordingInfo& info,
                                                       const WriterOptions& options = {});
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  // <dir>/<sensor>/<index>.png for the sensor in slot `slot` (index into info.sensors).
  Status write_image(std::size_t slot, std::int64_t index, const ImageView& image);
  // frames.csv row; indices must be 0, 1, 2, ... and t_ns strictly increasing.
  Status append_frame_time(std::int64_t index, std::int64_t t_ns);
  // Both at once: one image per slot, then the frames.csv row. Returns the new frame's index
  // through *index if non-null.
  Status write_frame(std::int64_t t_ns, std::span<const ImageView> images,
                     std::int64_t* index = nullptr);
  Status append_truth(const TruthSample& sample);
  Status append_sim_label(const SimLabel& label);
  Status finish();

  const RecordingInfo& info() const noexcept { return info_; }
  const std::filesystem::path& dir() const noexcept { return dir_; }
  std::int64_t frame_count() const noexcept { return frames_; }

 private:
  RecordingWriter() = default;
  Status check_image(std::size_t slot, const ImageView& image) const;
  void remove_pngs(std::int64_t index, std::size_t slots);

  std::filesystem::path dir_;
  RecordingInfo info_;
  WriterOptions options_;
  std::FILE* frames_csv_ = nullptr;  // unbuffered: each row is on disk once appended
  long frames_csv_bytes_ = 0;        // up to the last complete row
  std::FILE* truth_csv_ = nullptr;
  std::FILE* labels_csv_ = nullptr;
  std::int64_t frames_ = 0;
  std::int64_t last_t_ns_ = 0;
  std::int64_t last_truth_t_ns_ = 0;
  std::int64_t truth_rows_ = 0;
  std::array<int, 2> slot_channels_{0, 0};
  std::mutex mutex_;  // guards slot_channels_
  bool finished_ = false;
};

struct ReaderOptions {
  // Read every PNG's header at open() (size, bit depth, colour type). Cheap: 33 bytes a file.
  bool check_png_headers = true;
};

// Reads and validates a recording directory. open() checks recording.json, frames.csv, the
// PNG files (presence, count, headers) and, when present, truth.csv and sim_labels.csv; any
// problem is an error naming the file and key or line. Nothing is skipped silently.
class RecordingReader {
 public:
  struct Frame {
    std::int64_t index = 0;
    std::int64_t t_ns = 0;
    std::array<Image, 2> images;         // by slot (info().sensors order)
    const TruthSample* truth = nullptr;  // truth row with the same t_ns, if any
  };

  // Never throws; running out of memory is an error too.
  static Result<RecordingReader> open(const std::filesystem::path& dir,
                                      const ReaderOptions& options = {}) noexcept;

  const std::filesystem::path& dir() const noexcept { return dir_; }
  const RecordingInfo& info() const noexcept { return info_; }
  std::size_t frame_count() const noexcept { return t_ns_.size(); }
  std::size_t sensor_count() const noexcept { return info_.sensors.size(); }
  int slot_of(SensorId s) const noexcept;              // -1 if the sensor is not recorded
  int channels() const noexcept { return channels_; }  // 1 or 3 (0 if headers were not read)
  std::int64_t t_ns(std::size_t index) const noexcept { return t_ns_[index]; }
  const std::vector<std::int64_t>& times_ns() const noexcept { return t_ns_; }

  bool has_truth() const noexcept { return has_truth_; }
  const std::vector<TruthSample>& truth() const noexcept { return truth_; }
  const TruthSample* truth_at(std::int64_t t_ns) const noexcept;

  bool has_sim_labels() const noexcept { return has_labels_; }
  const std::vector<SimLabel>& sim_labels() const noexcept { return labels_; }

  std::filesystem::path frame_path(std::size_t slot, std::size_t index) const;
  Status read_image(std::size_t slot, std::size_t index, Image* out) const;
  Status read_frame(std::size_t index, Frame* out) const;

 private:
  static Result<RecordingReader> open_impl(const std::filesystem::path& dir,
                                           const ReaderOptions& options);

  std::filesystem::path dir_;
  RecordingInfo info_;
  std::vector<std::int64_t> t_ns_;
  std::vector<TruthSample> truth_;
  std::vector<SimLabel> labels_;
  bool has_truth_ = false;
  bool has_labels_ = false;
  int channels_ = 0;
};

}  // namespace tacse3::recording
