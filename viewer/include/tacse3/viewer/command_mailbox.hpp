// SPDX-License-Identifier: Apache-2.0
// tacse3 viewer: the viewer's controls -> DSP thread: one validated command at a time, and its
// ACK/NACK back to the HTTP request that sent it (docs/viewer.md, POST /api/command).
#pragma once

#include <atomic>

#include "tacse3/protocol/commands.hpp"

namespace tacse3::viewer {

// A single slot, lock-free. The web side holds at most one command in flight (the server
// serialises its requests), so the DSP thread never waits and a CAN ACK never goes to the wrong
// requester: the web command's answer comes back here, not on the bus.
class CommandMailbox {
 public:
  // Web side. false: a command is still waiting for the DSP thread.
  bool submit(const protocol::CommandResult& r) noexcept {
    int s = state_.load(std::memory_order_acquire);
    if (s == kAnswered) s = kIdle;  // the answer to a request that gave up waiting
    if (s != kIdle) return false;
    request_ = r;
    state_.store(kPending, std::memory_order_release);
    return true;
  }
  // Web side: true once the DSP thread answered the submitted command.
  bool poll(protocol::Ack* ack) noexcept {
    if (state_.load(std::memory_order_acquire) != kAnswered) return false;
    *ack = ack_;
    state_.store(kIdle, std::memory_order_release);
    return true;
  }
  // DSP side: the waiting command, if any; answer() it before the next take().
  bool take(protocol::CommandResult* r) const noexcept {
    if (state_.load(std::memory_order_acquire) != kPending) return false;
    *r = request_;
    return true;
  }
  void answer(const protocol::Ack& a) noexcept {
    ack_ = a;
    state_.store(kAnswered, std::memory_order_release);
  }

 private:
  enum : int { kIdle = 0, kPending = 1, kAnswered = 2 };
  std::atomic<int> state_{kIdle};
  protocol::CommandResult request_{};
  protocol::Ack ack_{};
};

}  // namespace tacse3::viewer
