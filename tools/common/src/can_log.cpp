// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: --can-log: encodes each replayed cycle with the protocol library, candump -L lines.
#include "tacse3/tools/can_log.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#ifdef TACSE3_TOOLS_HAVE_PROTOCOL
#include "tacse3/protocol/protocol.hpp"
#endif

namespace tacse3::tools {

#ifdef TACSE3_TOOLS_HAVE_PROTOCOL
namespace proto = tacse3::protocol;

namespace {

std::string write_frame(std::FILE* f, const std::filesystem::path& path, std::int64_t t_ns,
                        const proto::CanFrame& frame) {
  proto::LogRecord rec;
  rec.time_us = static_cast<std::uint64_t>(std::max<std::int64_t>(t_ns, 0) / 1000);
  std::memcpy(rec.iface.data(), "can0", 5);
  rec.frame = frame;
  char line[proto::kCandumpLineMax + 2];
  const std::size_t n = proto::format_candump_line(rec, line, sizeof(line));
  if (n == 0) return path.string() + ": internal error: frame not representable as candump -L";
  line[n] = '\n';
  if (std::fwrite(line, 1, n + 1, f) != n + 1) return path.string() + ": write error";
  return {};
}

proto::VelocityMode to_proto(ProxyMode m) {
  switch (m) {
    case ProxyMode::kAuto:
      return proto::VelocityMode::kAuto;
    case ProxyMode::kVelocity:
      return proto::VelocityMode::kVelocity;
    case ProxyMode::kDisplacement:
      return proto::VelocityMode::kDisplacement;
  }
  return proto::VelocityMode::kAuto;
}

}  // namespace

bool can_log_available() noexcept {
  return true;
}

CanLogger::~CanLogger() {
  if (f_ != nullptr) std::fclose(f_);
}

std::string CanLogger::open(const std::filesystem::path& file, dsp::FusionMethod method,
                            ProxyMode mode) {
  path_ = file;
  method_ = method;
  mode_ = mode;
  f_ = std::fopen(file.c_str(), "w");
  if (f_ == nullptr) return file.string() + ": cannot open the --can-log file for writing";
  return {};
}

std::string CanLogger::emit_status(const FrameResult& r, bool periodic) {
  proto::TxConfig tx;
  proto::StatusGroup g;
  proto::StatusMsg& s = g.status;
  const bool any_contact = r.contact[0] || r.contact[1];
  s.state = !any_contact      ? proto::State::kNoContact
            : r.single_sensor ? proto::State::kDegradedSingleSensor
                              : proto::State::kTracking;
  s.health_left = r.present[0] ? proto::SensorHealth::kOk : proto::SensorHealth::kNotAvailable;
  s.health_right = r.present[1] ? proto::SensorHealth::kOk : proto::SensorHealth::kNotAvailable;
  s.contact_left = r.contact[0];
  s.contact_right = r.contact[1];
  s.slip_left = r.slipping[0].value_or(false);
  s.slip_right = r.slipping[1].value_or(false);
  s.fusion = method_ == dsp::FusionMethod::kPaper ? proto::FusionMethod::kPaper
                                                  : proto::FusionMethod::kJoint;
  s.velocity_mode = to_proto(mode_);
  s.confidence = std::clamp(r.confidence, 0.0, 1.0);
  const double nan = std::nan("");
  g.contact.area_left_m2 = nan;  // not computed by the replay
  g.contact.area_right_m2 = nan;
  g.contact.confidence_left = nan;
  g.contact.confidence_right = nan;
  g.timing.dsp_time_s = nan;
  g.timing.latency_p50_s = nan;
  g.timing.latency_p99_s = nan;
  std::array<proto::CanFrame, 4> frames{};
  if (proto::encode_status_group(g, status_counter_, tx, frames) != proto::Status::kOk) {
    return path_.string() + ": internal error: status encoding failed";
  }
  status_counter_ = static_cast<std::uint8_t>((status_counter_ + 1) & 0x0F);
  const std::size_t count = periodic ? frames.size() : 1;  // change-triggered: Status alone
  for (std::size_t i = 0; i < count; ++i) {
    if (std::string e = write_frame(f_, path_, r.t_ns, frames[i]); !e.empty()) return e;
  }
  return {};
}

std::string CanLogger::append(const FrameResult& r) {
  if (f_ == nullptr) return path_.string() + ": not open";
  proto::Cycle c;
  c.timestamp_us = static_cast<std::uint64_t>(std::max<std::int64_t>(r.t_ns, 0) / 1000);
  c.estimate_valid = r.estimate_valid;
  c.single_sensor = r.single_sensor;
  c.pose_reset = first_;
  c.angular = {r.twist[0], r.twist[1], r.twist[2]};
  c.linear = {r.twist[3], r.twist[4], r.twist[5]};
  c.orientation = {r.pose.q.w(), r.pose.q.x(), r.pose.q.y(), r.pose.q.z()};
  c.position = {r.pose.p.x(), r.pose.p.y(), r.pose.p.z()};
  proto::TxConfig tx;
  proto::CycleFrames out;
  if (proto::encode_cycle(c, cycle_counter_, tx, out) != proto::Status::kOk) {
    return path_.string() + ": internal error: cycle encoding failed";
  }
  cycle_counter_ = static_cast<std::uint8_t>((cycle_counter_ + 1) & 0x0F);
  for (std::size_t i = 0; i < out.count; ++i) {
    if (std::string e = write_frame(f_, path_, r.t_ns, out.frames[i]); !e.empty()) return e;
  }
  // Status: every 100 ms (with the rest of the group), or alone when a flag changes.
  const unsigned flags = (r.contact[0] ? 1u : 0u) | (r.contact[1] ? 2u : 0u) |
                         (r.slipping[0].value_or(false) ? 4u : 0u) |
                         (r.slipping[1].value_or(false) ? 8u : 0u) | (r.single_sensor ? 16u : 0u);
  const bool periodic = !have_status_ || r.t_ns - last_status_ns_ >= 100'000'000;
  if (periodic) {
    if (std::string e = emit_status(r, true); !e.empty()) return e;
    last_status_ns_ = have_status_ ? last_status_ns_ + 100'000'000 : r.t_ns;
    if (r.t_ns - last_status_ns_ >= 100'000'000) last_status_ns_ = r.t_ns;
    have_status_ = true;
  } else if (flags != last_flags_) {
    if (std::string e = emit_status(r, false); !e.empty()) return e;
  }
  last_flags_ = flags;
  first_ = false;
  ++frames_;
  return {};
}

std::string CanLogger::close() {
  if (f_ == nullptr) return {};
  const bool ok = std::fclose(f_) == 0;
  f_ = nullptr;
  return ok ? std::string() : path_.string() + ": write error on close";
}

#else  // no protocol library in this build

bool can_log_available() noexcept {
  return false;
}
CanLogger::~CanLogger() = default;
std::string CanLogger::open(const std::filesystem::path& file, dsp::FusionMethod, ProxyMode) {
  return file.string() +
         ": --can-log needs the protocol library (tacse3_protocol), which this "
         "build does not have";
}
std::string CanLogger::append(const FrameResult&) {
  return "--can-log not available";
}
std::string CanLogger::close() {
  return {};
}
std::string CanLogger::emit_status(const FrameResult&, bool) {
  return {};
}

#endif

}  // namespace tacse3::tools
