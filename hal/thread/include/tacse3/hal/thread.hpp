// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: a joinable thread with an explicit stack size.
#pragma once

#include <pthread.h>

#include <cstddef>
#include <functional>

namespace tacse3::hal {

// std::thread with the stack size as a required argument (std::thread cannot set one, and the
// default, RLIMIT_STACK, is 8 MiB: under the daemon's memory locking a touched page stays
// resident, and the size bounds how many can be).
// Sizes are rounded up to whole pages and to at least PTHREAD_STACK_MIN. Like std::thread, a
// Thread must be joined before it is destroyed (else std::terminate).
class Thread {
 public:
  Thread() noexcept = default;
  // Starts fn on a new thread with a stack of stack_bytes. Throws std::system_error when the
  // thread cannot be created.
  Thread(std::size_t stack_bytes, std::function<void()> fn);
  Thread(Thread&& other) noexcept;
  Thread& operator=(Thread&& other) noexcept;
  Thread(const Thread&) = delete;
  Thread& operator=(const Thread&) = delete;
  ~Thread();

  bool joinable() const noexcept { return joinable_; }
  void join();
  pthread_t native_handle() const noexcept { return handle_; }

 private:
  pthread_t handle_{};
  bool joinable_ = false;
};

// The stack size a running thread was created with (pthread_getattr_np), 0 if unknown.
std::size_t stack_size_of(pthread_t thread) noexcept;

}  // namespace tacse3::hal
