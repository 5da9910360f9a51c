// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: counts frames missing from a driver's 32-bit sequence numbers, across wraparound.
#include "tacse3/hal/camera/sequence.hpp"

namespace tacse3::hal {

std::uint32_t SequenceTracker::update(std::uint32_t sequence) noexcept {
  if (!have_last_) {
    have_last_ = true;
    last_ = sequence;
    return 0;
  }
  const std::uint32_t step = sequence - last_;  // modulo 2^32
  if (step == 0) {
    ++repeats_;
    return 0;
  }
  last_ = sequence;
  if (step > max_gap_) {
    ++restarts_;
    return 0;
  }
  const std::uint32_t missing = step - 1;
  dropped_ += missing;
  return missing;
}

}  // namespace tacse3::hal
