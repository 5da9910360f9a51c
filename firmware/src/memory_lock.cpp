// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: locking the daemon's memory (docs/performance.md, Memory).
#include "tacse3/firmware/memory_lock.hpp"

#include <link.h>
#include <sys/auxv.h>
#include <sys/mman.h>
#include <unistd.h>
#include <unwind.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <exception>
#include <fstream>
#include <sstream>

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
  std::ifstream f("/proc/self/smaps");
  std::stringstream text;
  text << f.rdbuf();
  std::size_t released = 0;
  for (const Mapping& m : clean_file_mappings(text.str())) {
    if (!inside(all, m.begin) || inside(keep, m.begin)) continue;
    if (madvise(reinterpret_cast<void*>(m.begin), m.end - m.begin, MADV_DONTNEED) == 0)
      released += m.end - m.begin;
  }
  return released;
}

}  // namespace

std::vector<Mapping> clean_file_mappings(const std::string& smaps) {
  std::vector<Mapping> all;
  std::istringstream in(smaps);
  std::string line;
  while (std::getline(in, line)) {
    unsigned long lo = 0, hi = 0;
    char perms[5] = {};
    int used = 0;
    // A mapping's header: "lo-hi perms offset dev inode [path]"; its fields: "Key: value kB".
    if (std::sscanf(line.c_str(), "%lx-%lx %4s %*s %*s %*s%n", &lo, &hi, perms, &used) == 3 &&
        used > 0) {
      Mapping m;
      m.begin = lo;
      m.end = hi;
      m.writable = perms[1] == 'w';
      const std::size_t path = line.find_first_not_of(' ', static_cast<std::size_t>(used));
      m.file = path != std::string::npos && line[path] == '/';
      all.push_back(m);
      continue;
    }
    long kib = 0;
    if (all.empty()) continue;
    if (std::sscanf(line.c_str(), "Rss: %ld", &kib) == 1) all.back().rss_kib = kib;
    if (std::sscanf(line.c_str(), "Anonymous: %ld", &kib) == 1) all.back().anonymous_kib = kib;
  }
  std::vector<Mapping> clean;
  for (const Mapping& m : all)
    if (m.file && !m.writable && m.anonymous_kib == 0) clean.push_back(m);
  return clean;
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
  // Before mlockall: pages of a locked mapping cannot be released.
  r.released_bytes = release_clean_pages(realtime);
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
