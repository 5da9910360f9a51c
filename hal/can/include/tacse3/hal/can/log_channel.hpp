// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: the candump -L log backend (read frames from a log, write frames as a log).
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>

#include "tacse3/hal/can/channel.hpp"

namespace tacse3::hal::can {

// Reads frames from a `candump -L` text stream and/or writes sent frames to one. Either side is
// optional: send() without an output, or receive() without an input, fails / returns kEnd.
// Reading is not paced: a log file is consumed as fast as it is read (timeouts do not apply).
class LogChannel final : public Channel {
 public:
  // "-" means stdin (input) / stdout (output); an empty path means "none". nullptr on failure.
  // An input path must be a regular file or a FIFO (a directory or device is refused).
  static std::unique_ptr<LogChannel> open(const std::string& input_path,
                                          const std::string& output_path, std::string& error,
                                          std::string iface_name = "can0");
  // Adopt already-open streams (not closed by the channel).
  LogChannel(std::FILE* in, std::FILE* out, std::string iface_name = "can0");
  ~LogChannel() override;

  bool send(const CanFrame& f) override;
  RxResult receive(RxFrame& out, int timeout_ms) override;
  const std::string& last_error() const override { return error_; }
  // tx_frames: lines written; tx_errors: frames refused or write failures; rx_frames: data
  // frames read; error_frames: error frames in the input log. No queue, the bus is always
  // error-active and nothing is ever dropped by policy.
  ChannelStats stats() const override;

  // Time stamp written for sent frames; defaults to CLOCK_REALTIME (as candump does).
  void set_clock(std::function<std::uint64_t()> now_us) { now_us_ = std::move(now_us); }

  std::uint64_t lines_read() const { return lines_; }
  std::uint64_t bad_lines() const { return bad_lines_; }     // not parseable as candump -L
  std::uint64_t skipped_frames() const { return skipped_; }  // error / remote frames

  // The first write error of the output ("CAN log FILE: write failed: CAUSE"). After it, send()
  // writes nothing more: a log cut mid-line is worse than one that stops at a line's end (an
  // output file opened here is cut back to its last whole line, e.g. after a full disk). Safe to
  // call from another thread than send()'s.
  bool write_failed() const noexcept { return write_failed_.load(std::memory_order_acquire); }
  const std::string& write_error() const noexcept { return write_error_; }

 private:
  std::FILE* in_ = nullptr;
  std::FILE* out_ = nullptr;
  bool own_in_ = false;
  bool own_out_ = false;
  std::string iface_;
  long long line_end_ = -1;  // an opened output file's size up to its last whole line
  std::string in_name_ = "(standard input)";  // for messages: the quoted path
  std::string out_name_ = "the output";       // for messages: the path, or "standard output"
  std::string error_;
  std::string write_error_;  // set once, before write_failed_
  std::atomic<bool> write_failed_{false};
  std::function<std::uint64_t()> now_us_;
  std::uint64_t lines_ = 0;
  std::uint64_t bad_lines_ = 0;
  std::uint64_t skipped_ = 0;
  std::atomic<std::uint64_t> tx_frames_{0}, tx_errors_{0}, rx_frames_{0}, error_frames_{0};
};

}  // namespace tacse3::hal::can
