// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: fixed-capacity lock-free single-producer single-consumer ring of small values.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace tacse3::hal {

// One thread calls push() (or fills back() and commits it), one other thread (or the same
// one) calls pop() (or reads front() until it pops it). Neither ever blocks or allocates, so
// push() is safe inside a library callback such as libcamera's requestCompleted. The in-place
// pair hands large elements over without copying them in and out. Capacity must be a power of
// two; holds up to Capacity elements.
template <typename T, std::size_t Capacity>
class SpscRing {
  static_assert(Capacity >= 2 && (Capacity & (Capacity - 1)) == 0, "capacity: power of two");

 public:
  // Producer: the slot to fill next, or null when full; commit() hands it over.
  T* back() noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) == Capacity) return nullptr;
    return &slots_[head & (Capacity - 1)];
  }
  void commit() noexcept {
    head_.store(head_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }
  // Consumer: the oldest committed slot, or null when empty; pop() frees it.
  T* front() noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return nullptr;
    return &slots_[tail & (Capacity - 1)];
  }
  void pop() noexcept {
    tail_.store(tail_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }

  // false when full (the element is not stored).
  bool push(const T& value) noexcept {
    static_assert(std::is_trivially_copyable_v<T>, "push() copies the element");
    T* slot = back();
    if (slot == nullptr) return false;
    *slot = value;
    commit();
    return true;
  }
  // false when empty.
  bool pop(T& value) noexcept {
    static_assert(std::is_trivially_copyable_v<T>, "pop() copies the element");
    const T* slot = front();
    if (slot == nullptr) return false;
    value = *slot;
    pop();
    return true;
  }
  // Approximate when the other side is running.
  std::size_t size() const noexcept {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }
  bool empty() const noexcept { return size() == 0; }
  static constexpr std::size_t capacity() noexcept { return Capacity; }

 private:
  alignas(64) std::atomic<std::size_t> head_{0};  // written by the producer
  alignas(64) std::atomic<std::size_t> tail_{0};  // written by the consumer
  alignas(64) std::array<T, Capacity> slots_{};
};

}  // namespace tacse3::hal
