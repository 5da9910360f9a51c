// SPDX-License-Identifier: Apache-2.0
// tacse3 canmon: decoding, per-node reassembly, error counting and bus-load metering.
#include "monitor.hpp"

#include <variant>

namespace tacse3::canmon {

Monitor::Monitor(const MonitorOptions& o) : options_(o) {
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    tp::Endpoint ep;
    ep.node_id = static_cast<std::uint8_t>(i);
    ep.layout = o.layout;
    nodes_[i].reassembler = tp::CycleReassembler(ep);
  }
}

double Monitor::average_load() const {
  if (!bus_.started || bus_.last_us <= bus_.first_us) return 0.0;
  const double span_s = static_cast<double>(bus_.last_us - bus_.first_us) * 1e-6;
  if (span_s < bus_.window_s) return 0.0;
  return bus_.total_bits / options_.timing.nominal_bps / span_s;
}

void Monitor::meter(const hal::can::RxFrame& rx, Sink& sink) {
  BusLoadMeter& b = bus_;
  if (!b.started) {
    b.started = true;
    b.first_us = rx.time_us;
    b.window_start_us = rx.time_us;
  }
  const auto window_us = static_cast<std::uint64_t>(b.window_s * 1e6);
  while (rx.time_us >= b.window_start_us + window_us) {
    b.last_window_load = b.window_bits / options_.timing.nominal_bps / b.window_s;
    if (b.last_window_load > b.peak_load) b.peak_load = b.last_window_load;
    b.window_bits = 0.0;
    b.window_start_us += window_us;
    sink.on_window(b.window_start_us);
  }
  bool exact = true;
  const double bits = tp::frame_bits_on_wire(rx.frame, options_.timing, &exact);
  b.all_exact = b.all_exact && exact;
  b.window_bits += bits;
  b.total_bits += bits;
  if (rx.time_us > b.last_us) b.last_us = rx.time_us;
}

void Monitor::ingest(const hal::can::RxFrame& rx, Sink& sink) {
  ++totals_.frames;
  meter(rx, sink);
  tp::Decoded d;
  const tp::Status s = tp::decode(rx.frame, options_.layout, d);
  tp::SplitId id;
  const bool ours =
      tp::split_id(options_.layout, rx.frame.id, rx.frame.extended, id) == tp::Status::kOk &&
      tp::find_message(id.message) != nullptr;
  if (!ours) {
    ++totals_.foreign_frames;
    return;
  }
  if (options_.node != 0 && id.node != options_.node) return;
  NodeView& n = nodes_[id.node];
  n.seen = true;
  if (s != tp::Status::kOk) {
    if (s == tp::Status::kBadCrc) {
      ++totals_.crc_errors;
      ++n.stats.crc_errors;
    } else {
      ++totals_.length_errors;
      ++n.stats.length_errors;
    }
    tp::Cycle ignored;
    (void)n.reassembler.feed(rx.frame, ignored);  // the reassembler counts its own frames
    sink.on_error(rx.time_us, rx.frame, s);
    return;
  }
  ++totals_.tacse3_frames;
  ++n.stats.frames;
  tp::Cycle c;
  switch (d.message) {
    case tp::MessageId::kTimestamp:
    case tp::MessageId::kTwistAngular:
    case tp::MessageId::kTwistLinear:
    case tp::MessageId::kPoseOrientation:
    case tp::MessageId::kPosePosition:
    case tp::MessageId::kCycleFd:
      if (n.reassembler.feed(d, c) == tp::CycleReassembler::Result::kComplete) {
        if (!n.cycle) n.first_cycle_time_us = rx.time_us;
        n.last_cycle_time_us = rx.time_us;
        n.cycle = c;
        sink.on_cycle(id.node, rx.time_us, c);
      }
      return;
    case tp::MessageId::kStatus: {
      const auto& m = std::get<tp::StatusMsg>(d.payload);
      (void)n.status_counter.check(m.counter);  // counts gaps and repeats
      n.stats.status_counter_gaps = n.status_counter.gaps();
      n.stats.status_repeated = n.status_counter.repeated();
      n.status = m;
      break;
    }
    case tp::MessageId::kStatusContact:
      n.contact = std::get<tp::ContactMsg>(d.payload);
      break;
    case tp::MessageId::kStatusTiming:
      n.timing = std::get<tp::TimingMsg>(d.payload);
      break;
    case tp::MessageId::kStatusCounters:
      n.counters = std::get<tp::CountersMsg>(d.payload);
      break;
    case tp::MessageId::kAck:
      n.ack = std::get<tp::Ack>(d.payload);
      break;
    case tp::MessageId::kCommand:
      break;
  }
  sink.on_message(id.node, rx.time_us, d);
}

}  // namespace tacse3::canmon
