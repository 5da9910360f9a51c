// SPDX-License-Identifier: Apache-2.0
// tacse3 fuzz: candump -L line parser; parse -> format -> parse is a fixed point.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>

#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view line(reinterpret_cast<const char*>(data), size);
  tp::LogRecord r;
  if (tp::parse_candump_line(line, r) != tp::Status::kOk) return 0;
  char buf[tp::kCandumpLineMax];
  const std::size_t n = tp::format_candump_line(r, buf, sizeof buf);
  if (n == 0) {
    // Only records whose time stamp does not fit 10 digits of seconds may be unrepresentable.
    if (r.time_us / 1000000u < 10000000000ull && !r.rtr) __builtin_trap();
    return 0;
  }
  tp::LogRecord again;
  if (tp::parse_candump_line(std::string_view(buf, n), again) != tp::Status::kOk) __builtin_trap();
  if (again.time_us != r.time_us || again.frame.id != r.frame.id ||
      again.frame.extended != r.frame.extended || again.frame.fd != r.frame.fd ||
      again.frame.len != r.frame.len || again.rtr != r.rtr || again.error_frame != r.error_frame ||
      std::memcmp(again.iface.data(), r.iface.data(), r.iface.size()) != 0) {
    __builtin_trap();
  }
  if (!r.rtr && std::memcmp(again.frame.data.data(), r.frame.data.data(), r.frame.len) != 0) {
    __builtin_trap();
  }
  return 0;
}
