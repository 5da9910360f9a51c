// SPDX-License-Identifier: Apache-2.0
// tacse3 fileio: bounded reads of regular files and atomic replacement (POSIX).
#include "tacse3/fileio/file_io.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>

namespace tacse3::fileio {
namespace {

namespace fs = std::filesystem;

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

// Closes the descriptor and, unless kept, removes the file it was created as.
struct OwnedFile {
  int fd = -1;
  std::string unlink_path;
  OwnedFile() = default;
  OwnedFile(const OwnedFile&) = delete;
  OwnedFile& operator=(const OwnedFile&) = delete;
  ~OwnedFile() {
    if (fd >= 0) ::close(fd);
    if (!unlink_path.empty()) ::unlink(unlink_path.c_str());
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

bool write_all(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

fs::path directory_of(const fs::path& file) {
  return file.has_parent_path() ? file.parent_path() : fs::path(".");
}

// A new file beside `file` (O_EXCL: never an existing one); 0666 less the umask, like fopen.
bool create_temporary(const fs::path& file, OwnedFile* tmp, std::string* error) {
  static std::atomic<unsigned> counter{0};
  const fs::path dir = directory_of(file);
  for (int attempt = 0; attempt < 100; ++attempt) {
    // Appended piece by piece: GCC 12 at -O3 reports a false -Wrestrict for "." + std::string.
    std::string name(1, '.');
    name += file.filename().string();
    name += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
    const std::string path = (dir / name).string();
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0666);
    if (fd >= 0) {
      tmp->fd = fd;
      tmp->unlink_path = path;
      return true;
    }
    if (errno != EEXIST) break;
  }
  *error = file.string() + ": cannot create a temporary file in " + dir.string() + os_error(errno);
  return false;
}

}  // namespace

std::string os_error(int err) {
  return std::string(" (") + std::strerror(err) + ")";
}

std::string size_text(std::size_t bytes) {
  if (bytes % (1u << 20) == 0) return std::to_string(bytes >> 20) + " MiB";
  return std::to_string(bytes) + " bytes";
}

ReadResult read_regular_file(const fs::path& file, std::size_t max_bytes,
                             std::string* out) noexcept {
  ReadResult r;
  // O_NONBLOCK: opening a FIFO with no writer, or a device, returns at once instead of waiting;
  // fstat on the descriptor then checks the very file that would be read.
  OwnedFile f;
  f.fd = ::open(file.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (f.fd < 0) {
    r.error = errno == ENOENT ? ReadError::kNotFound : ReadError::kOpen;
    r.os_errno = errno;
    return r;
  }
  struct stat st {};
  if (::fstat(f.fd, &st) != 0) {
    r.error = ReadError::kRead;
    r.os_errno = errno;
    return r;
  }
  if (!S_ISREG(st.st_mode)) {
    r.error = ReadError::kNotRegular;
    r.kind = kind_of(st.st_mode);
    return r;
  }
  if (static_cast<std::uintmax_t>(st.st_size) > max_bytes) {
    r.error = ReadError::kTooLarge;
    return r;
  }
  try {
    std::string text;
    text.reserve(static_cast<std::size_t>(st.st_size));
    if (!read_all(f.fd, max_bytes, &text)) {
      r.error = errno == EFBIG ? ReadError::kTooLarge : ReadError::kRead;
      r.os_errno = errno;
      return r;
    }
    *out = std::move(text);
  } catch (...) {
    r.error = ReadError::kRead;
    r.os_errno = ENOMEM;
  }
  return r;
}

bool check_output_file(const fs::path& file, std::string* error) {
  const std::string name = file.string();
  if (name.empty()) {
    *error = "empty output file name; give the path of the file to write";
    return false;
  }
  struct stat st {};
  if (::lstat(file.c_str(), &st) == 0) {
    if (!S_ISREG(st.st_mode)) {
      *error = name + ": is " + kind_of(st.st_mode) +
               "; refusing to replace it (give the path of a regular file or of a new one)";
      return false;
    }
  } else if (errno != ENOENT) {
    *error = name + ": cannot check the output file" + os_error(errno);
    return false;
  }
  const fs::path dir = directory_of(file);
  if (::stat(dir.c_str(), &st) != 0) {
    *error = errno == ENOENT
                 ? name + ": the directory " + dir.string() +
                       " does not exist; create it or give another path"
                 : name + ": cannot check the directory " + dir.string() + os_error(errno);
    return false;
  }
  if (!S_ISDIR(st.st_mode)) {
    *error = name + ": " + dir.string() + " is not a directory; give another path";
    return false;
  }
  if (::access(dir.c_str(), W_OK | X_OK) != 0) {
    *error = name + ": cannot write in the directory " + dir.string() + os_error(errno);
    return false;
  }
  return true;
}

bool write_file_atomically(const fs::path& file, const std::string& text, std::string* error) {
  if (!check_output_file(file, error)) return false;
  struct stat old {};
  const bool replacing = ::lstat(file.c_str(), &old) == 0;
  OwnedFile tmp;
  if (!create_temporary(file, &tmp, error)) return false;
  // A replaced file keeps its permission bits (a calibration readable only by its group stays so).
  if (replacing && ::fchmod(tmp.fd, old.st_mode & 07777) != 0) {
    *error = file.string() + ": cannot set the temporary file's mode" + os_error(errno);
    return false;
  }
  // fsync before the rename: after a power cut the name holds the old or the whole new file.
  if (!write_all(tmp.fd, text) || ::fsync(tmp.fd) != 0) {
    *error = file.string() + ": write error" + os_error(errno);
    return false;
  }
  const int fd = tmp.fd;
  tmp.fd = -1;
  if (::close(fd) != 0) {
    *error = file.string() + ": write error" + os_error(errno);
    return false;
  }
  // Checked again just before the rename: the target may have changed since the first check.
  if (!check_output_file(file, error)) return false;
  if (::rename(tmp.unlink_path.c_str(), file.c_str()) != 0) {
    *error = file.string() + ": cannot rename the temporary file into place" + os_error(errno);
    return false;
  }
  tmp.unlink_path.clear();
  return true;
}

}  // namespace tacse3::fileio
