// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: pairing the two sensors' frames by timestamp (pure logic, times injected).
#pragma once

#include <cstdint>

namespace tacse3::firmware {

// The frame at the head of one sensor's queue, as the DSP thread sees it.
struct PendingFrame {
  bool present = false;
  std::int64_t t_ns = 0;        // the frame's capture timestamp
  std::int64_t arrival_ns = 0;  // when the DSP thread first saw it (CLOCK_MONOTONIC)
};

struct PairingConfig {
  // Two frames pair when their timestamps differ by at most this (board: pair_tolerance_us).
  std::int64_t tolerance_ns = 2'000'000;
  // A frame whose partner has not arrived this long after the frame itself is processed alone
  // even though the other sensor still counts as alive. The daemon uses the stale time: while
  // the other sensor delivers at all, its frame for this instant is awaited (a late capture
  // thread must not split pairs), and a skipped partner shows up as a newer frame (rule 3).
  std::int64_t max_wait_ns = 50'000'000;
};

// tolerance_us and stale_ms from the board's [pipeline] table.
PairingConfig pairing_config(int tolerance_us, int stale_ms) noexcept;

enum class PairAction : std::uint8_t {
  kWait = 0,   // nothing to do yet
  kPair,       // process both heads together
  kLeftAlone,  // process the left head alone (its partner is missing or the right is down)
  kRightAlone,
  kDropLeft,  // the left head is older than the last processed sample: discard it
  kDropRight,
};
const char* to_string(PairAction a) noexcept;

// Decides what to do with the two queue heads. `*_alive`: that sensor is expected to deliver
// (configured, streaming and not stale). `last_t_ns`: timestamp of the last processed sample
// (INT64_MIN before the first) -- output samples must be strictly increasing in time.
//  1. A head not newer than last_t_ns is dropped (late frame whose partner was already used).
//     Its pad's thread skips the image stages of a frame already late when it takes it; one that
//     became late during them is dropped with them done (PadStager::stage).
//  2. Both heads within tolerance: pair.
//  3. Both heads, further apart: the older one is processed alone (its partner was dropped).
//  4. One head: alone at once if the other sensor is not alive, else after max_wait_ns.
PairAction decide_pairing(const PendingFrame& left, const PendingFrame& right, bool left_alive,
                          bool right_alive, std::int64_t last_t_ns, std::int64_t now_ns,
                          const PairingConfig& config) noexcept;

}  // namespace tacse3::firmware
