// SPDX-License-Identifier: Apache-2.0
// tacse3 fuzz: the board file parser (config/board_file). Any text gives either a board or an
// error message; a board it accepts can be described and turned into a fusion config.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "tacse3/config/board_file.hpp"

namespace tc = tacse3::config;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  tc::BoardConfig board;
  std::string error;
  if (!tc::parse_board(text, "fuzz.toml", &board, &error)) {
    if (error.empty()) __builtin_trap();  // every refusal names its reason
    return 0;
  }
  if (tc::describe(board).empty()) __builtin_trap();
  (void)tc::fusion_config(board);
  return 0;
}
