// SPDX-License-Identifier: Apache-2.0
// firmware::Thread: the running thread has the stack size it was created with.
#include <gtest/gtest.h>
#include <pthread.h>
#include <unistd.h>

#include <atomic>
#include <climits>
#include <cstddef>

#include "tacse3/firmware/thread.hpp"

namespace tacse3::firmware {
namespace {

std::size_t stack_seen_by(std::size_t requested) {
  std::size_t seen = 0;
  Thread t(requested, [&seen] { seen = stack_size_of(pthread_self()); });
  t.join();
  return seen;
}

TEST(Thread, RunningThreadHasTheRequestedStack) {
  EXPECT_EQ(stack_seen_by(64 * 1024), 64u * 1024u);
  EXPECT_EQ(stack_seen_by(512 * 1024), 512u * 1024u);
  EXPECT_EQ(stack_seen_by(2 * 1024 * 1024), 2u * 1024u * 1024u);
}

TEST(Thread, SizeIsRoundedUpToPagesAndTheMinimum) {
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  EXPECT_EQ(stack_seen_by(64 * 1024 + 1), 64 * 1024 + page);
  // Below the minimum: raised to it (glibc may raise it further, to fit the static TLS).
  EXPECT_GE(stack_seen_by(1), static_cast<std::size_t>(PTHREAD_STACK_MIN));
}

TEST(Thread, TheWholeStackIsUsable) {
  // Touch all but 16 KiB of a 256 KiB stack (the rest holds the thread's own frames and TLS).
  std::atomic<int> sum{0};
  Thread t(256 * 1024, [&sum] {
    volatile unsigned char buf[240 * 1024];
    for (std::size_t i = 0; i < sizeof(buf); i += 1024) buf[i] = 1;
    int s = 0;
    for (std::size_t i = 0; i < sizeof(buf); i += 1024) s += buf[i];
    sum = s;
  });
  t.join();
  EXPECT_EQ(sum.load(), 240);
}

TEST(Thread, MovesAndJoinsLikeStdThread) {
  Thread empty;
  EXPECT_FALSE(empty.joinable());
  std::atomic<bool> ran{false};
  Thread a(64 * 1024, [&ran] { ran = true; });
  EXPECT_TRUE(a.joinable());
  Thread b(std::move(a));
  EXPECT_FALSE(a.joinable());  // NOLINT(bugprone-use-after-move): the moved-from state is the point
  empty = std::move(b);
  empty.join();
  EXPECT_FALSE(empty.joinable());
  EXPECT_TRUE(ran.load());
}

}  // namespace
}  // namespace tacse3::firmware
