// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: rolling-counter checking and the cycle reassembler.
#include "tacse3/protocol/reassembler.hpp"

#include <variant>

namespace tacse3::protocol {
namespace {

constexpr unsigned kPartTimestamp = 1u << 0;
constexpr unsigned kPartAngular = 1u << 1;
constexpr unsigned kPartLinear = 1u << 2;
constexpr unsigned kPartOrientation = 1u << 3;
constexpr unsigned kPartPosition = 1u << 4;
constexpr unsigned kAllParts =
    kPartTimestamp | kPartAngular | kPartLinear | kPartOrientation | kPartPosition;

bool is_cycle_message(std::uint8_t message_id) noexcept {
  switch (static_cast<MessageId>(message_id)) {
    case MessageId::kTimestamp:
    case MessageId::kTwistAngular:
    case MessageId::kTwistLinear:
    case MessageId::kPoseOrientation:
    case MessageId::kPosePosition:
    case MessageId::kCycleFd:
      return true;
    default:
      return false;
  }
}

}  // namespace

CounterChecker::Result CounterChecker::check(std::uint8_t counter) noexcept {
  counter = static_cast<std::uint8_t>(counter & 0x0Fu);
  if (!have_) {
    have_ = true;
    last_ = counter;
    return Result::kFirst;
  }
  const auto delta = static_cast<std::uint8_t>((counter - last_) & 0x0Fu);
  last_ = counter;
  if (delta == 1) return Result::kInSequence;
  if (delta == 0) {
    ++repeated_;
    return Result::kRepeated;
  }
  gaps_ += delta - 1u;
  return Result::kGap;
}

CycleReassembler::CycleReassembler(const Endpoint& endpoint) noexcept : endpoint_(endpoint) {}

void CycleReassembler::resync() noexcept {
  have_ = false;
  complete_ = false;
  mask_ = 0;
  have_last_time_ = false;
}

CycleReassembler::Result CycleReassembler::feed(const CanFrame& f, Cycle& out) noexcept {
  SplitId id;
  if (split_id(endpoint_.layout, f.id, f.extended, id) != Status::kOk) return Result::kIgnored;
  if (id.node != endpoint_.node_id || !is_cycle_message(id.message)) return Result::kIgnored;
  Decoded d;
  switch (decode(f, endpoint_.layout, d)) {
    case Status::kOk:
      return feed(d, out);
    case Status::kBadCrc:
      ++stats_.crc_errors;
      return Result::kRejected;
    case Status::kBadCounter:
      ++stats_.counter_errors;
      return Result::kRejected;
    default:
      ++stats_.length_errors;
      return Result::kRejected;
  }
}

CycleReassembler::Result CycleReassembler::feed(const Decoded& d, Cycle& out) noexcept {
  if (d.node_id != endpoint_.node_id) return Result::kIgnored;
  Result r = Result::kIgnored;
  if (const auto* m = std::get_if<TimestampMsg>(&d.payload)) {
    r = accept(m->counter, kPartTimestamp);
    if (r == Result::kPartial) {
      partial_.timestamp_us = m->timestamp_us;
      partial_.estimate_valid = m->estimate_valid;
      partial_.single_sensor = m->single_sensor;
      partial_.pose_reset = m->pose_reset;
      partial_.saturated = m->saturated;
    }
  } else if (const auto* a = std::get_if<AngularMsg>(&d.payload)) {
    r = accept(a->counter, kPartAngular);
    if (r == Result::kPartial) {
      partial_.angular = a->angular;
      partial_.angular_saturated = a->saturated;
    }
  } else if (const auto* l = std::get_if<LinearMsg>(&d.payload)) {
    r = accept(l->counter, kPartLinear);
    if (r == Result::kPartial) {
      partial_.linear = l->linear;
      partial_.linear_saturated = l->saturated;
    }
  } else if (const auto* o = std::get_if<OrientationMsg>(&d.payload)) {
    r = accept(o->counter, kPartOrientation);
    if (r == Result::kPartial) partial_.orientation = o->orientation;
  } else if (const auto* p = std::get_if<PositionMsg>(&d.payload)) {
    r = accept(p->counter, kPartPosition);
    if (r == Result::kPartial) {
      partial_.position = p->position;
      partial_.position_saturated = p->saturated;
    }
  } else if (const auto* c = std::get_if<Cycle>(&d.payload)) {
    r = accept(c->counter, kAllParts);
    if (r == Result::kPartial) partial_ = *c;
  }
  if (r != Result::kPartial) return r;
  if (mask_ != kAllParts) return Result::kPartial;
  // That frame completed the cycle.
  complete_ = true;
  partial_.counter = counter_;
  if (have_last_time_ && partial_.timestamp_us != kTimestampInvalid &&
      partial_.timestamp_us <= last_time_us_) {
    ++stats_.stale;
    return Result::kDropped;
  }
  if (partial_.timestamp_us != kTimestampInvalid) {
    have_last_time_ = true;
    last_time_us_ = partial_.timestamp_us;
  }
  ++stats_.samples;
  out = partial_;
  return Result::kComplete;
}

// Counter bookkeeping for one accepted frame carrying `parts`. Returns kPartial when the frame's
// parts are to be stored (the caller stores them, then checks for completion), kDropped when the
// frame is discarded.
CycleReassembler::Result CycleReassembler::accept(std::uint8_t counter, unsigned parts) noexcept {
  ++stats_.frames;
  counter = static_cast<std::uint8_t>(counter & 0x0Fu);
  if (have_ && counter == counter_) {
    if (complete_ || (mask_ & parts) != 0) {
      ++stats_.repeated;
      return Result::kDropped;
    }
  } else if (have_) {
    const auto delta = static_cast<unsigned>((counter - counter_) & 0x0Fu);
    if (delta == 15u) {
      // A frame of the cycle before the current one: late or repeated. Keep the current cycle.
      ++stats_.repeated;
      return Result::kDropped;
    }
    if (!complete_) ++stats_.incomplete;
    stats_.counter_gaps += delta - 1u;
    have_ = false;
  }
  if (!have_) {
    have_ = true;
    complete_ = false;
    counter_ = counter;
    mask_ = 0;
    partial_ = Cycle{};
  }
  mask_ |= parts;
  return Result::kPartial;
}

}  // namespace tacse3::protocol
