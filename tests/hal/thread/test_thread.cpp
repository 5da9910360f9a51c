// SPDX-License-Identifier: Apache-2.0
// hal::Thread: the running thread has the stack size it was created with.
#include <gtest/gtest.h>
#include <pthread.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <climits>
#include <cstddef>

#include "tacse3/hal/thread.hpp"

namespace tacse3::hal {
namespace {

std::size_t stack_seen_by(std::size_t requested) {
  std::size_t seen = 0;
  Thread t(requested, [&seen] { seen = stack_size_of(pthread_self()); });
  t.join();
  return seen;
}

// What Thread gives for a request: whole pages, and at least PTHREAD_STACK_MIN (16 KiB on x86-64,
// 128 KiB on aarch64, where glibc allows for 64 KiB pages).
std::size_t expected_stack(std::size_t requested) {
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  const std::size_t rounded = (requested + page - 1) / page * page;
  return std::max(rounded, static_cast<std::size_t>(PTHREAD_STACK_MIN));
}

TEST(Thread, RunningThreadHasTheRequestedStack) {
  for (std::size_t kib : {64u, 512u, 2048u}) {
    EXPECT_EQ(stack_seen_by(kib * 1024), expected_stack(kib * 1024)) << kib << " KiB";
  }
  EXPECT_EQ(expected_stack(2048 * 1024), 2048u * 1024u);  // above every minimum: exact
}

TEST(Thread, SizeIsRoundedUpToPagesAndTheMinimum) {
  // glibc reuses the stack of a finished thread when it is large enough and at most four times
  // the request: the earlier tests' stacks are smaller, the same size, or larger than that.
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  EXPECT_EQ(expected_stack(256 * 1024 + 1), 256 * 1024 + page);
  EXPECT_EQ(stack_seen_by(64 * 1024 + 1), expected_stack(64 * 1024 + 1));
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
}  // namespace tacse3::hal
