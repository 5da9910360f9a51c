// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: status codes returned by every fallible protocol call (no exceptions).
#pragma once

#include <cstdint>

namespace tacse3::protocol {

enum class Status : std::uint8_t {
  kOk = 0,
  kUnknownId,       // not a tacse3 identifier under the configured id layout (or node id 0)
  kBadLength,       // payload length / classic-vs-FD format does not match the message table
  kBadCrc,          // CRC-8 mismatch
  kBadCounter,      // the counters inside one CAN FD cycle frame disagree
  kBadArgument,     // an argument of the call is outside its documented range
  kWrongMessage,    // a valid frame, but not the message the call expects
  kNotAvailable,    // the requested value is marked invalid / not available
  kBufferTooSmall,  // an output buffer cannot hold the result
  kParseError,      // malformed text (candump line)
};

// One convention for every tacse3 status type (this one and config::Status): `!s` is true on a
// failure, and nothing converts to bool, so `if (s)` compiles on neither and a check reads the
// same everywhere: `if (!s)` or `if (s != Status::kOk)`.
constexpr bool operator!(Status s) noexcept {
  return s != Status::kOk;
}

constexpr const char* to_string(Status s) noexcept {
  switch (s) {
    case Status::kOk:
      return "ok";
    case Status::kUnknownId:
      return "unknown identifier";
    case Status::kBadLength:
      return "wrong payload length or frame format";
    case Status::kBadCrc:
      return "CRC mismatch";
    case Status::kBadCounter:
      return "inconsistent counters in one frame";
    case Status::kBadArgument:
      return "argument out of range";
    case Status::kWrongMessage:
      return "not the expected message";
    case Status::kNotAvailable:
      return "value not available";
    case Status::kBufferTooSmall:
      return "buffer too small";
    case Status::kParseError:
      return "parse error";
  }
  return "unknown status";
}

}  // namespace tacse3::protocol
