// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: a joinable thread with an explicit stack size.
#include "tacse3/hal/thread.hpp"

#include <unistd.h>

#include <climits>
#include <exception>
#include <memory>
#include <system_error>
#include <utility>

namespace tacse3::hal {

namespace {

std::size_t round_stack(std::size_t bytes) noexcept {
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  const std::size_t min = PTHREAD_STACK_MIN;
  const std::size_t b = bytes < min ? min : bytes;
  return (b + page - 1) / page * page;
}

void* trampoline(void* arg) {
  const std::unique_ptr<std::function<void()>> fn(static_cast<std::function<void()>*>(arg));
  try {
    (*fn)();
  } catch (...) {
    std::terminate();  // as std::thread does: an exception must not leave a thread silently
  }
  return nullptr;
}

}  // namespace

Thread::Thread(std::size_t stack_bytes, std::function<void()> fn) {
  pthread_attr_t attr;
  int e = pthread_attr_init(&attr);
  if (e != 0) throw std::system_error(e, std::generic_category(), "pthread_attr_init");
  e = pthread_attr_setstacksize(&attr, round_stack(stack_bytes));
  auto owned = std::make_unique<std::function<void()>>(std::move(fn));
  if (e == 0) e = pthread_create(&handle_, &attr, trampoline, owned.get());
  pthread_attr_destroy(&attr);
  if (e != 0) throw std::system_error(e, std::generic_category(), "pthread_create");
  owned.release();  // the thread owns it now
  joinable_ = true;
}

Thread::Thread(Thread&& other) noexcept
    : handle_(other.handle_), joinable_(std::exchange(other.joinable_, false)) {}

Thread& Thread::operator=(Thread&& other) noexcept {
  if (joinable_) std::terminate();
  handle_ = other.handle_;
  joinable_ = std::exchange(other.joinable_, false);
  return *this;
}

Thread::~Thread() {
  if (joinable_) std::terminate();
}

void Thread::join() {
  if (!joinable_) throw std::system_error(EINVAL, std::generic_category(), "join");
  const int e = pthread_join(handle_, nullptr);
  if (e != 0) throw std::system_error(e, std::generic_category(), "pthread_join");
  joinable_ = false;
}

std::size_t stack_size_of(pthread_t thread) noexcept {
  pthread_attr_t attr;
  if (pthread_getattr_np(thread, &attr) != 0) return 0;
  std::size_t size = 0;
  if (pthread_attr_getstacksize(&attr, &size) != 0) size = 0;
  pthread_attr_destroy(&attr);
  return size;
}

}  // namespace tacse3::hal
