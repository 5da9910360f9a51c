// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: GPIO backend on libgpiod 1.6's C++ bindings (gpiod::chip, gpiod::line).
#include <errno.h>
#include <poll.h>

#include <cstring>

#include "tacse3/hal/gpio.hpp"

#if TACSE3_HAL_HAS_LIBGPIOD
#include <exception>
#include <gpiod.hpp>
#include <stdexcept>
#include <system_error>
#endif

namespace tacse3::hal {

bool libgpiod_available() noexcept {
  return TACSE3_HAL_HAS_LIBGPIOD != 0;
}

#if TACSE3_HAL_HAS_LIBGPIOD
namespace {

GpioError errno_error(int e) noexcept {
  switch (e) {
    case ENOENT:
    case ENODEV:
    case ENXIO:
      return GpioError::kNotFound;
    case EACCES:
    case EPERM:
      return GpioError::kPermission;
    case EBUSY:
      return GpioError::kBusy;
    default:
      return GpioError::kIo;
  }
}

// libgpiodcxx reports failures by throwing; nothing escapes this file.
class LibgpiodGpio final : public GpioBackend {
 public:
  ~LibgpiodGpio() override { close(); }

  GpioStatus open(const GpioConfig& config) override {
    close();
    for (std::size_t i = 0; i < kGpioLineCount; ++i) {
      const auto which = static_cast<GpioLine>(i);
      const GpioLineConfig& lc = config.line(which);
      if (!lc.enabled) continue;
      GpioStatus st = request(config, which, lc);
      if (!st.ok()) {
        close();
        return st;
      }
    }
    open_ = true;
    return GpioStatus::success();
  }

  bool has(GpioLine line) const override { return static_cast<bool>(slot(line).line); }

  GpioStatus write(GpioLine line, bool active) override {
    Slot& s = slot(line);
    if (!s.line) return absent(line);
    try {
      s.line.set_value(active ? 1 : 0);
    } catch (const std::system_error& e) {
      return GpioStatus::error(errno_error(e.code().value()), "GPIO %s: set value: %s",
                               to_string(line), e.what());
    } catch (const std::exception& e) {
      return GpioStatus::error(GpioError::kIo, "GPIO %s: set value: %s", to_string(line), e.what());
    }
    return GpioStatus::success();
  }

  GpioStatus read(GpioLine line, bool& active) override {
    active = false;
    Slot& s = slot(line);
    if (!s.line) return absent(line);
    try {
      active = s.line.get_value() != 0;
    } catch (const std::system_error& e) {
      return GpioStatus::error(errno_error(e.code().value()), "GPIO %s: get value: %s",
                               to_string(line), e.what());
    } catch (const std::exception& e) {
      return GpioStatus::error(GpioError::kIo, "GPIO %s: get value: %s", to_string(line), e.what());
    }
    return GpioStatus::success();
  }

  GpioStatus wait_edges(int timeout_ms, GpioEdge* edges, std::size_t capacity,
                        std::size_t& count) override {
    count = 0;
    std::array<pollfd, kGpioLineCount> fds{};
    std::array<GpioLine, kGpioLineCount> which{};
    nfds_t n = 0;
    for (std::size_t i = 0; i < kGpioLineCount; ++i) {
      if (slots_[i].event_fd < 0) continue;
      fds[n].fd = slots_[i].event_fd;
      fds[n].events = POLLIN | POLLPRI;
      which[n] = static_cast<GpioLine>(i);
      ++n;
    }
    if (n == 0) {  // no inputs: just wait
      ::poll(nullptr, 0, timeout_ms);
      return GpioStatus::success();
    }
    int wait = timeout_ms;
    while (count < capacity) {
      const int r = ::poll(fds.data(), n, wait);
      if (r < 0) {
        if (errno == EINTR) return GpioStatus::success();
        return GpioStatus::error(GpioError::kIo, "GPIO: poll on line events: %s",
                                 std::strerror(errno));
      }
      if (r == 0) break;
      for (nfds_t k = 0; k < n && count < capacity; ++k) {
        if ((fds[k].revents & (POLLIN | POLLPRI)) == 0) continue;
        try {
          const gpiod::line_event ev = slot(which[k]).line.event_read();
          edges[count].line = which[k];
          edges[count].active = ev.event_type == gpiod::line_event::RISING_EDGE;
          edges[count].timestamp_ns = static_cast<std::int64_t>(ev.timestamp.count());
          ++count;
        } catch (const std::exception& e) {
          return GpioStatus::error(GpioError::kIo, "GPIO %s: reading an edge event: %s",
                                   to_string(which[k]), e.what());
        }
      }
      wait = 0;  // drain what is already queued, then return
    }
    return GpioStatus::success();
  }

  void close() override {
    for (Slot& s : slots_) {
      if (s.line) {
        try {
          s.line.release();
        } catch (const std::exception&) {
          // Releasing a line of a vanished chip: nothing left to do.
        }
      }
      s.line = gpiod::line();
      s.event_fd = -1;
    }
    open_ = false;
  }

  const char* name() const override { return "libgpiod"; }

 private:
  struct Slot {
    gpiod::line line;  // holds its chip open
    int event_fd = -1;
  };

  Slot& slot(GpioLine line) { return slots_[static_cast<std::size_t>(line)]; }
  const Slot& slot(GpioLine line) const { return slots_[static_cast<std::size_t>(line)]; }

  static GpioStatus absent(GpioLine line) noexcept {
    return GpioStatus::error(GpioError::kNotConfigured, "GPIO %s: not in the board file",
                             to_string(line));
  }

