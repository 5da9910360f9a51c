// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: counts frames missing from a driver's 32-bit sequence numbers, across wraparound.
#pragma once

#include <cstdint>

namespace tacse3::hal {

// Feed every delivered frame's sequence number; update() returns how many frames are missing
// just before it. Unsigned modular arithmetic makes 0xFFFFFFFF -> 0 a step of one. A step of 0
// (repeated number) or larger than max_gap (a backwards jump: the driver restarted its
// counter) is not a drop: the tracker resynchronises and counts a restart instead.
class SequenceTracker {
 public:
  static constexpr std::uint32_t kDefaultMaxGap = 1u << 16;  // ~9 minutes at 120 Hz

  explicit SequenceTracker(std::uint32_t max_gap = kDefaultMaxGap) noexcept : max_gap_(max_gap) {}

  std::uint32_t update(std::uint32_t sequence) noexcept;
  // Forget the previous number: the next update() starts a new run (after STREAMON, reopen).
  void reset() noexcept { have_last_ = false; }

  std::uint64_t dropped() const noexcept { return dropped_; }
  std::uint64_t restarts() const noexcept { return restarts_; }
  std::uint64_t repeats() const noexcept { return repeats_; }

 private:
  std::uint32_t max_gap_;
  bool have_last_ = false;
  std::uint32_t last_ = 0;
  std::uint64_t dropped_ = 0;
  std::uint64_t restarts_ = 0;
  std::uint64_t repeats_ = 0;
};

}  // namespace tacse3::hal
