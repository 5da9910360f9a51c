// SPDX-License-Identifier: Apache-2.0
// tacse3 fileio: reading and replacing files safely, for every library and program that reads a
// user's file or writes one (POSIX). A FIFO or a device is reported at once, never waited on; a
// text input is bounded; an output replaces only a regular file, atomically.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>

namespace tacse3::fileio {

enum class ReadError { kNone, kNotFound, kOpen, kNotRegular, kTooLarge, kRead };

// What read_regular_file found; the caller words the message for its reader.
struct ReadResult {
  ReadError error = ReadError::kNone;
  int os_errno = 0;       // for kOpen and kRead
  const char* kind = "";  // for kNotRegular: "a FIFO", "a directory", ...
  bool ok() const noexcept { return error == ReadError::kNone; }
};

// Reads `file` into *out if it is a regular file of at most max_bytes (*out is untouched
// otherwise). Opened with O_NONBLOCK and checked with fstat on the descriptor, so a FIFO or a
// device returns kNotRegular at once. Never throws (an allocation failure is kRead, ENOMEM).
ReadResult read_regular_file(const std::filesystem::path& file, std::size_t max_bytes,
                             std::string* out) noexcept;

// " (strerror(err))", to append to a message.
std::string os_error(int err);
// "1 MiB", or "N bytes" for a bound that is not a whole number of MiB.
std::string size_text(std::size_t bytes);

// Checks that write_file_atomically can write `file`: its directory exists and is writable,
// and `file` is absent or a regular file (never a symlink, FIFO, device or directory).
bool check_output_file(const std::filesystem::path& file, std::string* error);

// check_output_file, then writes `text` to a new unique file beside `file` and renames it over
// `file`, so a reader sees the old or the new content, never a part. A replaced file keeps its
// permission bits.
bool write_file_atomically(const std::filesystem::path& file, const std::string& text,
                           std::string* error);

}  // namespace tacse3::fileio
