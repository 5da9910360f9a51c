// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: fixed-size window of timing samples with percentiles (no heap, no locks).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>

namespace tacse3::firmware {

// The last N samples (microseconds). percentile() sorts a copy on the stack: O(N log N) with
// N = 256, cheap enough at the 10 Hz status rate, and nothing allocates.
template <std::size_t N = 256>
class TimingWindow {
 public:
  void add(std::uint32_t us) noexcept {
    samples_[next_] = us;
    next_ = (next_ + 1) % N;
    count_ = count_ < N ? count_ + 1 : N;
  }
  std::size_t count() const noexcept { return count_; }
  void clear() noexcept { count_ = next_ = 0; }
  // Nearest-rank percentile p in [0, 100] over the window; -1 when empty.
  std::int64_t percentile(double p) const noexcept {
    if (count_ == 0) return -1;
    std::array<std::uint32_t, N> copy;
    std::copy_n(samples_.begin(), count_, copy.begin());
    std::size_t rank = static_cast<std::size_t>(p / 100.0 * static_cast<double>(count_) + 0.999999);
    rank = std::clamp<std::size_t>(rank, 1, count_);
    std::nth_element(copy.begin(), copy.begin() + static_cast<std::ptrdiff_t>(rank - 1),
                     copy.begin() + static_cast<std::ptrdiff_t>(count_));
    return copy[rank - 1];
  }

 private:
  std::array<std::uint32_t, N> samples_{};
  std::size_t next_ = 0;
  std::size_t count_ = 0;
};

}  // namespace tacse3::firmware
