// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: streaming NumPy .npy writer.
#include "tacse3/tools/npy.hpp"

#include <bit>

namespace tacse3::tools {

static_assert(std::endian::native == std::endian::little, "the .npy writer assumes little endian");

std::string npy_header(const std::string& descr, const std::vector<std::int64_t>& shape) {
  std::string dict = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': (";
  for (std::size_t i = 0; i < shape.size(); ++i) {
    dict += std::to_string(shape[i]);
    if (shape.size() == 1 || i + 1 < shape.size()) dict += ",";
    if (i + 1 < shape.size()) dict += " ";
  }
  dict += "), }";
  // magic(6) + version(2) + header length(2) + dict + padding + '\n' ≡ 0 (mod 64)
  const std::size_t unpadded = 10 + dict.size() + 1;
  dict.append((64 - unpadded % 64) % 64, ' ');
  dict += '\n';
  std::string h("\x93NUMPY\x01\x00", 8);
  const std::size_t len = dict.size();
  h += static_cast<char>(len & 0xff);
  h += static_cast<char>((len >> 8) & 0xff);
  return h + dict;
}

NpyWriter::~NpyWriter() {
  if (f_ != nullptr) std::fclose(f_);
}

std::string NpyWriter::open(const std::filesystem::path& file, const std::string& descr,
                            std::size_t item_bytes, std::int64_t n,
                            const std::vector<std::int64_t>& tail) {
  path_ = file;
  f_ = std::fopen(file.c_str(), "wb");
  if (f_ == nullptr) return file.string() + ": cannot open for writing";
  std::vector<std::int64_t> shape{n};
  record_elements_ = 1;
  for (auto t : tail) {
    shape.push_back(t);
    record_elements_ *= static_cast<std::size_t>(t);
  }
  record_bytes_ = record_elements_ * item_bytes;
  n_ = n;
  written_ = 0;
  const std::string h = npy_header(descr, shape);
  if (std::fwrite(h.data(), 1, h.size(), f_) != h.size()) return file.string() + ": write error";
  return {};
}

std::string NpyWriter::append(const void* data) {
  if (f_ == nullptr) return path_.string() + ": not open";
  if (written_ >= n_) return path_.string() + ": more records than declared";
  if (std::fwrite(data, 1, record_bytes_, f_) != record_bytes_) {
    return path_.string() + ": write error (disk full?)";
  }
  ++written_;
  return {};
}

std::string NpyWriter::close() {
  if (f_ == nullptr) return {};
  const bool ok = std::fclose(f_) == 0;
  f_ = nullptr;
  if (!ok) return path_.string() + ": write error on close";
  if (written_ != n_) {
    return path_.string() + ": " + std::to_string(written_) + " records written, " +
           std::to_string(n_) + " declared";
  }
  return {};
}

}  // namespace tacse3::tools
