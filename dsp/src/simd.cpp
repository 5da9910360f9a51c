// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: the SIMD target list and selection (simd.hpp) on Highway's dispatch.
#include "tacse3/dsp/simd.hpp"

#include <hwy/highway.h>
#include <hwy/targets.h>

#include <cstdint>

namespace tacse3::dsp {
namespace {

// Bit of the i-th compiled and supported target, best (lowest bit) first; 0 if none. The set is
// read once, before simd_select_target can narrow what hwy::SupportedTargets() reports.
std::int64_t target_bit(int i) noexcept {
#if TACSE3_SIMD_DYNAMIC
  static const std::int64_t all = hwy::SupportedTargets() & HWY_TARGETS;
#else
  static const std::int64_t all = HWY_STATIC_TARGET;
#endif
  std::int64_t left = all;
  for (; left != 0; left &= left - 1) {
    if (i-- == 0) return left & -left;
  }
  return 0;
}

}  // namespace

int simd_target_count() noexcept {
  int n = 0;
  while (target_bit(n) != 0) ++n;
  return n;
}

const char* simd_target_name(int i) noexcept {
  const std::int64_t bit = i >= 0 ? target_bit(i) : 0;
  return bit != 0 ? hwy::TargetName(bit) : "";
}

void simd_select_target(int i) noexcept {
#if TACSE3_SIMD_DYNAMIC
  const std::int64_t bit = i >= 0 ? target_bit(i) : 0;
  hwy::SetSupportedTargetsForTest(bit);  // 0 ends the restriction
  hwy::GetChosenTarget().Update(hwy::SupportedTargets());
#else
  (void)i;  // one target only
#endif
}

}  // namespace tacse3::dsp
