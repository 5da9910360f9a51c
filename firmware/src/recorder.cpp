// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: --record DIR through the bounded streaming recording writer.
#include "tacse3/firmware/recorder.hpp"

#include <cstdio>
#include <span>
#include <system_error>

namespace tacse3::firmware {

std::unique_ptr<FrameRecorder> FrameRecorder::start(const std::filesystem::path& dir,
                                                    const RecorderConfig& config,
                                                    std::string* error) {
  std::unique_ptr<FrameRecorder> r(new FrameRecorder());
  r->config_ = config;
  bool all_rgb = true;
  recording::StreamWriterOptions o;
  o.info.width = config.width;
  o.info.height = config.height;
  o.info.fps = config.fps;
  o.info.sensors.clear();
  for (std::size_t s = 0; s < 2; ++s) {
    if (!config.sensors[s]) continue;
    o.info.sensors.push_back(s == 0 ? recording::SensorId::kLeft : recording::SensorId::kRight);
    all_rgb = all_rgb && config.formats[s] == dsp::PixelFormat::kRgb888;
  }
  if (o.info.sensors.empty()) {
    *error = dir.string() + ": the board has no sensor";
    return nullptr;
  }
  r->channels_ = all_rgb ? 3 : 1;
  o.channels = r->channels_;
  o.ring_frames = config.ring_frames;
  o.info.rig.pixel_pitch_mm = config.pixel_pitch_mm;
  o.info.rig.finger_separation_mm = config.finger_separation_mm;
  o.info.extra_json = R"({"recorded_by":"tacse3d"})";
  const std::size_t pixels =
      static_cast<std::size_t>(config.width) * static_cast<std::size_t>(config.height);
  for (std::size_t s = 0; s < 2; ++s) {
    if (config.sensors[s] && !all_rgb) r->grey_[s] = std::make_unique<std::uint8_t[]>(pixels);
  }
  auto w = recording::StreamWriter::start(dir, o);
  if (!w) {
    *error = dir.string() + ": " + w.status().message();
    return nullptr;
  }
  r->writer_ = std::move(w).value();
  return r;
}

bool FrameRecorder::to_image(std::size_t s, const dsp::FrameView& v,
                             recording::StreamImage* out) noexcept {
  if (v.width != config_.width || v.height != config_.height || v.data == nullptr) return false;
  out->width = v.width;
  out->height = v.height;
  out->channels = channels_;
  if (channels_ == 3 || v.format == dsp::PixelFormat::kGrey) {
    // Stored as delivered (RGB888 on an all-RGB board, or GREY).
    out->data = v.data;
    out->stride_bytes = v.stride_bytes;
    return true;
  }
  std::uint8_t* dst = grey_[s].get();
  const int bpp = v.format == dsp::PixelFormat::kRgb888 ? 3 : 2;  // RGB888 or YUYV
  const int stride = v.stride_bytes > 0 ? v.stride_bytes : v.width * bpp;
  for (int y = 0; y < v.height; ++y) {
    const std::uint8_t* row =
        v.data + static_cast<std::size_t>(y) * static_cast<std::size_t>(stride);
    std::uint8_t* o = dst + static_cast<std::size_t>(y) * static_cast<std::size_t>(v.width);
    if (bpp == 2) {
      for (int x = 0; x < v.width; ++x) o[x] = row[2 * x];  // YUYV: Y0 U Y1 V
    } else {
      // BT.601 luma with 8-bit weights (77, 150, 29)/256, rounded.
      for (int x = 0; x < v.width; ++x) {
        const std::uint8_t* p = row + 3 * x;
        o[x] = static_cast<std::uint8_t>((77u * p[0] + 150u * p[1] + 29u * p[2] + 128u) >> 8);
      }
    }
  }
  out->data = dst;
  out->stride_bytes = v.width;
  return true;
}

void FrameRecorder::record(std::int64_t t_ns, const dsp::FrameView* left,
                           const dsp::FrameView* right) noexcept {
  std::array<recording::StreamImage, 2> images{};
  std::size_t n = 0;
  const std::array<const dsp::FrameView*, 2> views{left, right};
  for (std::size_t s = 0; s < 2; ++s) {
    if (!config_.sensors[s]) continue;
    if (views[s] == nullptr || !to_image(s, *views[s], &images[n])) {
      ++incomplete_;  // a pad missing at this instant: the format holds complete rows only
      return;
    }
    ++n;
  }
  writer_->push(t_ns, std::span<const recording::StreamImage>(images.data(), n));
}

std::filesystem::path numbered_recording_dir(const std::filesystem::path& root,
                                             std::uint16_t number) {
  char name[16];
  std::snprintf(name, sizeof name, "rec-%05u", static_cast<unsigned>(number));
  return root / name;
}

protocol::AckCode start_numbered_recording(const std::string& root, std::uint16_t number,
                                           const RecorderConfig& config,
                                           std::unique_ptr<FrameRecorder>* out,
                                           std::string* message) {
  if (root.empty()) {
    *message = "START_RECORDING refused: the board file has no [record] dir";
    return protocol::AckCode::kNoRecordDir;
  }
  std::error_code ec;
  if (!std::filesystem::is_directory(root, ec)) {
    message->assign("START_RECORDING refused: [record] dir ")
        .append(root)
        .append(" is not a directory");
    return protocol::AckCode::kDiskError;
  }
  const std::filesystem::path dir = numbered_recording_dir(root, number);
  if (std::filesystem::symlink_status(dir, ec).type() != std::filesystem::file_type::not_found) {
    message->assign("START_RECORDING refused: ")
        .append(dir.string())
        .append(" exists (recordings are never overwritten)");
    return protocol::AckCode::kRecordingExists;
  }
  std::string e;
  *out = FrameRecorder::start(dir, config, &e);
  if (!*out) {
    message->assign("START_RECORDING failed: ").append(e);
    return protocol::AckCode::kDiskError;
  }
  message->assign("recording to ").append(dir.string());
  return protocol::AckCode::kAck;
}

std::string FrameRecorder::close() {
  const recording::Status s = writer_->close();
  return s ? std::string() : s.message();
}

}  // namespace tacse3::firmware
