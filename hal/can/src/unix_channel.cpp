// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: candump -L over a Unix stream socket.
#include "tacse3/hal/can/unix_channel.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>

#include "tacse3/protocol/candump.hpp"

namespace tacse3::hal::can {
namespace {

// Error texts are formatted into strings reserved at open: the sending thread never allocates.
constexpr std::size_t kErrorCapacity = 320;

std::uint64_t realtime_us() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000u +
         static_cast<std::uint64_t>(ts.tv_nsec) / 1000u;
}

std::int64_t monotonic_ms() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000 + ts.tv_nsec / 1000000;
}

bool make_address(const std::string& path, sockaddr_un& addr, std::string& error) {
  addr = sockaddr_un{};
  addr.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof addr.sun_path) {
    error = std::string("CAN socket path '") + path + "' must have 1.." +
            std::to_string(sizeof addr.sun_path - 1) + " characters";
    return false;
  }
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  return true;
}

std::string errno_text(const char* what, const std::string& path, int e) {
  return std::string(what) + " '" + path + "': " + std::strerror(e);
}

// A socket file nobody listens on (a daemon that was killed) may be replaced; anything else may
// not: a live daemon's socket, or a file that is not a socket.
bool clear_stale_socket(const std::string& path, const sockaddr_un& addr, std::string& error) {
  struct stat st {};
  if (lstat(path.c_str(), &st) != 0) return true;  // nothing there
  if (!S_ISSOCK(st.st_mode)) {
    error = std::string("CAN socket path '") + path +
            "' exists and is not a socket; choose another path";
    return false;
  }
  const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (probe < 0) {
    error = errno_text("cannot create a socket for", path, errno);
    return false;
  }
  const bool live = ::connect(probe, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0;
  ::close(probe);
  if (live) {
    error = std::string("CAN socket '") + path + "' is in use: another tacse3d listens on it";
    return false;
  }
  if (::unlink(path.c_str()) != 0) {
    error = errno_text("cannot remove the stale CAN socket", path, errno);
    return false;
  }
  return true;
}

}  // namespace

UnixSocketChannel::UnixSocketChannel(std::string path, std::string iface, int listen_fd)
    : path_(std::move(path)), iface_(std::move(iface)), listen_fd_(listen_fd) {
  if (iface_.empty() || iface_.size() > 16) iface_ = "can0";
  for (Peer& p : peers_) p.out = std::make_unique<char[]>(kPeerTxBuffer);
  tx_error_.reserve(kErrorCapacity);
  rx_error_.reserve(kErrorCapacity);
}

UnixSocketChannel::~UnixSocketChannel() {
  for (Peer& p : peers_) {
    const int fd = p.fd.load(std::memory_order_relaxed);
    if (fd >= 0) ::close(fd);
  }
  if (listen_fd_ >= 0) {
    ::close(listen_fd_);
    ::unlink(path_.c_str());
  }
}

std::unique_ptr<UnixSocketChannel> UnixSocketChannel::listen(const std::string& path,
                                                             std::string& error,
                                                             std::string iface_name) {
  sockaddr_un addr{};
  if (!make_address(path, addr, error) || !clear_stale_socket(path, addr, error)) return nullptr;
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    error = errno_text("cannot create the CAN socket", path, errno);
    return nullptr;
  }
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    error = errno_text("cannot create the CAN socket", path, errno);
    ::close(fd);
    return nullptr;
  }
  if (::listen(fd, static_cast<int>(kMaxPeers)) != 0) {
    error = errno_text("cannot listen on the CAN socket", path, errno);
    ::close(fd);
    ::unlink(path.c_str());
    return nullptr;
  }
  return std::unique_ptr<UnixSocketChannel>(new UnixSocketChannel(path, std::move(iface_name), fd));
}

std::unique_ptr<UnixSocketChannel> UnixSocketChannel::connect(const std::string& path,
                                                              std::string& error,
                                                              std::string iface_name) {
  sockaddr_un addr{};
  if (!make_address(path, addr, error)) return nullptr;
  // Non-blocking from the start: a daemon whose backlog is full answers EAGAIN at once instead
  // of holding the caller past its timeout.
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    error = errno_text("cannot create a socket for", path, errno);
    return nullptr;
  }
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const int e = errno;
    ::close(fd);
    error = e == EAGAIN ? std::string("tacse3d on CAN socket '") + path +
                              "' accepts no more connections now (backlog full); try again"
            : e == ENOENT || e == ECONNREFUSED
                ? std::string("no tacse3d listens on CAN socket '") + path + "' (" +
                      std::strerror(e) + "): start it with --can-socket " + path
                : errno_text("cannot connect to the CAN socket", path, e);
    return nullptr;
  }
  std::unique_ptr<UnixSocketChannel> ch(new UnixSocketChannel(path, std::move(iface_name), -1));
  ch->attach_peer(fd);
  return ch;
}

