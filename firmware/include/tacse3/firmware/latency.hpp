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

// The latencies of one sent cycle, each into its own window. `sent_ns`: the cycle's last frame
// handed to the channel (CLOCK_MONOTONIC).
//  - sample: from the cycle's SampleTime (the later frame's capture timestamp, what the Timestamp
//    frame carries) -- StatusTiming's LatencyP50/P99, which tacse3-truth subtracts from
//    arrival - SampleTime (docs/truth.md);
//  - later / earlier arrival: from the moment the capture thread received the sample's later /
//    earlier frame from its camera (equal for one pad alone): the firmware's own share.
// A value outside (0, 10 s) is not a latency (a camera not stamping on CLOCK_MONOTONIC) and is
// left out of that window.
class CycleLatency {
 public:
  struct Times {
    std::int64_t sample_ns = 0;
    std::int64_t later_arrival_ns = 0;
    std::int64_t earlier_arrival_ns = 0;
    std::int64_t sent_ns = 0;
  };
  void add(const Times& t) noexcept {
    last_sample_us_ = add_to(sample_, t.sent_ns - t.sample_ns, last_sample_us_);
    (void)add_to(later_, t.sent_ns - t.later_arrival_ns, -1);
    (void)add_to(earlier_, t.sent_ns - t.earlier_arrival_ns, -1);
  }
  const TimingWindow<>& sample() const noexcept { return sample_; }
  const TimingWindow<>& later_arrival() const noexcept { return later_; }
  const TimingWindow<>& earlier_arrival() const noexcept { return earlier_; }
  std::int64_t last_sample_us() const noexcept { return last_sample_us_; }  // -1: none yet

 private:
  static std::int64_t add_to(TimingWindow<>& w, std::int64_t ns, std::int64_t last) noexcept {
    if (ns <= 0 || ns >= 10'000'000'000) return last;
    w.add(static_cast<std::uint32_t>(ns / 1000));
    return ns / 1000;
  }
  TimingWindow<> sample_;
  TimingWindow<> later_;
  TimingWindow<> earlier_;
  std::int64_t last_sample_us_ = -1;
};

}  // namespace tacse3::firmware
