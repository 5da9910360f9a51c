// SPDX-License-Identifier: Apache-2.0
// tacse3 config: reading the library's files safely (private to tacse3_config).
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

}  // namespace tacse3::config::detail
