// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: rolling-counter checking and the cycle reassembler (controller side).
#pragma once

#include <cstdint>

#include "tacse3/protocol/codec.hpp"

namespace tacse3::protocol {

// Checks a 4-bit rolling counter that must advance by exactly one per message (status counter).
class CounterChecker {
 public:
  enum class Result : std::uint8_t { kFirst, kInSequence, kGap, kRepeated };
  Result check(std::uint8_t counter) noexcept;
  std::uint32_t gaps() const noexcept { return gaps_; }          // missing counter values
  std::uint32_t repeated() const noexcept { return repeated_; }  // same value twice in a row
  void reset() noexcept { *this = CounterChecker{}; }

 private:
  bool have_ = false;
  std::uint8_t last_ = 0;
  std::uint32_t gaps_ = 0;
  std::uint32_t repeated_ = 0;
};

struct ReassemblerStats {
  std::uint32_t frames = 0;          // cycle frames of this node accepted (valid CRC and length)
  std::uint32_t samples = 0;         // complete cycles emitted
  std::uint32_t crc_errors = 0;      // cycle frames of this node with a bad CRC
  std::uint32_t length_errors = 0;   // cycle frames of this node with a wrong length/format
  std::uint32_t counter_errors = 0;  // CAN FD cycle frames whose five counters disagree
  std::uint32_t counter_gaps = 0;    // counter values skipped (cycles never seen at all)
  std::uint32_t repeated = 0;        // frames of a cycle already complete, or of the cycle before
  std::uint32_t incomplete = 0;      // cycles abandoned with frames missing (truncated)
  std::uint32_t stale = 0;           // complete cycles whose timestamp did not advance (dropped)
};

// Reassembles the cycle frames of one node into complete twist+pose samples. A sample is emitted
// only when all five classic frames of one counter value (or one CAN FD cycle frame) arrived
// with valid CRCs, and its timestamp is newer than the last emitted one. Frame order within a
// cycle does not matter. Fixed size, no allocation.
class CycleReassembler {
 public:
  enum class Result : std::uint8_t {
    kIgnored,   // not a cycle frame of this node (other node, status, other id)
    kRejected,  // a cycle frame of this node that failed CRC / length / counter checks
    kPartial,   // accepted, cycle not complete yet
    kComplete,  // accepted and `out` holds a complete cycle
    kDropped,   // accepted but discarded (repeated or stale)
  };

  CycleReassembler() noexcept = default;  // node 1, 11-bit identifiers
  explicit CycleReassembler(const Endpoint& endpoint) noexcept;

  Result feed(const CanFrame& f, Cycle& out) noexcept;
  // For callers that already decoded the frame (decode() returned kOk).
  Result feed(const Decoded& d, Cycle& out) noexcept;

  const ReassemblerStats& stats() const noexcept { return stats_; }
  const Endpoint& endpoint() const noexcept { return endpoint_; }
  // Forget the cycle in progress and the counter history (statistics are kept).
  void resync() noexcept;

 private:
  Result accept(std::uint8_t counter, unsigned parts) noexcept;

  Endpoint endpoint_;
  ReassemblerStats stats_;
  Cycle partial_;
  bool have_ = false;      // partial_/counter_ describe a cycle
  bool complete_ = false;  // that cycle was completed (emitted or dropped as stale)
  std::uint8_t counter_ = 0;
  unsigned mask_ = 0;
  bool have_last_time_ = false;
  std::uint64_t last_time_us_ = 0;
};

}  // namespace tacse3::protocol
