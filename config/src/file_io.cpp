// SPDX-License-Identifier: Apache-2.0
// tacse3 config: bounded reads of regular files (POSIX).
#include "file_io.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>

namespace tacse3::config::detail {
namespace {

namespace fs = std::filesystem;

std::string os_error(int err) {
  return std::string(" (") + std::strerror(err) + ")";
}

// "a FIFO" etc., for messages about a path that is not a regular file.
const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISLNK(mode)) return "a symbolic link";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

std::string size_text(std::size_t bytes) {
  if (bytes % (1u << 20) == 0) return std::to_string(bytes >> 20) + " MiB";
  return std::to_string(bytes) + " bytes";
}

// Closes the descriptor.
struct OwnedFile {
  int fd = -1;
  OwnedFile() = default;
  OwnedFile(const OwnedFile&) = delete;
  OwnedFile& operator=(const OwnedFile&) = delete;
  ~OwnedFile() {
    if (fd >= 0) ::close(fd);
  }
};

bool read_all(int fd, std::size_t max_bytes, std::string* out) {
  char buf[16384];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return false;
    if (n == 0) return true;
    // The file may have grown since fstat: the bound holds for what is read.
    if (out->size() + static_cast<std::size_t>(n) > max_bytes) {
      errno = EFBIG;
      return false;
    }
    out->append(buf, static_cast<std::size_t>(n));
  }
}

}  // namespace

bool read_regular_file(const fs::path& file, std::size_t max_bytes, const char* what,
                       std::string* out, std::string* error) {
  const std::string name = file.string();
  // O_NONBLOCK: opening a FIFO with no writer, or a device, returns at once instead of waiting;
  // fstat on the descriptor then checks the very file that would be read.
  OwnedFile f;
  f.fd = ::open(file.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (f.fd < 0) {
    *error = errno == ENOENT ? name + ": no such file"
                             : name + ": cannot open for reading" + os_error(errno);
    return false;
  }
  struct stat st {};
  if (::fstat(f.fd, &st) != 0) {
    *error = name + ": cannot read" + os_error(errno);
    return false;
  }
  if (!S_ISREG(st.st_mode)) {
    *error = name + ": is " + kind_of(st.st_mode) + ", expected " + what +
             " (a regular file); give the path of one";
    return false;
  }
  const std::string too_large =
      name + ": file is larger than " + size_text(max_bytes) + "; not " + what;
  if (static_cast<std::uintmax_t>(st.st_size) > max_bytes) {
    *error = too_large;
    return false;
  }
  std::string text;
  text.reserve(static_cast<std::size_t>(st.st_size));
  if (!read_all(f.fd, max_bytes, &text)) {
    *error = errno == EFBIG ? too_large : name + ": read error" + os_error(errno);
    return false;
  }
  *out = std::move(text);
  return true;
}

}  // namespace tacse3::config::detail
