// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: locking the daemon's memory (docs/performance.md, Memory).
#include "tacse3/firmware/memory_lock.hpp"

#include <link.h>
#include <malloc.h>
#include <sys/auxv.h>
#include <sys/mman.h>
#include <unistd.h>
#include <unwind.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iterator>
#include <string>

namespace tacse3::firmware {

namespace {

template <typename F>
const void* address_of(F* f) noexcept {
  return reinterpret_cast<const void*>(f);
}

struct Search {
  std::span<const void* const> code;  // empty: every object
  std::vector<LoadedObject>* out;
};

bool holds(const dl_phdr_info& info, std::uintptr_t a) noexcept {
  for (int i = 0; i < info.dlpi_phnum; ++i) {
    const ElfW(Phdr)& p = info.dlpi_phdr[i];
    if (p.p_type != PT_LOAD) continue;
    const std::uintptr_t begin = info.dlpi_addr + p.p_vaddr;
    if (a >= begin && a - begin < p.p_memsz) return true;
  }
  return false;
}

int visit(dl_phdr_info* info, std::size_t, void* data) {
  auto* s = static_cast<Search*>(data);
  const bool wanted =
      s->code.empty() || std::any_of(s->code.begin(), s->code.end(), [&](const void* c) {
        return c != nullptr && holds(*info, reinterpret_cast<std::uintptr_t>(c));
      });
  if (!wanted) return 0;
  const auto page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
  LoadedObject o;
  o.path = info->dlpi_name != nullptr ? info->dlpi_name : "";
  for (int i = 0; i < info->dlpi_phnum; ++i) {
    const ElfW(Phdr)& p = info->dlpi_phdr[i];
    if (p.p_type != PT_LOAD || p.p_memsz == 0) continue;
    const std::uintptr_t begin = (info->dlpi_addr + p.p_vaddr) & ~(page - 1);
    const std::uintptr_t end = (info->dlpi_addr + p.p_vaddr + p.p_memsz + page - 1) & ~(page - 1);
    o.segments.push_back({begin, end - begin});
  }
  s->out->push_back(std::move(o));
  return 0;
}

bool inside(const std::vector<LoadedObject>& objects, std::uintptr_t a) noexcept {
  return std::any_of(objects.begin(), objects.end(),
                     [a](const LoadedObject& o) { return o.contains(a); });
}

// Releases the clean pages of the loaded objects outside `keep`; returns the bytes of the
// mappings released. Only an object's own mappings: a device's (a camera's buffers, mapped
// read-only) has no page to read back, and touching it after a release raises SIGBUS.
std::size_t release_clean_pages(const std::vector<LoadedObject>& keep) {
  const std::vector<LoadedObject> all = objects_containing({});
  // Line by line through a stack buffer: the file is ~250 KiB, and a heap copy of it on this
  // thread would leave its pages resident, then locked.
  std::vector<Mapping> mappings;
  if (std::FILE* f = std::fopen("/proc/self/smaps", "re")) {
    char line[1024];
    bool line_start = true;
    while (std::fgets(line, sizeof line, f) != nullptr) {
      // A line longer than the buffer (a long path) is read in pieces: only its first counts.
      if (line_start) scan_smaps_line(line, &mappings);
      line_start = std::strchr(line, '\n') != nullptr;
    }
    std::fclose(f);
  }
  std::size_t released = 0;
  for (const Mapping& m : mappings) {
    if (!is_clean_file_mapping(m) || !inside(all, m.begin) || inside(keep, m.begin)) continue;
    if (madvise(reinterpret_cast<void*>(m.begin), m.end - m.begin, MADV_DONTNEED) == 0)
      released += m.end - m.begin;
  }
  return released;
}

}  // namespace

void scan_smaps_line(const char* line, std::vector<Mapping>* mappings) {
  unsigned long lo = 0, hi = 0;
  char perms[5] = {};
  int used = 0;
  // A mapping's header: "lo-hi perms offset dev inode [path]"; its fields: "Key: value kB".
  if (std::sscanf(line, "%lx-%lx %4s %*s %*s %*s%n", &lo, &hi, perms, &used) == 3 && used > 0) {
    Mapping m;
    m.begin = lo;
    m.end = hi;
    m.writable = perms[1] == 'w';
    const char* path = line + used;
    while (*path == ' ') ++path;
    m.file = *path == '/';
    mappings->push_back(m);
    return;
  }
  long kib = 0;
  if (mappings->empty()) return;
  if (std::sscanf(line, "Rss: %ld", &kib) == 1) mappings->back().rss_kib = kib;
  if (std::sscanf(line, "Anonymous: %ld", &kib) == 1) mappings->back().anonymous_kib = kib;
}

bool is_clean_file_mapping(const Mapping& m) noexcept {
  return m.file && !m.writable && m.anonymous_kib == 0;
}

std::vector<Mapping> clean_file_mappings(const std::string& smaps) {
  std::vector<Mapping> all;
  std::string line;
  for (std::size_t at = 0; at < smaps.size();) {
    const std::size_t end = std::min(smaps.find('\n', at), smaps.size());
    line.assign(smaps, at, end - at);
    at = end + 1;
    scan_smaps_line(line.c_str(), &all);
  }
  std::vector<Mapping> out;
  std::copy_if(all.begin(), all.end(), std::back_inserter(out), is_clean_file_mapping);
  return out;
}

std::vector<LoadedObject> objects_containing(std::span<const void* const> code) {
  std::vector<LoadedObject> out;
  Search s{code, &out};
  dl_iterate_phdr(visit, &s);
  return out;
}

std::span<const void* const> realtime_code() noexcept {
  // The loader's base is where its first segment is mapped (getauxval AT_BASE; 0 if the program
  // is static). The libc and libm functions are taken through their pointers, so the addresses
  // are the libraries' own, not the program's PLT stubs (the program is position-independent);
  // getpid, because no sanitizer intercepts it.
  static const void* const code[] = {
      address_of(&lock_memory),
      address_of(&::getpid),
      address_of(static_cast<double (*)(double)>(&std::cos)),
      address_of(&std::terminate),
      address_of(&_Unwind_Resume),
      reinterpret_cast<const void*>(getauxval(AT_BASE)),
  };
  return code;
}

MemoryLock lock_memory() {
  MemoryLock r;
  const std::vector<LoadedObject> realtime = objects_containing(realtime_code());
  // Before mlockall: pages of a locked mapping cannot be released. Then the heap's free pages
  // (start-up garbage, the smaps text above) go back too, or mlockall would keep them resident.
  r.released_bytes = release_clean_pages(realtime);
  malloc_trim(0);
  if (mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT) != 0) {
    const int e = errno;
    // EINVAL: a kernel without MCL_ONFAULT. Then everything, now.
    if (e == EINVAL && mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      r.locked = true;
      return r;
    }
    r.message =
        std::string("mlockall: ") + std::strerror(e) + " (needs CAP_IPC_LOCK or RLIMIT_MEMLOCK)";
    return r;
  }
  r.locked = true;
  for (const LoadedObject& o : realtime) {
    for (const LoadedObject::Segment& s : o.segments) {
      if (mlock(reinterpret_cast<const void*>(s.begin), s.bytes) == 0) {
        r.full_bytes += s.bytes;
      } else if (r.message.empty()) {
        r.message = "mlock " + (o.path.empty() ? std::string("the program") : o.path) + ": " +
                    std::strerror(errno) + " (locked as touched instead)";
      }
    }
  }
  return r;
}

}  // namespace tacse3::firmware