void UnixSocketChannel::attach_peer(int fd) {
  for (Peer& p : peers_) {
    if (p.state.load(std::memory_order_acquire) != kFree) continue;
    p.in_len = 0;
    p.discarding = false;
    p.read_eof = false;
    p.fd.store(fd, std::memory_order_relaxed);
    p.state.store(kOpen, std::memory_order_release);
    accepted_.fetch_add(1, std::memory_order_relaxed);
    peer_count_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  ::close(fd);
  refused_.fetch_add(1, std::memory_order_relaxed);
}

void UnixSocketChannel::set_rx_error(const char* fmt, ...) {
  char buf[kErrorCapacity];
  va_list ap;
  va_start(ap, fmt);
  const int n = std::vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  rx_error_.assign(buf, n < 0 ? 0 : std::min<std::size_t>(n, sizeof buf - 1));
}

void UnixSocketChannel::set_tx_error(const char* fmt, ...) {
  char buf[kErrorCapacity];
  va_list ap;
  va_start(ap, fmt);
  const int n = std::vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  tx_error_.assign(buf, n < 0 ? 0 : std::min<std::size_t>(n, sizeof buf - 1));
}

const std::string& UnixSocketChannel::last_error() const {
  return std::this_thread::get_id() == rx_thread_.load(std::memory_order_relaxed) ? rx_error_
                                                                                  : tx_error_;
}

ChannelStats UnixSocketChannel::stats() const {
  ChannelStats s;
  s.tx_frames = tx_frames_.load(std::memory_order_relaxed);
  s.tx_dropped = tx_dropped_.load(std::memory_order_relaxed);
  s.tx_errors = tx_errors_.load(std::memory_order_relaxed);
  s.rx_frames = rx_frames_.load(std::memory_order_relaxed);
  s.error_frames = error_frames_.load(std::memory_order_relaxed);
  return s;
}

UnixSocketChannel::Counters UnixSocketChannel::counters() const {
  Counters c;
  c.accepted = accepted_.load(std::memory_order_relaxed);
  c.refused = refused_.load(std::memory_order_relaxed);
  c.disconnected = disconnected_.load(std::memory_order_relaxed);
  c.bad_lines = bad_lines_.load(std::memory_order_relaxed);
  c.long_lines = long_lines_.load(std::memory_order_relaxed);
  c.skipped = skipped_.load(std::memory_order_relaxed);
  c.peers = peer_count_.load(std::memory_order_relaxed);
  return c;
}

std::string UnixSocketChannel::first_bad_line() const {
  if (!have_bad_.load(std::memory_order_acquire)) return {};
  return std::string(first_bad_.data());
}

// --- sending thread ---------------------------------------------------------------------------

// Brings the sending thread's view of one peer up to date. Returns with p.tx_attached true only
// for a peer that may be written to.
void UnixSocketChannel::tx_visit(Peer& p) {
  const std::uint8_t st = p.state.load(std::memory_order_acquire);
  if (st == kOpen && !p.tx_attached) {
    p.tx_attached = true;
    p.tx_broken = false;
    p.out_head = 0;
    p.out_len = 0;
  } else if (st == kClosing) {
    p.tx_attached = false;
    p.state.store(kReleased, std::memory_order_release);
  }
}

void UnixSocketChannel::flush(Peer& p) {
  const int fd = p.fd.load(std::memory_order_relaxed);
  while (p.out_len > 0 && !p.tx_broken) {
    const std::size_t chunk = std::min(p.out_len, kPeerTxBuffer - p.out_head);
    const ssize_t n = ::send(fd, p.out.get() + p.out_head, chunk, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      p.out_head = (p.out_head + static_cast<std::size_t>(n)) % kPeerTxBuffer;
      p.out_len -= static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return;
    // EPIPE, ECONNRESET: the peer is gone; the receiving thread sees the hang-up and closes it.
    set_tx_error("CAN socket %s: write to a peer failed: %s", path_.c_str(),
                 std::strerror(n < 0 ? errno : EPIPE));
    p.tx_broken = true;
    p.out_len = 0;
  }
}

void UnixSocketChannel::enqueue(Peer& p, const char* line, std::size_t n) {
  if (p.tx_broken) return;
  if (kPeerTxBuffer - p.out_len < n) {
    flush(p);
    if (kPeerTxBuffer - p.out_len < n) {
      tx_dropped_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
  }
  std::size_t tail = (p.out_head + p.out_len) % kPeerTxBuffer;
  for (std::size_t i = 0; i < n; ++i) {
    p.out[tail] = line[i];
    tail = tail + 1 == kPeerTxBuffer ? 0 : tail + 1;
  }
  p.out_len += n;
  flush(p);
}

bool UnixSocketChannel::send(const CanFrame& f) {
  protocol::LogRecord r;
  r.time_us = realtime_us();
  std::memcpy(r.iface.data(), iface_.c_str(), iface_.size() + 1);
  r.frame = f;
  char line[protocol::kCandumpLineMax + 2];
  const std::size_t n = protocol::format_candump_line(r, line, sizeof line - 1);
  if (n == 0) {
    set_tx_error("frame cannot be written as a candump line");
    tx_errors_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  line[n] = '\n';
  for (Peer& p : peers_) {
    tx_visit(p);
    if (p.tx_attached) enqueue(p, line, n + 1);
  }
  tx_frames_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

void UnixSocketChannel::service() {
  for (Peer& p : peers_) {
    tx_visit(p);
    if (p.tx_attached) flush(p);
  }
}

// --- receiving thread -------------------------------------------------------------------------

void UnixSocketChannel::hang_up(Peer& p) {
  ::shutdown(p.fd.load(std::memory_order_relaxed), SHUT_RDWR);
  p.state.store(kClosing, std::memory_order_release);
  peer_count_.fetch_sub(1, std::memory_order_relaxed);
  disconnected_.fetch_add(1, std::memory_order_relaxed);
}

void UnixSocketChannel::reap() {
  for (Peer& p : peers_) {
    if (p.state.load(std::memory_order_acquire) != kReleased) continue;
    ::close(p.fd.load(std::memory_order_relaxed));
    p.fd.store(-1, std::memory_order_relaxed);
    p.state.store(kFree, std::memory_order_release);
  }
}

// Peers that hung up free their slot once the sending thread lets go (within one cycle); a
// connection waits in the backlog for that rather than be refused while only kMaxPeers live
// peers fill the table.
bool UnixSocketChannel::slot_coming_free() const {
  bool free = false, coming = false;
  for (const Peer& p : peers_) {
    const std::uint8_t st = p.state.load(std::memory_order_acquire);
    free = free || st == kFree;
    coming = coming || st == kClosing || st == kReleased;
  }
  return !free && coming;
}

void UnixSocketChannel::accept_peers() {
  for (;;) {
    reap();
    if (slot_coming_free()) return;
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) return;  // EAGAIN, or a connection that died before it was taken
    attach_peer(fd);
  }
}

void UnixSocketChannel::bad_line(const char* line, std::size_t n, bool oversized) {
  bad_lines_.fetch_add(1, std::memory_order_relaxed);
  if (oversized) long_lines_.fetch_add(1, std::memory_order_relaxed);
  if (have_bad_.load(std::memory_order_relaxed)) return;
  const std::size_t k = std::min(n, first_bad_.size() - 1);
  for (std::size_t i = 0; i < k; ++i) {
    const char c = line[i];
    first_bad_[i] = c >= 0x20 && c < 0x7F ? c : '?';  // the text goes into a log line
  }
  first_bad_[k] = '\0';
  have_bad_.store(true, std::memory_order_release);
}

// Reads what fits in the line buffer. false when the peer is gone (it was hung up).
bool UnixSocketChannel::read_peer(Peer& p, short revents) {
  const int fd = p.fd.load(std::memory_order_relaxed);
  if ((revents & POLLIN) != 0 && !p.read_eof) {
    const ssize_t n = ::read(fd, p.in.data() + p.in_len, p.in.size() - p.in_len);
    if (n > 0) {
      p.in_len += static_cast<std::size_t>(n);
      return true;
    }
    if (n == 0) {
      p.read_eof = true;  // half-closed: it may still read replies
    } else if (errno != EAGAIN && errno != EINTR) {
      set_rx_error("CAN socket %s: read from a peer failed: %s", path_.c_str(),
                   std::strerror(errno));
      hang_up(p);
      return false;
    }
  }
  if ((revents & (POLLHUP | POLLERR)) != 0) {
    hang_up(p);
    return false;
  }
  return true;
}

// Takes complete lines out of the buffer until one is a data frame.
bool UnixSocketChannel::next_frame(Peer& p, RxFrame& out) {
  for (;;) {
    char* nl = static_cast<char*>(std::memchr(p.in.data(), '\n', p.in_len));
    if (nl == nullptr) {
      if (p.in_len == p.in.size()) {  // no newline in kLineMax bytes: skip to the next one
        if (!p.discarding) bad_line(p.in.data(), p.in_len, true);
        p.discarding = true;
        p.in_len = 0;
      }
      return false;
    }
    const std::size_t used = static_cast<std::size_t>(nl - p.in.data()) + 1;
    std::size_t len = used - 1;
    while (len > 0 && p.in[len - 1] == '\r') --len;
    const bool skip = p.discarding;
    p.discarding = false;
    protocol::LogRecord r;
    bool got = false;
    if (!skip && len > 0) {
      if (protocol::parse_candump_line(std::string_view(p.in.data(), len), r) !=
          protocol::Status::kOk) {
        bad_line(p.in.data(), len, false);
      } else if (r.rtr || r.error_frame) {
        if (r.error_frame) error_frames_.fetch_add(1, std::memory_order_relaxed);
        skipped_.fetch_add(1, std::memory_order_relaxed);
      } else {
        got = true;
      }
    }
    std::memmove(p.in.data(), p.in.data() + used, p.in_len - used);
    p.in_len -= used;
    if (got) {
      out.frame = r.frame;
      out.time_us = realtime_us();  // when it arrived, as SocketCAN stamps it
      rx_frames_.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
  }
}

RxResult UnixSocketChannel::receive(RxFrame& out, int timeout_ms) {
  rx_thread_.store(std::this_thread::get_id(), std::memory_order_relaxed);
  const std::int64_t deadline = timeout_ms < 0 ? -1 : monotonic_ms() + timeout_ms;
  for (;;) {
    reap();
    bool any_open = false;
    for (Peer& p : peers_) {
      if (p.state.load(std::memory_order_acquire) != kOpen) continue;
      any_open = true;
      if (next_frame(p, out)) return RxResult::kFrame;
    }
    if (listen_fd_ < 0 && !any_open) return RxResult::kEnd;  // the server hung up

    std::array<pollfd, kMaxPeers + 1> fds{};
    std::array<Peer*, kMaxPeers + 1> who{};
    nfds_t n = 0;
    if (listen_fd_ >= 0 && !slot_coming_free()) fds[n++] = pollfd{listen_fd_, POLLIN, 0};
    for (Peer& p : peers_) {
      if (p.state.load(std::memory_order_acquire) != kOpen) continue;
      // A full buffer waits for next_frame to make room; after EOF only hang-ups are of interest.
      const bool want_data = !p.read_eof && p.in_len < p.in.size();
      who[n] = &p;
      fds[n++] = pollfd{p.fd.load(std::memory_order_relaxed),
                        static_cast<short>(want_data ? POLLIN : 0), 0};
    }
    int wait = -1;
    if (deadline >= 0)
      wait = static_cast<int>(std::max<std::int64_t>(0, deadline - monotonic_ms()));
    // Peers that hung up wait for the sending thread to let go: look again soon.
    for (const Peer& p : peers_) {
      const std::uint8_t st = p.state.load(std::memory_order_acquire);
      if ((st == kClosing || st == kReleased) && (wait < 0 || wait > 10)) wait = 10;
    }
    const int r = ::poll(fds.data(), n, wait);
    if (r < 0 && errno != EINTR) {
      set_rx_error("CAN socket %s: poll failed: %s", path_.c_str(), std::strerror(errno));
      return RxResult::kError;
    }
    if (r > 0) {
      // Peers first: one that hung up frees its slot before a new one asks for it.
      for (nfds_t i = 0; i < n; ++i) {
        if (fds[i].revents != 0 && who[i] != nullptr) read_peer(*who[i], fds[i].revents);
      }
      if (listen_fd_ >= 0 && fds[0].fd == listen_fd_ && fds[0].revents != 0) accept_peers();
    }
    // Also after input that held no frame: a peer writing junk must not keep the caller from
    // its timeout (the daemon checks for stop between calls). Buffered lines wait for the next
    // call.
    if (deadline >= 0 && monotonic_ms() >= deadline) return RxResult::kTimeout;
  }
}

}  // namespace tacse3::hal::can
