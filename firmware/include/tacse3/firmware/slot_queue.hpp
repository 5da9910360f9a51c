// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: a single-producer single-consumer FIFO of large elements, filled and read in
// place, that touches only as many slots as are ever in use at once.
#pragma once

#include <array>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <new>
#include <type_traits>

#include "tacse3/hal/camera/spsc_ring.hpp"

namespace tacse3::firmware {

// The same in-place pair as hal::SpscRing (back()/commit() on the producer, front()/pop() on the
// consumer) with the same capacity, but the producer always fills the lowest free slot, and a
// slot's element is constructed there the first time it is handed out. A ring walks through
// every slot in turn, so each becomes resident and (under mlockall) locked although one or two
// are in use at a time; here a 31 KB staged frame per slot costs memory only for the slots the
// cameras' buffering really fills (2026-11-29: 0.36 MiB of the daemon's RSS).
//
// The free slots are a bitmask: only the producer clears bits (commit), only the consumer sets
// them (pop, with release, after its last read of the slot). The order of the filled slots is
// an SpscRing of their indices, whose commit publishes the slot's contents.
template <typename T, std::size_t Capacity>
class SpscSlotQueue {
  static_assert(Capacity >= 2 && Capacity <= 32, "capacity: 2..32 (one bit per slot)");
  static_assert(std::is_default_constructible_v<T>, "slots are built in place by back()");

 public:
  // User-provided, so that default-initialising the queue leaves storage_ untouched. An owner
  // that is value-initialised (make_unique<std::array<...>>()) is still zeroed in full: the
  // daemon uses make_unique_for_overwrite.
  SpscSlotQueue() noexcept {}  // NOLINT(modernize-use-equals-default)
  SpscSlotQueue(const SpscSlotQueue&) = delete;
  SpscSlotQueue& operator=(const SpscSlotQueue&) = delete;
  ~SpscSlotQueue() {
    for (std::size_t i = 0; i < Capacity; ++i)
      if ((built_ >> i) & 1U) slot(i)->~T();
  }

  // Producer, before the consumer runs: builds the first n slots now (n is clamped to the
  // capacity), so that a producer which never has more than n in use takes no page fault later.
  void reserve(std::size_t n) noexcept {
    for (std::size_t i = 0; i < n && i < Capacity; ++i) build(i);
  }
  // Producer: the lowest free slot, or null when every slot is filled; commit() hands it over.
  T* back() noexcept {
    const std::uint32_t free = free_.load(std::memory_order_acquire);
    if (free == 0) return nullptr;
    next_ = static_cast<std::uint8_t>(std::countr_zero(free));
    build(next_);
    return slot(next_);
  }
  // Producer: hands over the slot the last back() returned.
  void commit() noexcept {
    free_.fetch_and(~(std::uint32_t{1} << next_), std::memory_order_relaxed);
    order_.push(next_);  // never full: it holds at most Capacity indices
  }
  // Consumer: the oldest committed slot, or null when empty; pop() frees it.
  T* front() noexcept {
    const std::uint8_t* i = order_.front();
    return i == nullptr ? nullptr : slot(*i);
  }
  void pop() noexcept {
    const std::uint8_t* i = order_.front();
    if (i == nullptr) return;
    const std::uint32_t bit = std::uint32_t{1} << *i;
    order_.pop();
    free_.fetch_or(bit, std::memory_order_release);
  }

  // Approximate when the other side is running.
  std::size_t size() const noexcept { return order_.size(); }
  bool empty() const noexcept { return order_.empty(); }
  static constexpr std::size_t capacity() noexcept { return Capacity; }
  // Producer: how many slots have ever been handed out (their pages are resident).
  std::size_t slots_built() const noexcept {
    return static_cast<std::size_t>(std::popcount(built_));
  }

 private:
  void* raw(std::size_t i) noexcept { return storage_.data() + i * sizeof(T); }
  // Only for a built slot: launder needs the object to exist.
  T* slot(std::size_t i) noexcept { return std::launder(static_cast<T*>(raw(i))); }
  void build(std::size_t i) noexcept {
    if ((built_ >> i) & 1U) return;
    ::new (raw(i)) T();
    built_ |= std::uint32_t{1} << i;
  }

  static constexpr std::uint32_t kAllFree =
      Capacity == 32 ? ~std::uint32_t{0} : (std::uint32_t{1} << Capacity) - 1;
  alignas(64) std::atomic<std::uint32_t> free_{kAllFree};
  std::uint32_t built_ = 0;  // producer only
  std::uint8_t next_ = 0;    // producer only: the slot the last back() returned
  hal::SpscRing<std::uint8_t, std::bit_ceil(Capacity)> order_;
  // Left uninitialised: a slot's pages are first written when it is first handed out.
  alignas(alignof(T) > 64 ? alignof(T) : 64) std::array<std::byte, sizeof(T) * Capacity> storage_;
};

}  // namespace tacse3::firmware
