// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: in-memory simulated recordings for the benchmark and the accuracy test.
#include "tacse3/tools/sim_source.hpp"

#include <atomic>
#include <cmath>

namespace tacse3::tools {

namespace rec = tacse3::recording;

std::unique_ptr<SimSource> SimSource::create(const sim::SimConfig& config, const std::string& name,
                                             int channels, std::string* error) {
  if (channels != 1 && channels != 3) {
    *error = name + ": channels must be 1 or 3";
    return nullptr;
  }
  if (config.rig.width != kPipelineWidth || config.rig.height != kPipelineHeight) {
    *error = name + ": the pipeline needs 320x240 frames";
    return nullptr;
  }
  std::unique_ptr<SimSource> s(new SimSource());
  std::string err;
  s->sim_ = sim::Simulator::create(config, &err);
  if (!s->sim_) {
    *error = name + ": " + err;
    return nullptr;
  }
  s->channels_ = channels;
  const sim::Scenario& scn = s->sim_->scenario();
  SourceInfo& in = s->info_;
  in.name = name;
  in.width = config.rig.width;
  in.height = config.rig.height;
  in.has_sensor = {config.sensors[0], config.sensors[1]};
  in.pixel_pitch_mm = config.rig.pixel_pitch_mm;
  in.finger_separation_mm = s->sim_->finger_separation_mm();
  // The part of tacse3-sim's "sim" block the tools read (the regime, for reports only).
  in.extra_json =
      std::string("{\"sim\":{\"regime\":\"") + (scn.sliding() ? "slide" : "stick") + "\"}}";
  const int n = scn.frame_count();
  in.t_ns.resize(static_cast<std::size_t>(n));
  in.truth.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const std::int64_t t = scn.frame_time_ns(i);
    in.t_ns[static_cast<std::size_t>(i)] = t;
    const sim::Pose p = s->sim_->truth(t);
    rec::TruthSample& ts = in.truth[static_cast<std::size_t>(i)];
    ts.t_ns = t;
    ts.qw = p.q.w();
    ts.qx = p.q.x();
    ts.qy = p.q.y();
    ts.qz = p.q.z();
    ts.px = p.p.x() * 1e-3;
    ts.py = p.p.y() * 1e-3;
    ts.pz = p.p.z() * 1e-3;
  }
  for (std::size_t k = 0; k < 2; ++k) {
    if (in.has_sensor[k]) s->buf_[k].assign(s->sim_->frame_bytes(channels), 0);
  }
  return s;
}

namespace {
// Bytes of kept frames, over every SimSource of the process (the benchmark reads several
// recordings on several threads).
std::atomic<std::size_t> g_cached_bytes{0};
}  // namespace

SimSource::~SimSource() {
  g_cached_bytes.fetch_sub(cached_bytes_, std::memory_order_relaxed);
}

std::string SimSource::read(std::size_t index, std::array<const dsp::FrameView*, 2>* views) {
  *views = {nullptr, nullptr};
  if (index >= info_.t_ns.size()) return info_.name + ": frame index out of range";
  const bool kept = index < cache_.size() && !cache_[index][info_.has_sensor[0] ? 0 : 1].empty();
  if (kept) {
    ++cache_hits_;
  } else if (std::string e = simulate_to(index); !e.empty()) {
    return e;
  }
  for (std::size_t k = 0; k < 2; ++k) {
    if (!info_.has_sensor[k]) continue;
    const std::uint8_t* px = kept ? cache_[index][k].data() : buf_[k].data();
    views_[k] = frame_view(px, info_.width, info_.height, channels_);
    (*views)[k] = &views_[k];
  }
  return {};
}

// Simulates up to frame `index` and renders it into buf_: from the frame after the last one
// simulated, or from frame 0 when `index` is not after it. Its labels follow the frames
// simulated; a frame served from the cache changes neither.
std::string SimSource::simulate_to(std::size_t index) {
  if (static_cast<std::int64_t>(index) <= last_) {
    for (std::size_t k = 0; k < 2; ++k) sim_->reset(static_cast<sim::Sensor>(k));
    info_.labels.clear();
    last_ = -1;
  }
  // Frames skipped by the caller are still simulated (the physics needs every step).
  for (std::int64_t i = last_ + 1; i <= static_cast<std::int64_t>(index); ++i) {
    const std::int64_t t = info_.t_ns[static_cast<std::size_t>(i)];
    const bool want_image = i == static_cast<std::int64_t>(index);
    for (std::size_t k = 0; k < 2; ++k) {
      if (!info_.has_sensor[k]) continue;
      const auto s = static_cast<sim::Sensor>(k);
      const sim::SimStatus st =
          want_image ? sim_->render(s, t, buf_[k], channels_) : sim_->step(s, t);
      if (st != sim::SimStatus::kOk) return info_.name + ": simulator: " + sim::to_string(st);
      const rec::SimLabel l = sim_label(*sim_, s, i, t);
      info_.labels.push_back(l);
    }
  }
  last_ = static_cast<std::int64_t>(index);
  keep(index);
  return {};
}

// Copies the frame just rendered into the cache while the process-wide budget allows.
void SimSource::keep(std::size_t index) {
  std::size_t bytes = 0;
  for (std::size_t k = 0; k < 2; ++k) bytes += info_.has_sensor[k] ? buf_[k].size() : 0;
  std::size_t used = g_cached_bytes.load(std::memory_order_relaxed);
  do {
    if (used + bytes > kFrameCacheBytes) return;
  } while (!g_cached_bytes.compare_exchange_weak(used, used + bytes, std::memory_order_relaxed));
  cached_bytes_ += bytes;
  if (cache_.empty()) cache_.resize(info_.t_ns.size());
  for (std::size_t k = 0; k < 2; ++k) {
    if (info_.has_sensor[k]) cache_[index][k] = buf_[k];
  }
}

rec::SimLabel sim_label(const sim::Simulator& simulator, sim::Sensor sensor, std::int64_t index,
                        std::int64_t t_ns) {
  const sim::PadLabels& pl = simulator.labels(sensor);
  rec::SimLabel l;
  l.index = index;
  l.t_ns = t_ns;
  l.sensor = static_cast<rec::SensorId>(sensor);
  l.phase = sim::to_string(simulator.scenario().phase(sim::Simulator::seconds(t_ns)));
  l.in_contact = pl.in_contact;
  l.slipping = pl.slipping;
  l.slip_fraction = pl.slip_fraction;
  l.area_mm2 = pl.area_mm2;
  l.centroid_u_mm = pl.centroid_mm.x();
  l.centroid_v_mm = pl.centroid_mm.y();
  l.peak_depth_mm = pl.peak_depth_mm;
  return l;
}

}  // namespace tacse3::tools