  GpioStatus request(const GpioConfig& config, GpioLine which, const GpioLineConfig& lc) {
    const char* role = to_string(which);
    const std::string& chip_name = lc.chip.empty() ? config.chip : lc.chip;
    if (lc.name.empty() && lc.offset < 0) {
      return GpioStatus::error(GpioError::kBadConfig, "GPIO %s: give a line name or an offset",
                               role);
    }
    if (lc.name.empty() && chip_name.empty()) {
      return GpioStatus::error(GpioError::kBadConfig,
                               "GPIO %s: offset %d needs a chip (no default chip set)", role,
                               lc.offset);
    }
    gpiod::line line;
    try {
      if (chip_name.empty()) {
        line = gpiod::find_line(lc.name);  // every chip
        if (!line) {
          return GpioStatus::error(GpioError::kNotFound, "GPIO %s: no line named '%s' on any chip",
                                   role, lc.name.c_str());
        }
      } else {
        gpiod::chip chip(chip_name, gpiod::chip::OPEN_LOOKUP);
        if (!lc.name.empty()) {
          line = chip.find_line(lc.name);
          if (!line) {
            return GpioStatus::error(GpioError::kNotFound, "GPIO %s: no line named '%s' on %s",
                                     role, lc.name.c_str(), chip_name.c_str());
          }
        } else {
          if (static_cast<unsigned int>(lc.offset) >= chip.num_lines()) {
            return GpioStatus::error(GpioError::kBadConfig,
                                     "GPIO %s: offset %d beyond the %u lines of %s", role,
                                     lc.offset, chip.num_lines(), chip_name.c_str());
          }
          line = chip.get_line(static_cast<unsigned int>(lc.offset));
        }
      }
    } catch (const std::system_error& e) {
      const int err = e.code().value();
      return GpioStatus::error(errno_error(err), "GPIO %s: opening chip '%s': %s%s", role,
                               chip_name.c_str(), std::strerror(err),
                               err == EACCES ? " (is the user in group gpio?)" : "");
    } catch (const std::exception& e) {
      return GpioStatus::error(GpioError::kIo, "GPIO %s: opening chip '%s': %s", role,
                               chip_name.c_str(), e.what());
    }

    gpiod::line_request req;
    req.consumer = config.consumer;
    req.request_type = is_output(which) ? gpiod::line_request::DIRECTION_OUTPUT
                                        : gpiod::line_request::EVENT_BOTH_EDGES;
    if (lc.active_low) req.flags |= gpiod::line_request::FLAG_ACTIVE_LOW;
    switch (lc.bias) {
      case GpioBias::kAsIs:
        break;
      case GpioBias::kDisable:
        req.flags |= gpiod::line_request::FLAG_BIAS_DISABLE;
        break;
      case GpioBias::kPullUp:
        req.flags |= gpiod::line_request::FLAG_BIAS_PULL_UP;
        break;
      case GpioBias::kPullDown:
        req.flags |= gpiod::line_request::FLAG_BIAS_PULL_DOWN;
        break;
    }
    try {
      line.request(req, 0);
    } catch (const std::system_error& e) {
      const int err = e.code().value();
      std::string user;
      try {
        user = line.consumer();
      } catch (const std::exception&) {
      }
      return GpioStatus::error(errno_error(err), "GPIO %s: requesting line %u ('%s'): %s%s%s", role,
                               line.offset(), lc.name.c_str(), std::strerror(err),
                               user.empty() ? "" : "; held by ", user.c_str());
    } catch (const std::exception& e) {
      return GpioStatus::error(GpioError::kIo, "GPIO %s: requesting line %u: %s", role,
                               line.offset(), e.what());
    }
    Slot& s = slot(which);
    s.line = line;
    s.event_fd = -1;
    if (!is_output(which)) {
      try {
        s.event_fd = line.event_get_fd();
      } catch (const std::exception& e) {
        return GpioStatus::error(GpioError::kIo, "GPIO %s: event fd: %s", role, e.what());
      }
    }
    return GpioStatus::success();
  }

  std::array<Slot, kGpioLineCount> slots_{};
  bool open_ = false;
};

}  // namespace

std::unique_ptr<GpioBackend> make_libgpiod_gpio() {
  return std::make_unique<LibgpiodGpio>();
}

#else  // !TACSE3_HAL_HAS_LIBGPIOD

namespace {

class UnavailableGpio final : public GpioBackend {
 public:
  GpioStatus open(const GpioConfig& /*config*/) override {
    return GpioStatus::error(GpioError::kUnavailable,
                             "GPIO: built without libgpiod (libgpiod-dev not found at configure "
                             "time); use the null backend or rebuild");
  }
  bool has(GpioLine /*line*/) const override { return false; }
  GpioStatus write(GpioLine /*line*/, bool /*active*/) override { return open(GpioConfig{}); }
  GpioStatus read(GpioLine /*line*/, bool& active) override {
    active = false;
    return open(GpioConfig{});
  }
  GpioStatus wait_edges(int /*timeout_ms*/, GpioEdge* /*edges*/, std::size_t /*capacity*/,
                        std::size_t& count) override {
    count = 0;
    return open(GpioConfig{});
  }
  void close() override {}
  const char* name() const override { return "libgpiod (unavailable)"; }
};

}  // namespace

std::unique_ptr<GpioBackend> make_libgpiod_gpio() {
  return std::make_unique<UnavailableGpio>();
}

#endif

}  // namespace tacse3::hal
