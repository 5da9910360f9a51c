// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the f^z noise of a recording, from its frames before contact.
#include "tacse3/tools/contact_noise.hpp"

#include <algorithm>
#include <cmath>

namespace tacse3::tools {
namespace {

double median_of(std::vector<float>& v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

void PreContactNoise::add_frame(std::size_t index, const std::vector<double>& fz) {
  if (onset_ != kNone || index == 0) return;
  auto pool = [&](const std::vector<double>& frame) {
    ++quiet_;
    if (pooled_frames_ >= kMaxPooledFrames) return false;
    ++pooled_frames_;
    for (const double v : frame) pooled_.push_back(static_cast<float>(v));
    return true;
  };
  if (quiet_ < kSeedFrames) {
    pool(fz);
    if (quiet_ == kSeedFrames) refit();
    return;
  }
  double peak = -HUGE_VAL;
  for (const double v : fz) peak = std::max(peak, v - median_);
  if (peak > kOnsetSigma * sigma_) {
    if (pending_.empty()) pending_first_ = index;
    pending_.push_back(fz);
    if (pending_.size() >= kOnsetFrames) onset_ = pending_first_;
    return;
  }
  // A quiet frame: fewer than kOnsetFrames frames over the bar were noise after all.
  bool grew = false;
  for (const auto& f : pending_) grew = pool(f) || grew;
  pending_.clear();
  grew = pool(fz) || grew;
  if (grew) refit();
}

void PreContactNoise::refit() {
  if (pooled_.empty()) return;
  std::vector<float> v = pooled_;
  median_ = median_of(v);
  const auto med = static_cast<float>(median_);
  for (auto& x : v) x = std::abs(x - med);
  sigma_ = 1.4826 * median_of(v);
}

}  // namespace tacse3::tools
