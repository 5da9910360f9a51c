// SPDX-License-Identifier: Apache-2.0
// tacse3 viewer: a wait-free single-writer, single-reader slot for the latest value of a
// trivially copyable struct (a triple buffer). The DSP thread writes; the viewer thread reads.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <type_traits>

namespace tacse3::viewer {

// Three buffers: the writer owns one (back), the reader owns one (front), the third (middle)
// holds the latest published value. publish() and take() each swap their own buffer with the
// middle one in a single atomic exchange, so neither side ever waits, copies under a lock or
// sees a buffer the other side is writing: a torn value cannot be read. The writer fills back()
// completely before each publish() (the buffer it gets back holds an older value).
template <typename T>
class SnapshotSlot {
  static_assert(std::is_trivially_copyable_v<T>, "the slot holds plain data only");

 public:
  // Writer: the buffer to fill, then publish() it.
  T& back() noexcept { return buffers_[back_].value; }
  void publish() noexcept {
    const std::uint8_t old = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
    back_ = old & kIndex;
    published_.fetch_add(1, std::memory_order_relaxed);
  }

  // Reader: true when a value newer than front() was published; front() then holds it.
  bool take() noexcept {
    if ((middle_.load(std::memory_order_relaxed) & kFresh) == 0) return false;
    const std::uint8_t old = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = old & kIndex;
    return true;
  }
  const T& front() const noexcept { return buffers_[front_].value; }

  // Either side: how many values were published so far.
  std::uint64_t published() const noexcept { return published_.load(std::memory_order_relaxed); }

 private:
  static constexpr std::uint8_t kIndex = 0x3;
  static constexpr std::uint8_t kFresh = 0x4;
  struct alignas(64) Buffer {
    T value{};
  };
  std::array<Buffer, 3> buffers_{};
  alignas(64) std::atomic<std::uint8_t> middle_{1};
  std::atomic<std::uint64_t> published_{0};
  alignas(64) std::uint8_t back_ = 0;   // writer only
  alignas(64) std::uint8_t front_ = 2;  // reader only
};

}  // namespace tacse3::viewer
