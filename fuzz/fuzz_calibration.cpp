// SPDX-License-Identifier: Apache-2.0
// tacse3 fuzz: the calibration file parser (config/calibration_file). A file it accepts is
// written back by format_calibration, and that text parses again and formats to itself.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "tacse3/config/calibration_file.hpp"

namespace tc = tacse3::config;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  tc::CalibrationSet set;
  const tc::Status s = tc::parse_calibration(text, "fuzz.toml", &set);
  if (!s) {
    if (s.message().empty()) __builtin_trap();
    return 0;
  }
  std::string once;
  std::string error;
  if (!tc::format_calibration(set, &once, &error)) __builtin_trap();  // accepted = valid
  tc::CalibrationSet again;
  if (!tc::parse_calibration(once, "formatted.toml", &again)) __builtin_trap();
  std::string twice;
  if (!tc::format_calibration(again, &twice, &error) || twice != once) __builtin_trap();
  return 0;
}
