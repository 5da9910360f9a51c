// SPDX-License-Identifier: Apache-2.0
// viewer tests: the viewer's snapshot slot (triple buffer): the latest value wins, nothing is
// read twice, and a reader racing a writer never sees a torn value.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <thread>

#include "tacse3/viewer/snapshot_slot.hpp"
#include "tacse3/viewer/view_snapshot.hpp"

using namespace tacse3::viewer;

namespace {

// Every word derives from seq: a value mixed from two publications shows at once.
struct Block {
  std::uint64_t seq = 0;
  std::array<std::uint64_t, 4096> words{};
};

void fill(Block& b, std::uint64_t seq) {
  b.seq = seq;
  for (std::size_t i = 0; i < b.words.size(); ++i) b.words[i] = seq * 1'000'003 + i;
}

bool whole(const Block& b) {
  for (std::size_t i = 0; i < b.words.size(); ++i) {
    if (b.words[i] != b.seq * 1'000'003 + i) return false;
  }
  return true;
}

}  // namespace

TEST(SnapshotSlot, LatestValueWinsAndIsTakenOnce) {
  auto slot = std::make_unique<SnapshotSlot<Block>>();
  EXPECT_FALSE(slot->take()) << "nothing published yet";
  fill(slot->back(), 1);
  slot->publish();
  fill(slot->back(), 2);
  slot->publish();
  ASSERT_TRUE(slot->take());
  EXPECT_EQ(slot->front().seq, 2u);
  EXPECT_TRUE(whole(slot->front()));
  EXPECT_FALSE(slot->take()) << "the same value twice";
  EXPECT_EQ(slot->front().seq, 2u) << "front stays until the next take";
  fill(slot->back(), 3);
  slot->publish();
  ASSERT_TRUE(slot->take());
  EXPECT_EQ(slot->front().seq, 3u);
  EXPECT_EQ(slot->published(), 3u);
}

TEST(SnapshotSlot, ConcurrentReaderNeverSeesATornValue) {
  auto slot = std::make_unique<SnapshotSlot<Block>>();
  // The writer keeps publishing past kWrites until the reader has taken kMinTaken values, so a
  // loaded machine that starves the reader makes the test longer, not a failure.
  constexpr std::uint64_t kWrites = 200'000;
  constexpr std::uint64_t kMinTaken = 100;
  std::atomic<bool> done{false};
  std::atomic<std::uint64_t> taken{0};
  std::uint64_t torn = 0;
  std::uint64_t backwards = 0;
  std::thread reader([&] {
    std::uint64_t last = 0;
    for (;;) {
      const bool finished = done.load(std::memory_order_acquire);
      if (!slot->take()) {
        if (finished) break;
        continue;
      }
      const Block& b = slot->front();
      taken.fetch_add(1, std::memory_order_relaxed);
      if (!whole(b)) ++torn;
      if (b.seq <= last) ++backwards;
      last = b.seq;
    }
  });
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  std::uint64_t s = 0;
  while (s < kWrites || (taken.load(std::memory_order_relaxed) < kMinTaken &&
                         std::chrono::steady_clock::now() < give_up)) {
    fill(slot->back(), ++s);
    slot->publish();
    if (s >= kWrites) std::this_thread::yield();
  }
  done.store(true, std::memory_order_release);
  reader.join();
  EXPECT_EQ(slot->front().seq, s);
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u) << "a value older than one already read";
  EXPECT_GE(taken.load(), kMinTaken) << "the reader hardly ever ran in 60 s";
}

TEST(SnapshotSlot, TheViewSnapshotIsBoundedPlainData) {
  static_assert(std::is_trivially_copyable_v<ViewSnapshot>);
  // Two working images and four grid fields per pad, plus the scalars: the copy the DSP thread
  // makes per publication.
  EXPECT_LT(sizeof(ViewSnapshot), 2 * (160 * 120 + 1200 * 13) + 512);
}
