// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: candump -L log channel.
#include "tacse3/hal/can/log_channel.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "tacse3/protocol/candump.hpp"

namespace tacse3::hal::can {
namespace {

std::uint64_t realtime_us() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000u +
         static_cast<std::uint64_t>(ts.tv_nsec) / 1000u;
}

// Opens a log to read: a regular file, or a FIFO (a live candump piped in, like stdin). A
// directory or a device is refused at once: /dev/zero would be read forever. O_NONBLOCK so the
// check comes before any wait; a FIFO then waits for its writer like a plain open would.
std::FILE* open_input(const std::string& path, std::string& error) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    error = "cannot open log '" + path + "': " + std::strerror(errno);
    return nullptr;
  }
  struct stat st {};
  const char* kind = nullptr;
  if (::fstat(fd, &st) != 0) {
    kind = "unreadable";
  } else if (S_ISDIR(st.st_mode)) {
    kind = "a directory";
  } else if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) {
    kind = "a device";
  } else if (S_ISSOCK(st.st_mode)) {
    kind = "a socket";
  }
  if (kind != nullptr) {
    error = "log '" + path + "' is " + kind + ", expected a candump -L log file (or - for stdin)";
    ::close(fd);
    return nullptr;
  }
  if (S_ISFIFO(st.st_mode)) ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  std::FILE* in = ::fdopen(fd, "r");
  if (in == nullptr) {
    error = "cannot open log '" + path + "': " + std::strerror(errno);
    ::close(fd);
  }
  return in;
}

}  // namespace

std::unique_ptr<LogChannel> LogChannel::open(const std::string& input_path,
                                             const std::string& output_path, std::string& error,
                                             std::string iface_name) {
  std::FILE* in = nullptr;
  std::FILE* out = nullptr;
  bool own_in = false, own_out = false;
  if (input_path == "-") {
    in = stdin;
  } else if (!input_path.empty()) {
    in = open_input(input_path, error);
    if (in == nullptr) return nullptr;
    own_in = true;
  }
  if (output_path == "-") {
    out = stdout;
  } else if (!output_path.empty()) {
    out = std::fopen(output_path.c_str(), "w");
    if (out == nullptr) {
      error = "cannot create log '" + output_path + "': " + std::strerror(errno);
      if (own_in) std::fclose(in);
      return nullptr;
    }
    // Unbuffered: send() writes each line at once, and after a failed write no buffered rest
    // can reach the file when it is closed.
    std::setvbuf(out, nullptr, _IONBF, 0);
    own_out = true;
  }
  auto ch = std::make_unique<LogChannel>(in, out, std::move(iface_name));
  ch->own_in_ = own_in;
  if (own_in) ch->in_name_ = "'" + input_path + "'";
  ch->own_out_ = own_out;
  if (!output_path.empty()) ch->out_name_ = output_path == "-" ? "standard output" : output_path;
  if (own_out) ch->line_end_ = 0;
  return ch;
}

LogChannel::LogChannel(std::FILE* in, std::FILE* out, std::string iface_name)
    : in_(in), out_(out), iface_(std::move(iface_name)), now_us_(realtime_us) {
  if (iface_.empty() || iface_.size() > 16) iface_ = "can0";
}

LogChannel::~LogChannel() {
  if (own_in_ && in_ != nullptr) std::fclose(in_);
  if (own_out_ && out_ != nullptr) std::fclose(out_);
}

ChannelStats LogChannel::stats() const {
  ChannelStats s;
  s.tx_frames = tx_frames_.load(std::memory_order_relaxed);
  s.tx_errors = tx_errors_.load(std::memory_order_relaxed);
  s.rx_frames = rx_frames_.load(std::memory_order_relaxed);
  s.error_frames = error_frames_.load(std::memory_order_relaxed);
  return s;
}

bool LogChannel::send(const CanFrame& f) {
  if (out_ == nullptr) {
    error_ = "log channel has no output";
    tx_errors_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  protocol::LogRecord r;
  r.time_us = now_us_();
  std::memcpy(r.iface.data(), iface_.c_str(), iface_.size() + 1);
  r.frame = f;
  char line[protocol::kCandumpLineMax + 2];
  const std::size_t n = protocol::format_candump_line(r, line, sizeof line - 1);
  if (n == 0) {
    error_ = "frame cannot be written as a candump line";
    tx_errors_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  line[n] = '\n';
  if (write_failed_.load(std::memory_order_relaxed)) {
    tx_errors_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  if (std::fwrite(line, 1, n + 1, out_) != n + 1 || std::fflush(out_) != 0) {
    const int e = errno;
    // A full disk took part of the line: cut a file back to its last whole line.
    if (line_end_ >= 0) (void)::ftruncate(::fileno(out_), line_end_);
    error_ = "CAN log " + out_name_ + ": write failed: " + std::strerror(e);
    write_error_ = error_;
    write_failed_.store(true, std::memory_order_release);
    tx_errors_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  if (own_out_) line_end_ = ::ftello(out_);  // -1 for a FIFO: nothing to cut
  tx_frames_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

RxResult LogChannel::receive(RxFrame& out, int /*timeout_ms*/) {
  if (in_ == nullptr) return RxResult::kEnd;
  char line[512];
  while (std::fgets(line, sizeof line, in_) != nullptr) {
    std::size_t len = std::strlen(line);
    if (len == sizeof line - 1 && line[len - 1] != '\n') {
      // Longer than any candump line: skip the rest of it.
      int c = 0;
      while ((c = std::fgetc(in_)) != EOF && c != '\n') {
      }
      ++lines_;
      ++bad_lines_;
      continue;
    }
    ++lines_;
    while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r')) line[--len] = '\0';
    if (len == 0) continue;
    protocol::LogRecord r;
    if (protocol::parse_candump_line(std::string_view(line, len), r) != protocol::Status::kOk) {
      ++bad_lines_;
      continue;
    }
    if (r.rtr || r.error_frame) {
      if (r.error_frame) error_frames_.fetch_add(1, std::memory_order_relaxed);
      ++skipped_;
      continue;
    }
    out.frame = r.frame;
    out.time_us = r.time_us;
    rx_frames_.fetch_add(1, std::memory_order_relaxed);
    return RxResult::kFrame;
  }
  if (std::ferror(in_) != 0) {
    error_ = "reading the log " + in_name_ + " failed: " + std::strerror(errno);
    return RxResult::kError;
  }
  return RxResult::kEnd;
}

}  // namespace tacse3::hal::can
