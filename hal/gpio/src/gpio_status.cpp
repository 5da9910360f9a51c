// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: GPIO status codes, line names and the null backend.
#include <time.h>

#include <cstdarg>
#include <cstdio>

#include "tacse3/hal/gpio.hpp"

namespace tacse3::hal {

const char* to_string(GpioError e) noexcept {
  switch (e) {
    case GpioError::kOk:
      return "ok";
    case GpioError::kNotConfigured:
      return "GPIO line not configured for this board";
    case GpioError::kNotFound:
      return "GPIO chip or line not found";
    case GpioError::kPermission:
      return "GPIO permission denied";
    case GpioError::kBusy:
      return "GPIO line busy";
    case GpioError::kIo:
      return "GPIO I/O error";
    case GpioError::kBadConfig:
      return "bad GPIO configuration";
    case GpioError::kBadState:
      return "GPIO call not valid now";
    case GpioError::kUnavailable:
      return "GPIO backend not compiled in";
  }
  return "unknown GPIO error";
}

GpioStatus GpioStatus::error(GpioError code, const char* fmt, ...) noexcept {
  GpioStatus s;
  s.code = code;
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(s.text.data(), s.text.size(), fmt, args);
  va_end(args);
  return s;
}

namespace {

class NullGpio final : public GpioBackend {
 public:
  GpioStatus open(const GpioConfig& /*config*/) override { return GpioStatus::success(); }
  bool has(GpioLine /*line*/) const override { return false; }
  GpioStatus write(GpioLine line, bool /*active*/) override { return absent(line); }
  GpioStatus read(GpioLine line, bool& active) override {
    active = false;
    return absent(line);
  }
  GpioStatus wait_edges(int timeout_ms, GpioEdge* /*edges*/, std::size_t /*capacity*/,
                        std::size_t& count) override {
    count = 0;
    // Nothing can happen: sleep, so a poll loop on the null board does not spin. Capped at 1 s.
    const int ms = timeout_ms < 0 || timeout_ms > 1000 ? 1000 : timeout_ms;
    timespec ts{};
    ts.tv_sec = ms / 1000;
    ts.tv_nsec = static_cast<long>(ms % 1000) * 1'000'000;
    clock_nanosleep(CLOCK_MONOTONIC, 0, &ts, nullptr);
    return GpioStatus::success();
  }
  void close() override {}
  const char* name() const override { return "null"; }

 private:
  static GpioStatus absent(GpioLine line) noexcept {
    return GpioStatus::error(GpioError::kNotConfigured, "GPIO %s: the null backend has no lines",
                             to_string(line));
  }
};

}  // namespace

std::unique_ptr<GpioBackend> make_null_gpio() {
  return std::make_unique<NullGpio>();
}

}  // namespace tacse3::hal
