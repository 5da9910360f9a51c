// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: candump -L log lines ("(sec.usec) iface id#data"), parse and format.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tacse3/protocol/can_frame.hpp"
#include "tacse3/protocol/status.hpp"

namespace tacse3::protocol {

// One line of `candump -L` (can-utils' log format), e.g.
//   (1700000000.123456) can0 021#0102030405060708      classic, 11-bit id (3 hex digits)
//   (1700000000.123456) can0 1ACE0021#01020304         classic, 29-bit id (8 hex digits)
//   (1700000000.123456) can0 026##1<128 hex digits>    CAN FD, flags nibble (1 = BRS, 2 = ESI)
//   (1700000000.123456) can0 021#R                     remote frame
// An 8-digit id with bit 29 set (CAN_ERR_FLAG) is an error frame.
struct LogRecord {
  std::uint64_t time_us = 0;     // the (seconds.microseconds) stamp in microseconds
  std::array<char, 17> iface{};  // NUL-terminated interface name, at most 16 characters
  CanFrame frame;
  bool rtr = false;
  bool error_frame = false;
};

inline constexpr std::size_t kCandumpLineMax = 200;  // longest line format_candump_line writes

// Parse one line (without or with the trailing newline). kParseError on anything malformed.
Status parse_candump_line(std::string_view line, LogRecord& out) noexcept;

// Write `r` as one line without newline into buf (NUL-terminated). Returns the number of
// characters written, or 0 if `cap` is too small or the record is not representable.
std::size_t format_candump_line(const LogRecord& r, char* buf, std::size_t cap) noexcept;

}  // namespace tacse3::protocol
