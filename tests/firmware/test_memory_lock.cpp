// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: lock_memory() and the objects it makes resident in full.
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <string>

#include "tacse3/firmware/memory_lock.hpp"

namespace tacse3::firmware {
namespace {

std::string basename_of(const std::string& p) {
  return p.substr(p.find_last_of('/') + 1);
}

bool covers(const LoadedObject& o, const void* a) {
  const auto x = reinterpret_cast<std::uintptr_t>(a);
  for (const auto& s : o.segments)
    if (x >= s.begin && x - s.begin < s.bytes) return true;
  return false;
}

TEST(MemoryLock, TheRealTimeCodeIsInTheProgramAndFiveLibraries) {
  const auto code = realtime_code();
  ASSERT_EQ(code.size(), 6u);
  const auto objects = objects_containing(code);
  // dladdr, independently of dl_iterate_phdr, names the object of every address.
  std::set<std::string> names;
  for (const void* c : code) {
    Dl_info info{};
    ASSERT_NE(dladdr(c, &info), 0);
    names.insert(basename_of(info.dli_fname));
    int holders = 0;
    for (const auto& o : objects) holders += covers(o, c) ? 1 : 0;
    EXPECT_EQ(holders, 1) << info.dli_fname;
  }
  EXPECT_EQ(objects.size(), 6u);
  EXPECT_EQ(names.size(), 6u);
  for (const char* lib : {"libc.so", "libm.so", "libstdc++.so", "libgcc_s.so", "ld-linux"}) {
    int found = 0;
    for (const auto& n : names) found += n.rfind(lib, 0) == 0 ? 1 : 0;
    EXPECT_EQ(found, 1) << lib;
  }
  Dl_info self{};
  ASSERT_NE(dladdr(code[0], &self), 0);
  EXPECT_EQ(basename_of(self.dli_fname), "firmware_test_memory_lock");
}

TEST(MemoryLock, SegmentsArePageAlignedAndEachObjectIsListedOnce) {
  const auto page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
  const void* memcpy_at = realtime_code()[1];
  const void* twice[] = {memcpy_at, reinterpret_cast<const void*>(&std::strlen), memcpy_at};
  const auto objects = objects_containing(twice);
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(basename_of(objects[0].path).rfind("libc.so", 0), 0u) << objects[0].path;
  ASSERT_FALSE(objects[0].segments.empty());
  for (const auto& s : objects[0].segments) {
    EXPECT_EQ(s.begin % page, 0u);
    EXPECT_EQ(s.bytes % page, 0u);
    EXPECT_GT(s.bytes, 0u);
  }
}

TEST(MemoryLock, HeapStackAndNullSelectNothing) {
  auto heap = std::make_unique<int>(1);
  int stack = 2;
  const void* none[] = {heap.get(), &stack, nullptr};
  EXPECT_TRUE(objects_containing(none).empty());
}

// The smaps fields (kB) of the mapping that holds `a`.
struct Vma {
  long size = -1, rss = -1, pss = -1, locked = -1;  // Locked is proportional, as Pss
};
Vma vma_of(const void* a) {
  std::ifstream f("/proc/self/smaps");
  const auto x = reinterpret_cast<std::uintptr_t>(a);
  Vma v;
  bool in = false;
  std::string line;
  while (std::getline(f, line)) {
    unsigned long lo = 0, hi = 0;
    if (std::sscanf(line.c_str(), "%lx-%lx ", &lo, &hi) == 2 && line.find(':') > line.find(' ')) {
      in = x >= lo && x < hi;
      continue;
    }
    if (!in) continue;
    std::istringstream s(line);
    std::string key;
    long kb = 0;
    s >> key >> kb;
    if (key == "Size:") v.size = kb;
    if (key == "Rss:") v.rss = kb;
    if (key == "Pss:") v.pss = kb;
    if (key == "Locked:") v.locked = kb;
  }
  return v;
}

// In a child (locking is process-wide): every mapping of the real-time objects is resident in
// full (Rss = Size) and locked (smaps' Locked is proportional, like Pss: the pages are shared
// with the parent).
TEST(MemoryLock, TheRealTimeObjectsAreLockedInFull) {
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const MemoryLock lock = lock_memory();
    if (!lock.locked) _exit(77);  // no CAP_IPC_LOCK and a small RLIMIT_MEMLOCK
    if (!lock.message.empty() || lock.full_bytes == 0) _exit(1);
    for (const void* c : realtime_code()) {
      const Vma v = vma_of(c);
      if (v.size <= 0 || v.rss != v.size || std::labs(v.locked - v.pss) > 1) _exit(2);
    }
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  if (WEXITSTATUS(status) == 77) GTEST_SKIP() << "memory locking not permitted here";
  EXPECT_EQ(WEXITSTATUS(status), 0)
      << "1: lock_memory reported a problem; 2: a mapping not resident";
}

}  // namespace
}  // namespace tacse3::firmware
