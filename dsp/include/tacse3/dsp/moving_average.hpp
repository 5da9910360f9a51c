// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: moving average of the last L twists (ring buffer, compile-time maximum length).
#pragma once

#include <Eigen/Core>
#include <array>

#include "tacse3/dsp/calibration.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// Paper Sec. IV-D: ξ̄_t = (1/L) Σ_{j=t−L+1..t} ξ*_j.
// Warm-up: until L samples have been pushed, the mean is over the samples received so far (not
// zero-padded), so the first frames after a reset are not attenuated.
// The sum is recomputed over the window on every push (≤ kMax · 6 additions) instead of a running
// sum, so no round-off accumulates however long it runs: the output is the mean of exactly the
// last L inputs. A non-finite input is replaced by zero (and counted) so NaN can never enter.
template <int kMax = kMaxMovingAverage>
class MovingAverage {
 public:
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  static_assert(kMax >= 1, "window must hold at least one sample");

  explicit MovingAverage(int length = 1) noexcept { (void)set_length(length); }

  // kBadArgument (length unchanged) unless 1 ≤ length ≤ kMax. Changing the length resets.
  Status set_length(int length) noexcept {
    if (length < 1 || length > kMax) return Status::kBadArgument;
    length_ = length;
    reset();
    return Status::kOk;
  }
  int length() const noexcept { return length_; }
  int size() const noexcept { return count_; }
  int rejected() const noexcept { return rejected_; }

  void reset() noexcept {
    count_ = 0;
    head_ = 0;
    rejected_ = 0;
    mean_.setZero();
  }

  // Pushes one sample and returns the mean over the last min(size, L) samples.
  const Vector6d& push(const Vector6d& x) noexcept {
    Vector6d s = x;
    if (!s.allFinite()) {
      s.setZero();
      ++rejected_;
    }
    buf_[static_cast<std::size_t>(head_)] = s;
    head_ = (head_ + 1) % length_;
    if (count_ < length_) ++count_;
    Vector6d sum = Vector6d::Zero();
    for (int i = 0; i < count_; ++i) sum += buf_[static_cast<std::size_t>(i)];
    mean_ = sum / static_cast<double>(count_);
    return mean_;
  }
  const Vector6d& mean() const noexcept { return mean_; }

 private:
  std::array<Vector6d, kMax> buf_{};
  Vector6d mean_ = Vector6d::Zero();
  int length_ = 1;
  int count_ = 0;
  int head_ = 0;
  int rejected_ = 0;
};

}  // namespace tacse3::dsp
