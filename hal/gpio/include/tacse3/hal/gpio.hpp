// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: the GPIO interface (status LED, tare button, sensor trigger, gripper-closed input).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "tacse3/config/gpio_lines.hpp"

namespace tacse3::hal {

enum class GpioError : std::uint8_t {
  kOk = 0,
  kNotConfigured,  // the line is not in the board file (every line is optional)
  kNotFound,       // the chip or the named line does not exist
  kPermission,     // EACCES opening the chip (user not in group gpio?)
  kBusy,           // the line is requested by another consumer
  kIo,             // any other kernel or library failure
  kBadConfig,      // inconsistent line configuration
  kBadState,       // call not valid now (e.g. write before open)
  kUnavailable,    // the backend was not compiled in
};

const char* to_string(GpioError e) noexcept;

// Result of a GPIO call: code + message naming the line and the cause. Never allocates.
struct GpioStatus {
  GpioError code = GpioError::kOk;
  std::array<char, 192> text{};

  bool ok() const noexcept { return code == GpioError::kOk; }
  explicit operator bool() const noexcept { return ok(); }
  const char* message() const noexcept { return text[0] != '\0' ? text.data() : to_string(code); }

  static GpioStatus success() noexcept { return {}; }
  static GpioStatus error(GpioError code, const char* fmt, ...) noexcept
      __attribute__((format(printf, 2, 3)));
};

// The line description is the board file's (config/); hal uses it as it is.
using config::GpioBias;
using config::GpioConfig;
using config::GpioLine;
using config::GpioLineConfig;
using config::is_output;
using config::kGpioLineCount;
using config::to_string;

// An edge on an input line: the logical level after the edge and the kernel's timestamp.
struct GpioEdge {
  GpioLine line = GpioLine::kTareButton;
  bool active = false;
  std::int64_t timestamp_ns = 0;
};

// A set of requested lines. Not thread-safe as a whole; write() to different lines from
// different threads is fine in the libgpiod backend (one kernel handle per line).
class GpioBackend {
 public:
  virtual ~GpioBackend() = default;
  // Requests every enabled line: outputs driven inactive, inputs with both-edge events.
  virtual GpioStatus open(const GpioConfig& config) = 0;
  virtual bool has(GpioLine line) const = 0;
  virtual GpioStatus write(GpioLine line, bool active) = 0;
  virtual GpioStatus read(GpioLine line, bool& active) = 0;
  // Waits up to timeout_ms (< 0: forever) for edges on the input lines and stores up to
  // `capacity` of them; count = how many (0 on timeout).
  virtual GpioStatus wait_edges(int timeout_ms, GpioEdge* edges, std::size_t capacity,
                                std::size_t& count) = 0;
  // Releases every line (outputs go back to the kernel; the LED may stay as it was).
  virtual void close() = 0;
  virtual const char* name() const = 0;
};

// No lines at all: open() succeeds, has() is false, writes/reads return kNotConfigured,
// wait_edges() sleeps for the timeout. For the sim board and hosts without GPIO.
std::unique_ptr<GpioBackend> make_null_gpio();

// libgpiod 1.6 (C++ bindings). Without libgpiod at build time open() returns kUnavailable.
std::unique_ptr<GpioBackend> make_libgpiod_gpio();
bool libgpiod_available() noexcept;

}  // namespace tacse3::hal
