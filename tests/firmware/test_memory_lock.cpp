// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: lock_memory() and the objects it makes resident in full.
#include <dlfcn.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
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
  return o.contains(reinterpret_cast<std::uintptr_t>(a));
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
  const void* getpid_at = realtime_code()[1];
  const void* twice[] = {getpid_at, reinterpret_cast<const void*>(&::getppid), getpid_at};
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

TEST(MemoryLock, OnlyCleanFileMappingsAreReleased) {
  const std::string smaps =
      "5555a000-5555b000 r--p 00000000 08:01 11 /usr/bin/prog\n"
      "Size:                  4 kB\nRss:                   4 kB\nAnonymous:             0 kB\n"
      "7f0000000000-7f0000010000 r-xp 00001000 08:01 12   /usr/lib/libx.so.1\n"
      "Rss:                  64 kB\nAnonymous:             0 kB\n"
      "7f0000010000-7f0000012000 r--p 00010000 08:01 12   /usr/lib/libx.so.1\n"
      "Rss:                   8 kB\nAnonymous:             8 kB\n"  // relocated: copied on write
      "7f0000012000-7f0000013000 rw-p 00012000 08:01 12   /usr/lib/libx.so.1\n"
      "Rss:                   4 kB\nAnonymous:             0 kB\n"  // writable
      "7f0000020000-7f0000030000 rw-p 00000000 00:00 0\n"
      "Rss:                  64 kB\nAnonymous:            64 kB\n"  // heap-like
      "7f0000030000-7f0000031000 r--s 00000000 00:05 77   /dev/shm/x (deleted)\n"
      "Anonymous:             0 kB\n"
      "7f0000040000-7f0000041000 r--p 00000000 00:00 0    [vvar]\n"
      "Anonymous:             0 kB\n"
      "7f0000050000-7f0000051000 r--p 00000000 08:01 13   /usr/lib/liby.so\n"  // no fields
      "VmFlags: rd mr mw me\n";
  const auto clean = clean_file_mappings(smaps);
  ASSERT_EQ(clean.size(), 3u);
  EXPECT_EQ(clean[0].begin, 0x5555a000u);
  EXPECT_EQ(clean[0].end, 0x5555b000u);
  EXPECT_EQ(clean[1].begin, 0x7f0000000000u);
  EXPECT_EQ(clean[1].rss_kib, 64);
  EXPECT_EQ(clean[2].begin, 0x7f0000030000u);  // a shared read-only file mapping
  EXPECT_EQ(clean[2].rss_kib, -1);
  EXPECT_TRUE(clean_file_mappings("").empty());
  EXPECT_TRUE(clean_file_mappings("garbage\nRss: 4 kB\n").empty());
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
  if (!TACSE3_TEST_KERNEL_MEMORY) GTEST_SKIP() << "qemu-user or ASan: mlock is not the kernel's";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // A library outside the six, loaded and relocated (its pages touched) before the lock.
    if (dlopen("libz.so.1", RTLD_NOW | RTLD_LOCAL) == nullptr) _exit(4);
    // A read-only shared mapping of a file that is no loaded object (as a camera's buffers are
    // mapped): it must stay as it is.
    char path[] = "/tmp/tacse3-memlock-XXXXXX";
    const int fd = mkstemp(path);
    if (fd < 0 || ftruncate(fd, 16 * 4096) != 0) _exit(5);
    unlink(path);
    auto* shared =
        static_cast<volatile const char*>(mmap(nullptr, 16 * 4096, PROT_READ, MAP_SHARED, fd, 0));
    if (shared == MAP_FAILED) _exit(5);
    for (int k = 0; k < 16; ++k) (void)shared[k * 4096];
    const MemoryLock lock = lock_memory();
    if (!lock.locked) _exit(77);  // no CAP_IPC_LOCK and a small RLIMIT_MEMLOCK
    if (!lock.message.empty() || lock.full_bytes == 0) _exit(1);
    for (const void* c : realtime_code()) {
      const Vma v = vma_of(c);
      if (v.size <= 0 || v.rss != v.size || std::labs(v.locked - v.pss) > 1) {
        std::fprintf(stderr, "%p: Size %ld Rss %ld Pss %ld Locked %ld kB\n", c, v.size, v.rss,
                     v.pss, v.locked);
        _exit(2);
      }
    }
    // The other objects' clean pages were released; few have been touched since.
    std::ifstream f("/proc/self/smaps");
    std::stringstream text;
    text << f.rdbuf();
    const auto rt = objects_containing(realtime_code());
    const auto all = objects_containing({});
    long rss = 0, size = 0;
    for (const Mapping& m : clean_file_mappings(text.str())) {
      const auto* at = reinterpret_cast<const void*>(m.begin);
      bool in_rt = false, loaded = false;
      for (const auto& o : rt) in_rt = in_rt || covers(o, at);
      for (const auto& o : all) loaded = loaded || covers(o, at);
      if (in_rt || !loaded) continue;
      rss += m.rss_kib;
      size += static_cast<long>((m.end - m.begin) / 1024);
    }
    if (lock.released_bytes == 0 || size == 0 || rss * 4 > size) _exit(3);
    const Vma kept = vma_of(const_cast<const char*>(shared));
    if (kept.size != 64 || kept.rss != 64) _exit(6);
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  if (WEXITSTATUS(status) == 77) GTEST_SKIP() << "memory locking not permitted here";
  EXPECT_EQ(WEXITSTATUS(status), 0)
      << "1: lock_memory reported a problem; 2: a real-time mapping not resident; 3: other "
         "objects' pages not released; 4: no libz.so.1; 5: no temporary file; 6: a mapping of "
         "no loaded object was released";
}

}  // namespace
}  // namespace tacse3::firmware
