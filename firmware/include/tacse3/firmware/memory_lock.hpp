// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: what the daemon keeps resident, and how (docs/performance.md, Memory).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace tacse3::firmware {

// A loaded object (the program or a shared library) and its loadable segments, page-aligned.
struct LoadedObject {
  struct Segment {
    std::uintptr_t begin = 0;
    std::size_t bytes = 0;
  };
  std::string path;  // as the dynamic loader names it ("" for the program itself)
  std::vector<Segment> segments;
  bool contains(std::uintptr_t a) const noexcept {
    for (const Segment& s : segments)
      if (a >= s.begin && a - s.begin < s.bytes) return true;
    return false;
  }
};

// The loaded objects holding any of `code` (addresses inside them), each once, in load order;
// every loaded object if `code` is empty. Addresses in no loaded object (heap, stack) select
// nothing.
std::vector<LoadedObject> objects_containing(std::span<const void* const> code);

// An address in each object the DSP thread runs through: the program (dsp/ and firmware/ are
// linked into it), libc, libm, libstdc++, libgcc_s and the dynamic loader.
std::span<const void* const> realtime_code() noexcept;

// A mapping of /proc/self/smaps, with what clean_file_mappings() needs of it.
struct Mapping {
  std::uintptr_t begin = 0, end = 0;
  bool writable = false;
  bool file = false;        // backed by a file (its path starts with '/')
  long rss_kib = -1;        // resident, -1 if not listed
  long anonymous_kib = -1;  // pages of it copied on write (relocated), -1 if not listed
};

// The mappings of `smaps` (the text of /proc/PID/smaps) that hold only clean file pages: backed
// by a file, not writable, no page copied on write. Dropping such pages loses nothing: a later
// access reads them back from the page cache.
std::vector<Mapping> clean_file_mappings(const std::string& smaps);
// One line of that text: a header starts a mapping in *mappings, a field fills the last one.
void scan_smaps_line(const char* line, std::vector<Mapping>* mappings);
// Only clean file pages (see clean_file_mappings()).
bool is_clean_file_mapping(const Mapping& m) noexcept;

struct MemoryLock {
  bool locked = false;             // every page is locked once touched, the real-time objects now
  std::size_t full_bytes = 0;      // bytes of the real-time objects made resident at start
  std::size_t released_bytes = 0;  // clean file mappings of other objects released at start
  std::string message;             // why not, or what could not be locked (empty if all done)
};

// Locks the process's memory for the real-time loop: the real-time objects in full and at once
// (mlock), everything else (heap, stacks, other libraries) page by page as it is first touched
// (mlockall MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT). First it releases the other loaded objects'
// clean pages (clean_file_mappings, MADV_DONTNEED): the loader touched them while relocating and
// running constructors, and only those the daemon uses again come back, locked. A kernel without
// MCL_ONFAULT (before 4.4) gets everything locked at once. Never fails hard: missing privileges
// are in `message`.
MemoryLock lock_memory();

}  // namespace tacse3::firmware
