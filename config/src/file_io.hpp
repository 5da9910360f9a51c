// SPDX-License-Identifier: Apache-2.0
// tacse3 config: reading and replacing the library's files safely (private to tacse3_config).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>

namespace tacse3::config::detail {

// Reads `file` into *out if it is a regular file of at most max_bytes. Anything else (missing,
// a directory, a FIFO, a device, too large) is false + *error naming the file; a FIFO or a
// device never blocks. `what` names the expected content ("a calibration file").
bool read_regular_file(const std::filesystem::path& file, std::size_t max_bytes,
                       const char* what, std::string* out, std::string* error);

// Checks that write_file_atomically can write `file`: its directory exists and is writable,
// and `file` is absent or a regular file (never a symlink, FIFO, device or directory).
bool check_output_file(const std::filesystem::path& file, std::string* error);

// check_output_file, then writes `text` to a new unique file beside `file` and renames it over
// `file`, so a reader sees the old or the new content, never a part. A replaced file keeps its
// permission bits.
bool write_file_atomically(const std::filesystem::path& file, const std::string& text,
                           std::string* error);

}  // namespace tacse3::config::detail
