// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: encoder, decoder, reassembler, commands and candump parsing never allocate.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "tacse3/protocol/protocol.hpp"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<int> g_allocations{0};
}  // namespace

void* operator new(std::size_t n) {
  if (g_counting.load()) g_allocations.fetch_add(1);
  void* p = std::malloc(n == 0 ? 1 : n);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
// GCC pairs these with the replaced operator new above but still warns that free() does not match
// "new"; the pairing is correct by construction.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
#pragma GCC diagnostic pop

namespace tp = tacse3::protocol;

TEST(NoAllocation, WholeControllerAndFirmwarePath) {
  tp::CycleReassembler reasm;
  tp::CommandReceiver rx;
  tp::Cycle c;
  c.timestamp_us = 42;
  c.angular = {0.1, 0.2, 0.3};
  g_counting = true;
  for (int k = 0; k < 100; ++k) {
    c.timestamp_us += 8333;
    for (auto mode : {tp::FrameMode::kClassic, tp::FrameMode::kFd}) {
      tp::TxConfig tx;
      tx.frame_mode = mode;
      tp::CycleFrames f;
      ASSERT_EQ(tp::encode_cycle(c, static_cast<std::uint8_t>(k), tx, f), tp::Status::kOk);
      for (std::size_t i = 0; i < f.count; ++i) {
        tp::Cycle out;
        (void)reasm.feed(f.frames[i], out);
        tp::LogRecord rec;
        rec.iface = {'c', 'a', 'n', '0'};
        rec.frame = f.frames[i];
        char line[tp::kCandumpLineMax];
        ASSERT_GT(tp::format_candump_line(rec, line, sizeof line), 0u);
        ASSERT_EQ(tp::parse_candump_line(line, rec), tp::Status::kOk);
      }
    }
    std::array<tp::CanFrame, 4> st;
    ASSERT_EQ(tp::encode_status_group(tp::StatusGroup{}, 0, tp::TxConfig{}, st), tp::Status::kOk);
    tp::Command cmd;
    cmd.code = tp::CommandCode::kSetFingerSeparation;
    cmd.finger_separation_m = 0.05;
    tp::CanFrame cf;
    ASSERT_EQ(tp::encode(cmd, tp::TxConfig{}, cf), tp::Status::kOk);
    const tp::CommandResult r = rx.receive(cf);
    tp::CanFrame ack;
    ASSERT_EQ(tp::encode(tp::make_ack(r), tp::TxConfig{}, ack), tp::Status::kOk);
    tp::Decoded d;
    ASSERT_EQ(tp::decode(ack, tp::IdLayout{}, d), tp::Status::kOk);
  }
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_EQ(reasm.stats().samples, 100u);  // FD cycles repeat the classic ones' counters
}
