// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: --can-log: the CAN frames the firmware would send, as a `candump -L` log.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "tacse3/tools/replay.hpp"

namespace tacse3::tools {

// True when this build has the protocol encoder (tacse3_protocol).
bool can_log_available() noexcept;

// Per frame: the five classic cycle frames (Timestamp, TwistAngular, TwistLinear,
// PoseOrientation, PosePosition) of node 1 with 11-bit identifiers; every 100 ms of recording
// time the status group (Status, StatusContact, StatusTiming, StatusCounters), and a lone Status
// frame when a contact or slip flag changes (docs/can-protocol.md). Time stamps are the frame
// times t_ns (the board's monotonic clock in a recording), interface "can0".
class CanLogger {
 public:
  ~CanLogger();
  std::string open(const std::filesystem::path& file, dsp::FusionMethod method, ProxyMode mode);
  std::string append(const FrameResult& r);
  std::string close();
  std::int64_t frames_written() const noexcept { return frames_; }

 private:
  std::string emit_status(const FrameResult& r, bool periodic);
  std::FILE* f_ = nullptr;
  std::filesystem::path path_;
  dsp::FusionMethod method_ = dsp::FusionMethod::kJoint;
  ProxyMode mode_ = ProxyMode::kAuto;
  std::uint8_t cycle_counter_ = 0;
  std::uint8_t status_counter_ = 0;
  std::int64_t last_status_ns_ = 0;
  bool have_status_ = false;
  bool first_ = true;
  unsigned last_flags_ = 0;
  std::int64_t frames_ = 0;
};

}  // namespace tacse3::tools
