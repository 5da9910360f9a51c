// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: a streaming writer of NumPy .npy files (format version 1.0, C order).
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace tacse3::tools {

// Writes one array of shape (n, tail...) record by record: open() writes the header with the
// final shape, append() adds one record of prod(tail) elements. Little-endian dtypes only:
// "<f4" (float), "<i8" (int64), "|u1" (uint8).
class NpyWriter {
 public:
  NpyWriter() = default;
  ~NpyWriter();
  NpyWriter(const NpyWriter&) = delete;
  NpyWriter& operator=(const NpyWriter&) = delete;

  // Empty string or an error naming the file.
  std::string open(const std::filesystem::path& file, const std::string& descr,
                   std::size_t item_bytes, std::int64_t n, const std::vector<std::int64_t>& tail);
  std::string append(const void* data);  // one record
  // Checks that exactly n records were written and closes the file.
  std::string close();

  std::size_t record_elements() const noexcept { return record_elements_; }

 private:
  std::FILE* f_ = nullptr;
  std::filesystem::path path_;
  std::size_t record_bytes_ = 0;
  std::size_t record_elements_ = 0;
  std::int64_t n_ = 0;
  std::int64_t written_ = 0;
};

// The .npy header bytes (magic, version 1.0, dict padded to a multiple of 64 bytes).
std::string npy_header(const std::string& descr, const std::vector<std::int64_t>& shape);

}  // namespace tacse3::tools
