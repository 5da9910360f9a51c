// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the recording-directory frame source (PNG decoding through tacse3_recording).
#include "tacse3/tools/source.hpp"

#include <nlohmann/json.hpp>

namespace tacse3::tools {

bool is_simulator_recording(const SourceInfo& info) {
  if (info.extra_json.empty()) return false;
  const auto j = nlohmann::json::parse(info.extra_json, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return false;
  const auto sim = j.find("sim");
  if (sim == j.end() || !sim->is_object()) return false;
  const auto gen = sim->find("generator");
  return gen != sim->end() && gen->is_string() && gen->get<std::string>() == "tacse3-sim";
}

namespace rec = tacse3::recording;

dsp::FrameView frame_view(const std::uint8_t* data, int width, int height, int channels) noexcept {
  dsp::FrameView v;
  v.data = data;
  v.width = width;
  v.height = height;
  v.stride_bytes = width * channels;
  v.size_bytes = static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
                 static_cast<std::size_t>(channels);
  v.format = channels == 3 ? dsp::PixelFormat::kRgb888 : dsp::PixelFormat::kGrey;
  return v;
}

std::unique_ptr<RecordingSource> RecordingSource::open(const std::filesystem::path& dir,
                                                       std::string* error) {
  auto opened = rec::RecordingReader::open(dir);
  if (!opened) {
    *error = opened.status().message();
    return nullptr;
  }
  std::unique_ptr<RecordingSource> s(new RecordingSource(std::move(opened).value()));
  const rec::RecordingInfo& ri = s->reader_.info();
  const std::string json = (s->reader_.dir() / "recording.json").string();
  if (ri.width != kPipelineWidth || ri.height != kPipelineHeight) {
    *error = json + ": frames are " + std::to_string(ri.width) + "x" + std::to_string(ri.height) +
             "; the tacse3 pipeline needs " + std::to_string(kPipelineWidth) + "x" +
             std::to_string(kPipelineHeight) + " (DM-Tac) frames";
    return nullptr;
  }
  if (s->reader_.frame_count() == 0) {
    *error = (s->reader_.dir() / "frames.csv").string() + ": the recording has no frames";
    return nullptr;
  }
  SourceInfo& in = s->info_;
  in.name = dir.string();
  in.width = ri.width;
  in.height = ri.height;
  in.pixel_pitch_mm = ri.rig.pixel_pitch_mm;
  in.finger_separation_mm = ri.rig.finger_separation_mm;
  in.t_ns = s->reader_.times_ns();
  in.truth = s->reader_.truth();
  in.labels = s->reader_.sim_labels();
  in.extra_json = ri.extra_json;
  for (int k = 0; k < 2; ++k) {
    s->slot_[static_cast<std::size_t>(k)] = s->reader_.slot_of(static_cast<rec::SensorId>(k));
    in.has_sensor[static_cast<std::size_t>(k)] = s->slot_[static_cast<std::size_t>(k)] >= 0;
  }
  return s;
}

std::string RecordingSource::read(std::size_t index, std::array<const dsp::FrameView*, 2>* views) {
  *views = {nullptr, nullptr};
  if (index >= reader_.frame_count()) {
    return (reader_.dir() / "frames.csv").string() + ": frame " + std::to_string(index) +
           " out of range";
  }
  if (rec::Status st = reader_.read_frame(index, &frame_); !st) return st.message();
  for (std::size_t k = 0; k < 2; ++k) {
    if (slot_[k] < 0) continue;
    const rec::Image& im = frame_.images[static_cast<std::size_t>(slot_[k])];
    if (im.width != kPipelineWidth || im.height != kPipelineHeight) {
      return reader_.frame_path(static_cast<std::size_t>(slot_[k]), index).string() +
             ": frame is " + std::to_string(im.width) + "x" + std::to_string(im.height) +
             ", the pipeline needs 320x240";
    }
    views_[k] = frame_view(im.pixels.data(), im.width, im.height, im.channels);
    (*views)[k] = &views_[k];
  }
  return {};
}

}  // namespace tacse3::tools
