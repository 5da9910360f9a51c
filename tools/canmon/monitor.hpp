// SPDX-License-Identifier: Apache-2.0
// tacse3 canmon: decoding, per-node reassembly, error counting and bus-load metering.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "tacse3/hal/can/channel.hpp"
#include "tacse3/protocol/protocol.hpp"

namespace tacse3::canmon {

namespace tp = tacse3::protocol;

struct NodeStats {
  std::uint64_t frames = 0;  // valid tacse3 frames from/to this node
  std::uint64_t crc_errors = 0;
  std::uint64_t length_errors = 0;
  std::uint32_t status_counter_gaps = 0;
  std::uint32_t status_repeated = 0;
};

struct NodeView {
  bool seen = false;
  tp::CycleReassembler reassembler;
  tp::CounterChecker status_counter;
  NodeStats stats;
  std::optional<tp::Cycle> cycle;  // latest complete cycle
  std::optional<tp::StatusMsg> status;
  std::optional<tp::ContactMsg> contact;
  std::optional<tp::TimingMsg> timing;
  std::optional<tp::CountersMsg> counters;
  std::optional<tp::Ack> ack;
  std::uint64_t first_cycle_time_us = 0;  // log/receive time of the first complete cycle
  std::uint64_t last_cycle_time_us = 0;
};

struct BusLoadMeter {
  double window_s = 1.0;
  std::uint64_t window_start_us = 0;
  double window_bits = 0.0;  // nominal-bit-time equivalent within the current window
  double last_window_load = 0.0;
  double peak_load = 0.0;
  double total_bits = 0.0;
  std::uint64_t first_us = 0;
  std::uint64_t last_us = 0;
  bool started = false;
  bool all_exact = true;  // false once an FD frame was estimated with worst-case stuffing
};

struct Totals {
  std::uint64_t frames = 0;          // data frames read
  std::uint64_t tacse3_frames = 0;   // decoded without error
  std::uint64_t foreign_frames = 0;  // identifiers that are not tacse3's under the layout
  std::uint64_t crc_errors = 0;
  std::uint64_t length_errors = 0;
};

// What the monitor reports, in order, as frames come in.
class Sink {
 public:
  virtual ~Sink() = default;
  virtual void on_cycle(std::uint8_t node, std::uint64_t rx_time_us, const tp::Cycle& c) = 0;
  virtual void on_message(std::uint8_t node, std::uint64_t rx_time_us, const tp::Decoded& d) = 0;
  virtual void on_error(std::uint64_t rx_time_us, const tp::CanFrame& f, tp::Status s) = 0;
  // Once per bus-load window of log/receive time.
  virtual void on_window(std::uint64_t rx_time_us) = 0;
};

struct MonitorOptions {
  tp::IdLayout layout{};
  int node = 0;  // 0: every node
  tp::BitTiming timing{};
};

class Monitor {
 public:
  explicit Monitor(const MonitorOptions& o);
  void ingest(const hal::can::RxFrame& rx, Sink& sink);

  const NodeView& node(std::uint8_t id) const { return nodes_[id & 63u]; }
  const Totals& totals() const { return totals_; }
  const BusLoadMeter& bus() const { return bus_; }
  const MonitorOptions& options() const { return options_; }
  // Average load over the whole observation (0 if less than one window was seen).
  double average_load() const;

 private:
  void meter(const hal::can::RxFrame& rx, Sink& sink);
  MonitorOptions options_;
  std::array<NodeView, 64> nodes_{};
  Totals totals_;
  BusLoadMeter bus_;
};

}  // namespace tacse3::canmon
