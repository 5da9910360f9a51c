// SPDX-License-Identifier: Apache-2.0
// tacse3 config: the GPIO lines a board file describes. Plain data, so the board parser needs no
// hal header; hal::GpioBackend::open() takes this description as it is.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace tacse3::config {

enum class GpioLine : std::uint8_t {
  kStatusLed = 0,  // output: blink pattern per daemon state
  kTareButton,     // input, edge events, debounced: a press requests a tare
  kSensorTrigger,  // output: sync/trigger pulse to the sensors
  kGripperClosed,  // input, edge events, debounced: gripper jaw closed switch
};
inline constexpr std::size_t kGpioLineCount = 4;

constexpr const char* to_string(GpioLine line) noexcept {
  switch (line) {
    case GpioLine::kStatusLed:
      return "status_led";
    case GpioLine::kTareButton:
      return "tare_button";
    case GpioLine::kSensorTrigger:
      return "sensor_trigger";
    case GpioLine::kGripperClosed:
      return "gripper_closed";
  }
  return "unknown_line";
}
constexpr bool is_output(GpioLine line) noexcept {
  return line == GpioLine::kStatusLed || line == GpioLine::kSensorTrigger;
}

enum class GpioBias : std::uint8_t { kAsIs = 0, kDisable, kPullUp, kPullDown };

// One line as the board file names it. Levels are logical: "active" is high unless active_low is
// set (the kernel inverts).
struct GpioLineConfig {
  bool enabled = false;  // false: the board has no such line; calls on it return kNotConfigured
  std::string chip;      // empty: GpioConfig::chip
  std::string name;      // line name, e.g. "GPIO17" (preferred: survives chip renumbering), or
  int offset = -1;       // the offset on the chip when name is empty
  bool active_low = false;
  GpioBias bias = GpioBias::kAsIs;
};

struct GpioConfig {
  // Chip for lines that name none: "gpiochip0", "/dev/gpiochip0", a label ("pinctrl-bcm2711")
  // or a number. Empty: named lines are searched on every chip (Pi 5 header moved chips).
  std::string chip = "gpiochip0";
  std::string consumer = "tacse3d";  // shown by gpioinfo
  std::array<GpioLineConfig, kGpioLineCount> lines{};

  GpioLineConfig& line(GpioLine l) noexcept { return lines[static_cast<std::size_t>(l)]; }
  const GpioLineConfig& line(GpioLine l) const noexcept {
    return lines[static_cast<std::size_t>(l)];
  }
};

}  // namespace tacse3::config
