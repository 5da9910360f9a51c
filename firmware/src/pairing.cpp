// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: frame pairing rule.
#include "tacse3/firmware/pairing.hpp"

namespace tacse3::firmware {

PairingConfig pairing_config(int tolerance_us, int stale_ms) noexcept {
  PairingConfig c;
  c.tolerance_ns = static_cast<std::int64_t>(tolerance_us) * 1000;
  c.max_wait_ns = static_cast<std::int64_t>(stale_ms) * 1'000'000;
  return c;
}

const char* to_string(PairAction a) noexcept {
  switch (a) {
    case PairAction::kWait:
      return "wait";
    case PairAction::kPair:
      return "pair";
    case PairAction::kLeftAlone:
      return "left-alone";
    case PairAction::kRightAlone:
      return "right-alone";
    case PairAction::kDropLeft:
      return "drop-left";
    case PairAction::kDropRight:
      return "drop-right";
  }
  return "?";
}

PairAction decide_pairing(const PendingFrame& left, const PendingFrame& right, bool left_alive,
                          bool right_alive, std::int64_t last_t_ns, std::int64_t now_ns,
                          const PairingConfig& config) noexcept {
  if (left.present && left.t_ns <= last_t_ns) return PairAction::kDropLeft;
  if (right.present && right.t_ns <= last_t_ns) return PairAction::kDropRight;
  if (left.present && right.present) {
    const std::int64_t d = left.t_ns - right.t_ns;
    if (d <= config.tolerance_ns && -d <= config.tolerance_ns) return PairAction::kPair;
    return d < 0 ? PairAction::kLeftAlone : PairAction::kRightAlone;
  }
  if (left.present) {
    if (!right_alive || now_ns - left.arrival_ns >= config.max_wait_ns) {
      return PairAction::kLeftAlone;
    }
    return PairAction::kWait;
  }
  if (right.present) {
    if (!left_alive || now_ns - right.arrival_ns >= config.max_wait_ns) {
      return PairAction::kRightAlone;
    }
    return PairAction::kWait;
  }
  return PairAction::kWait;
}

}  // namespace tacse3::firmware
