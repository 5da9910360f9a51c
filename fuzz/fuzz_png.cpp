// SPDX-License-Identifier: Apache-2.0
// tacse3 fuzz: the recording's PNG reader (recording/png.cpp, libspng). The input is written to
// a file, as the reader takes paths. Header and full decode must agree on a PNG both accept,
// and a decoded image holds exactly width x height x channels bytes.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "tacse3/recording/recording.hpp"

namespace tr = tacse3::recording;

namespace {
std::filesystem::path scratch_file() {
  static const std::filesystem::path p =
      std::filesystem::temp_directory_path() / ("tacse3-fuzz-png-" + std::to_string(getpid()));
  return p;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path file = scratch_file();
  std::FILE* f = std::fopen(file.c_str(), "wb");
  if (f == nullptr || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) {
    __builtin_trap();  // the scratch file must be writable
  }
  tr::PngHeader h;
  const tr::Status hs = tr::read_png_header(file, &h);
  tr::Image im;
  const tr::Status is = tr::read_png(file, &im);
  if (!hs && hs.message().empty()) __builtin_trap();
  if (!is && is.message().empty()) __builtin_trap();
  if (is) {
    if (im.channels != 1 && im.channels != 3) __builtin_trap();
    if (im.pixels.size() != tr::view(im).size()) __builtin_trap();
    if (hs && (h.width != im.width || h.height != im.height)) __builtin_trap();
  }
  return 0;
}
