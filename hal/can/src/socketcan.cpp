// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: SocketCAN raw channel with a bounded TX queue, error frames and recovery.
#include "tacse3/hal/can/socketcan.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>

namespace tacse3::hal::can {

// One queued frame, already in the kernel's layout so a retried write costs no conversion.
struct SocketCanChannel::TxSlot {
  canfd_frame frame;
  std::uint8_t mtu;  // CAN_MTU or CANFD_MTU: the write size
};

namespace {

// Messages are formatted into strings whose capacity is reserved at open, so setting an error on
// the TX path (e.g. the first ENOBUFS of a burst) never allocates.
constexpr std::size_t kErrorCapacity = 320;
constexpr std::uint32_t kMaxTxQueue = 4096;
// Error frames read per service() call: a flood (a bus with no other node answering, where every
// frame ends in an error) must not make service() unbounded.
constexpr int kMaxErrorFramesPerService = 32;

// Error classes the TX socket subscribes to. Left out on purpose: CAN_ERR_PROT, CAN_ERR_ACK and
// CAN_ERR_BUSERROR (one frame per bus error, they flood a bus without a receiver and say
// nothing about the state), CAN_ERR_LOSTARB (normal arbitration) and CAN_ERR_TRX.
constexpr can_err_mask_t kErrorMask =
    CAN_ERR_TX_TIMEOUT | CAN_ERR_CRTL | CAN_ERR_BUSOFF | CAN_ERR_RESTARTED | CAN_ERR_CNT;

void format_error(std::string& dst, const char* fmt, ...) __attribute__((format(printf, 2, 3)));
void format_error(std::string& dst, const char* fmt, ...) {
  char buf[kErrorCapacity];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  dst.assign(buf);
}

// "ENETDOWN (Network is down)": both the symbol a developer greps for and the text.
const char* errno_name(int e) {
  const char* n = strerrorname_np(e);
  return n != nullptr ? n : "E?";
}
const char* errno_text(int e) {
  const char* d = strerrordesc_np(e);
  return d != nullptr ? d : "unknown error";
}

// The interface is down or gone: nothing can be sent until it is back.
bool is_link_error(int e) {
  return e == ENETDOWN || e == ENXIO || e == ENODEV;
}

std::uint64_t realtime_us() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000u +
         static_cast<std::uint64_t>(ts.tv_nsec) / 1000u;
}

std::uint64_t relaxed_inc(std::atomic<std::uint64_t>& a, std::uint64_t n = 1) {
  // Single writer: a load + store is enough and cheaper than a locked RMW on arm.
  const std::uint64_t v = a.load(std::memory_order_relaxed) + n;
  a.store(v, std::memory_order_relaxed);
  return v;
}

}  // namespace

std::vector<SocketCanFilter> command_filters(const protocol::Endpoint& endpoint) {
  const std::uint32_t id =
      protocol::compose_id(endpoint.layout, endpoint.node_id, protocol::MessageId::kCommand);
  if (endpoint.layout.mode == protocol::IdMode::kExtended) {
    return {SocketCanFilter{(id & CAN_EFF_MASK) | CAN_EFF_FLAG,
                            CAN_EFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG}};
  }
  return {SocketCanFilter{id & CAN_SFF_MASK, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG}};
}

SocketCanChannel::SocketCanChannel(SocketOps& ops, std::string iface,
                                   const SocketCanOptions& options)
    : ops_(ops),
      iface_(std::move(iface)),
      fd_enabled_(options.fd),
      brs_(options.brs),
      filters_(options.filters),
      retry_initial_ms_(std::max<std::uint32_t>(options.retry_initial_ms, 1)),
      retry_max_ms_(
          std::max(options.retry_max_ms, std::max<std::uint32_t>(options.retry_initial_ms, 1))) {
  tx_error_.reserve(kErrorCapacity);
  rx_error_.reserve(kErrorCapacity);
}

// Create one socket on iface_: non-blocking raw socket, FD frames if configured, the role's
// filters, bound to the interface. With `require_up` an interface that is not IFF_UP fails
// with -ENETDOWN (used when probing for recovery). Returns the fd or -errno with `error` set.
int SocketCanChannel::open_socket(Role role, bool require_up, std::string& error) {
  const char* name = iface_.c_str();
  const int s = ops_.socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (s < 0) {
    const int e = -s;
    if (e == EAFNOSUPPORT || e == EPROTONOSUPPORT) {
      format_error(error,
                   "%s: SocketCAN is not available on this host: socket(PF_CAN, SOCK_RAW, "
                   "CAN_RAW) failed with %s (%s). The kernel has no CAN support loaded "
                   "(CONFIG_CAN / CONFIG_CAN_RAW; try 'modprobe can_raw'); without CAN hardware "
                   "use a candump -L log instead of an interface (tacse3d --can-log FILE|-, "
                   "tacse3-canmon --log FILE|-, tacse3-ctl --log-out FILE|-)",
                   name, errno_name(e), errno_text(e));
    } else {
      format_error(error, "%s: socket(PF_CAN, SOCK_RAW, CAN_RAW) failed: %s (%s)", name,
                   errno_name(e), errno_text(e));
    }
    return s;
  }
  auto fail = [&](int r, const char* what) {
    const int e = -r;
    format_error(error, "%s: %s failed: %s (%s)", name, what, errno_name(e), errno_text(e));
    ops_.close(s);
    return r;
  };
  const int index = ops_.if_index(s, name);
  if (index < 0) {
    const int e = -index;
    format_error(error,
                 "no CAN interface '%s': ioctl(SIOCGIFINDEX) failed with %s (%s) (check "
                 "[can].interface; 'ip -details link show %s')",
                 name, errno_name(e), errno_text(e), name);
    ops_.close(s);
    return index;
  }
  if (require_up) {
    const int flags = ops_.if_flags(s, name);
    if (flags < 0) return fail(flags, "ioctl(SIOCGIFFLAGS)");
    if ((flags & IFF_UP) == 0) {
      format_error(error, "%s: interface is down (waiting for 'ip link set %s up')", name, name);
      ops_.close(s);
      return -ENETDOWN;
    }
  }
  if (fd_enabled_) {
    const int on = 1;
    const int r = ops_.setsockopt(s, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on);
    if (r < 0) return fail(r, "setsockopt(CAN_RAW_FD_FRAMES) (interface or kernel without CAN FD)");
  }
  if (role == Role::kTx) {
    // No data frames on the TX socket (an empty filter list), only the error classes.
    int r = ops_.setsockopt(s, SOL_CAN_RAW, CAN_RAW_FILTER, nullptr, 0);
    if (r < 0) return fail(r, "setsockopt(CAN_RAW_FILTER, none)");
    const can_err_mask_t mask = kErrorMask;
    r = ops_.setsockopt(s, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &mask, sizeof mask);
    if (r < 0) return fail(r, "setsockopt(CAN_RAW_ERR_FILTER)");
  } else if (!filters_.empty()) {
    // can_filter and SocketCanFilter are both {u32 id, u32 mask}; copy to the kernel's type.
    std::vector<can_filter> f(filters_.size());
    for (std::size_t i = 0; i < f.size(); ++i) {
      f[i].can_id = filters_[i].id;
      f[i].can_mask = filters_[i].mask;
    }
    const int r = ops_.setsockopt(s, SOL_CAN_RAW, CAN_RAW_FILTER, f.data(),
                                  static_cast<socklen_t>(f.size() * sizeof(can_filter)));
    if (r < 0) return fail(r, "setsockopt(CAN_RAW_FILTER)");
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = index;
  const int r = ops_.bind(s, reinterpret_cast<const sockaddr*>(&addr), sizeof addr);
  if (r < 0) return fail(r, "bind");
  return s;
}

std::unique_ptr<SocketCanChannel> SocketCanChannel::open(const std::string& iface,
                                                         const SocketCanOptions& options,
                                                         std::string& error) {
  if (iface.empty() || iface.size() >= IFNAMSIZ) {
    error = "invalid CAN interface name '" + iface + "' (1.." + std::to_string(IFNAMSIZ - 1) +
            " characters)";
    return nullptr;
  }
  if (options.tx_queue < 1 || options.tx_queue > kMaxTxQueue) {
    error = iface + ": tx_queue " + std::to_string(options.tx_queue) + " out of range (1.." +
            std::to_string(kMaxTxQueue) + ")";
    return nullptr;
  }
  SocketOps& ops = options.ops != nullptr ? *options.ops : system_socket_ops();
  std::unique_ptr<SocketCanChannel> ch(new SocketCanChannel(ops, iface, options));
  ch->capacity_ = options.tx_queue;
  ch->ring_ = std::make_unique<TxSlot[]>(options.tx_queue);
  ch->tx_fd_ = ch->open_socket(Role::kTx, false, error);
  if (ch->tx_fd_ < 0) return nullptr;
  ch->rx_fd_ = ch->open_socket(Role::kRx, false, error);
  if (ch->rx_fd_ < 0) return nullptr;  // the destructor closes the TX socket
  // A configured interface that is not up yet (the service started before systemd-networkd
  // brought can0 up) is not an error: start in kDown and let service() pick it up.
  const int flags = ops.if_flags(ch->tx_fd_, iface.c_str());
  if (flags >= 0 && (flags & IFF_UP) == 0) ch->enter_down(ENETDOWN, "open");
  return ch;
}

SocketCanChannel::~SocketCanChannel() {
  // A last non-blocking attempt, so a one-shot tool's frame that met a full queue still goes.
  if (tx_fd_ >= 0 && count_ > 0 && state_.load(std::memory_order_relaxed) != BusState::kBusOff) {
    flush();
  }
  if (tx_fd_ >= 0) ops_.close(tx_fd_);
  if (rx_fd_ >= 0) ops_.close(rx_fd_);
}

const std::string& SocketCanChannel::last_error() const {
  return std::this_thread::get_id() == rx_thread_.load(std::memory_order_relaxed) ? rx_error_
                                                                                  : tx_error_;
}

ChannelStats SocketCanChannel::stats() const {
  ChannelStats s;
  s.tx_frames = tx_frames_.load(std::memory_order_relaxed);
  s.tx_dropped = tx_dropped_.load(std::memory_order_relaxed);
  s.tx_errors = tx_errors_.load(std::memory_order_relaxed);
  s.rx_frames = rx_frames_.load(std::memory_order_relaxed);
  s.error_frames = error_frames_.load(std::memory_order_relaxed);
  s.bus_off_events = bus_off_events_.load(std::memory_order_relaxed);
  s.restarts = restarts_.load(std::memory_order_relaxed);
  s.tx_queue_depth = depth_.load(std::memory_order_relaxed);
  s.bus_state = state_.load(std::memory_order_relaxed);
  return s;
}

SocketCanCounters SocketCanChannel::counters() const {
  SocketCanCounters c;
  c.tx_deferred = tx_deferred_.load(std::memory_order_relaxed);
  c.enobufs = enobufs_.load(std::memory_order_relaxed);
  c.gap_dropped = gap_dropped_.load(std::memory_order_relaxed);
  c.last_gap_dropped = last_gap_dropped_.load(std::memory_order_relaxed);
  c.warning_events = warning_events_.load(std::memory_order_relaxed);
  c.passive_events = passive_events_.load(std::memory_order_relaxed);
  c.down_events = down_events_.load(std::memory_order_relaxed);
  c.reopen_attempts = reopen_attempts_.load(std::memory_order_relaxed);
  c.rx_reopens = rx_reopens_.load(std::memory_order_relaxed);
  c.rx_skipped = rx_skipped_.load(std::memory_order_relaxed);
  c.tx_error_counter = tec_.load(std::memory_order_relaxed);
  c.rx_error_counter = rec_.load(std::memory_order_relaxed);
  return c;
}

// ---- sending thread -----------------------------------------------------------------------

void SocketCanChannel::set_state(BusState s) {
  const BusState old = state_.load(std::memory_order_relaxed);
  if (old == s) return;
  if (s == BusState::kErrorWarning) relaxed_inc(warning_events_);
  if (s == BusState::kErrorPassive) relaxed_inc(passive_events_);
  state_.store(s, std::memory_order_relaxed);
}

// Bus-off or down: from now on nothing is written; frames dropped from the full ring until
// recovery are "lost in the gap".
void SocketCanChannel::enter_gap(BusState s) {
  const BusState old = state_.load(std::memory_order_relaxed);
  if (old != BusState::kBusOff && old != BusState::kDown) {
    gap_start_dropped_ = tx_dropped_.load(std::memory_order_relaxed);
  }
  set_state(s);
}

void SocketCanChannel::leave_gap() {
  const std::uint64_t lost = tx_dropped_.load(std::memory_order_relaxed) - gap_start_dropped_;
  last_gap_dropped_.store(lost, std::memory_order_relaxed);
  relaxed_inc(gap_dropped_, lost);
  relaxed_inc(restarts_);
  tx_backoff_ms_ = 0;
  set_state(BusState::kErrorActive);
}

void SocketCanChannel::enter_down(int err, const char* call) {
  if (state_.load(std::memory_order_relaxed) != BusState::kDown) {
    relaxed_inc(down_events_);
    format_error(tx_error_,
                 "%s: %s: %s (%s): interface down or gone; %u frame(s) kept in the TX queue, "
                 "reopening every %u..%u ms",
                 iface_.c_str(), call, errno_name(err), errno_text(err), count_, retry_initial_ms_,
                 retry_max_ms_);
  }
  enter_gap(BusState::kDown);
  // The socket may be bound to a vanished ifindex (ENXIO/ENODEV after the device was removed):
  // a fresh socket bound by name is the one recovery that works for every cause.
  if (tx_fd_ >= 0) {
    ops_.close(tx_fd_);
    tx_fd_ = -1;
  }
  tx_backoff_ms_ = retry_initial_ms_;
  tx_next_retry_ms_ = ops_.now_ms() + retry_initial_ms_;
}

void SocketCanChannel::try_reopen_tx() {
  const std::int64_t now = ops_.now_ms();
  if (now < tx_next_retry_ms_) return;
  relaxed_inc(reopen_attempts_);
  std::string& err = tx_error_;
  const int s = open_socket(Role::kTx, true, err);
  if (s < 0) {
    tx_backoff_ms_ = std::min(tx_backoff_ms_ * 2, retry_max_ms_);
    tx_next_retry_ms_ = now + tx_backoff_ms_;
    return;
  }
  tx_fd_ = s;
  leave_gap();
  format_error(tx_error_, "%s: interface back; socket reopened, %llu frame(s) lost while down",
               iface_.c_str(),
               static_cast<unsigned long long>(last_gap_dropped_.load(std::memory_order_relaxed)));
}

void SocketCanChannel::handle_error_frame(std::uint32_t can_id, const std::uint8_t* data) {
  relaxed_inc(error_frames_);
  const BusState now = state_.load(std::memory_order_relaxed);
  if ((can_id & CAN_ERR_CNT) != 0) {
    tec_.store(data[6], std::memory_order_relaxed);
    rec_.store(data[7], std::memory_order_relaxed);
  }
  if ((can_id & CAN_ERR_BUSOFF) != 0) {
    if (now != BusState::kBusOff) {
      relaxed_inc(bus_off_events_);
      format_error(tx_error_,
                   "%s: controller bus-off (error frame CAN_ERR_BUSOFF): TX paused, %u frame(s) "
                   "queued; recovers on CAN_ERR_RESTARTED (set 'restart-ms' on the interface)",
                   iface_.c_str(), count_);
      enter_gap(BusState::kBusOff);
    }
    return;
  }
  if ((can_id & CAN_ERR_RESTARTED) != 0) {
    // The controller left bus-off (auto restart-ms or 'ip link set can0 type can restart').
    if (now == BusState::kBusOff) {
      leave_gap();
    } else {
      relaxed_inc(restarts_);
      set_state(BusState::kErrorActive);
    }
    return;
  }
  if ((can_id & CAN_ERR_CRTL) != 0) {
    const std::uint8_t c = data[1];
    if ((c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0) {
      if (now != BusState::kBusOff) set_state(BusState::kErrorPassive);
    } else if ((c & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) != 0) {
      if (now != BusState::kBusOff) set_state(BusState::kErrorWarning);
    } else if ((c & CAN_ERR_CRTL_ACTIVE) != 0) {
      if (now == BusState::kBusOff) {
        leave_gap();
      } else {
        set_state(BusState::kErrorActive);
      }
    }
  }
}

void SocketCanChannel::drain_error_frames() {
  for (int i = 0; i < kMaxErrorFramesPerService && tx_fd_ >= 0; ++i) {
    canfd_frame cf{};
    const ssize_t n = ops_.read(tx_fd_, &cf, sizeof cf);
    if (n == -EAGAIN || n == -EWOULDBLOCK) return;
    if (n == -EINTR) continue;
    if (n < 0) {
      const int e = static_cast<int>(-n);
      if (is_link_error(e)) {
        enter_down(e, "read");
      } else {
        format_error(tx_error_, "%s: read (error frames) failed: %s (%s)", iface_.c_str(),
                     errno_name(e), errno_text(e));
      }
      return;
    }
    if (n != CAN_MTU && n != CANFD_MTU) continue;
    if ((cf.can_id & CAN_ERR_FLAG) != 0) handle_error_frame(cf.can_id, cf.data);
  }
}

void SocketCanChannel::drop_head() {
  head_ = head_ + 1 == capacity_ ? 0 : head_ + 1;
  --count_;
}

// Write queued frames, oldest first, until the queue is empty or the kernel refuses for now.
void SocketCanChannel::flush() {
  // Each pass either removes the head or stops; the extra passes bound EINTR retries.
  for (std::uint32_t pass = 0; count_ > 0 && tx_fd_ >= 0 && pass < 2 * capacity_ + 2; ++pass) {
    const TxSlot& slot = ring_[head_];
    const ssize_t n = ops_.write(tx_fd_, &slot.frame, slot.mtu);
    if (n == static_cast<ssize_t>(slot.mtu)) {
      drop_head();
      relaxed_inc(tx_frames_);
      continue;
    }
    if (n == -EINTR) continue;
    if (n == -ENOBUFS || n == -EAGAIN || n == -EWOULDBLOCK) {
      // The qdisc / driver queue (ENOBUFS) or the socket buffer (EAGAIN) is full. Not an error:
      // the frame stays at the head and the next service() tries again.
      relaxed_inc(tx_deferred_);
      if (n == -ENOBUFS) relaxed_inc(enobufs_);
      break;
    }
    if (n < 0 && is_link_error(static_cast<int>(-n))) {
      enter_down(static_cast<int>(-n), "write");
      break;
    }
    // Anything else (EINVAL: FD frame on a classic-only interface, EMSGSIZE, a short write) is
    // about this frame: drop it and count it, so it cannot block the queue.
    if (n < 0) {
      const int e = static_cast<int>(-n);
      // EINVAL on a 72-byte write: the interface is classic-only (MTU 16), not the frame.
      const bool fd_on_classic = e == EINVAL && slot.mtu == CANFD_MTU;
      format_error(tx_error_, "%s: write of id 0x%X failed: %s (%s); frame dropped%s",
                   iface_.c_str(), slot.frame.can_id & CAN_EFF_MASK, errno_name(e), errno_text(e),
                   fd_on_classic ? " (CAN FD frame on an interface without FD: set 'fd on' on "
                                   "the interface or [can] mode = \"classic\")"
                                 : "");
    } else {
      format_error(tx_error_, "%s: short write (%d of %u bytes); frame dropped", iface_.c_str(),
                   static_cast<int>(n), static_cast<unsigned>(slot.mtu));
    }
    drop_head();
    relaxed_inc(tx_errors_);
  }
  depth_.store(count_, std::memory_order_relaxed);
}

bool SocketCanChannel::send(const CanFrame& f) {
  if (!protocol::is_valid_length(f.fd, f.len)) {
    relaxed_inc(tx_errors_);
    format_error(tx_error_, "%s: invalid %s frame length %u (id 0x%X)", iface_.c_str(),
                 f.fd ? "CAN FD" : "classic", static_cast<unsigned>(f.len), f.id);
    return false;
  }
  if (f.fd && !fd_enabled_) {
    relaxed_inc(tx_errors_);
    format_error(tx_error_,
                 "%s: CAN FD frame (id 0x%X) on a channel opened without FD ([can] mode)",
                 iface_.c_str(), f.id);
    return false;
  }
  if (count_ == capacity_) {
    // Full: the oldest frame goes (see the class comment for why the oldest).
    drop_head();
    relaxed_inc(tx_dropped_);
  }
  std::uint32_t tail = head_ + count_;
  if (tail >= capacity_) tail -= capacity_;
  TxSlot& slot = ring_[tail];
  std::memset(&slot.frame, 0, sizeof slot.frame);
  slot.frame.can_id = f.extended ? ((f.id & CAN_EFF_MASK) | CAN_EFF_FLAG) : (f.id & CAN_SFF_MASK);
  slot.frame.len = f.len;
  std::memcpy(slot.frame.data, f.data.data(), f.len);
  if (f.fd) {
    const bool brs = brs_ == BrsPolicy::kAlways || (brs_ == BrsPolicy::kFromFrame && f.brs);
    slot.frame.flags = brs ? CANFD_BRS : 0;
    slot.mtu = CANFD_MTU;
  } else {
    slot.mtu = CAN_MTU;  // can_frame shares canfd_frame's layout up to data[8]
  }
  ++count_;
  const BusState s = state_.load(std::memory_order_relaxed);
  if (s != BusState::kBusOff && s != BusState::kDown) {
    flush();
  } else {
    depth_.store(count_, std::memory_order_relaxed);
  }
  return true;
}

void SocketCanChannel::service() {
  drain_error_frames();
  const BusState s = state_.load(std::memory_order_relaxed);
  if (s == BusState::kDown) {
    try_reopen_tx();
    if (state_.load(std::memory_order_relaxed) == BusState::kDown) return;
    drain_error_frames();
  } else if (s == BusState::kBusOff) {
    // Nothing is written while bus-off: the driver has stopped its queue, and anything written
    // now would only fill the qdisc with stale frames. Recovery comes as an error frame.
    return;
  }
  if (state_.load(std::memory_order_relaxed) == BusState::kBusOff) return;
  flush();
}

// ---- receiving thread ---------------------------------------------------------------------

RxResult SocketCanChannel::receive(RxFrame& out, int timeout_ms) {
  rx_thread_.store(std::this_thread::get_id(), std::memory_order_relaxed);
  const std::int64_t deadline = timeout_ms < 0 ? -1 : ops_.now_ms() + timeout_ms;
  for (;;) {
    const std::int64_t now = ops_.now_ms();
    int wait = -1;
    if (deadline >= 0) {
      if (now > deadline) return RxResult::kTimeout;
      wait = static_cast<int>(deadline - now);
    }
    if (rx_fd_ < 0) {
      // The interface went away: retry with backoff, sleeping in between (never spinning).
      if (now >= rx_next_retry_ms_) {
        const int s = open_socket(Role::kRx, true, rx_error_);
        if (s >= 0) {
          rx_fd_ = s;
          rx_backoff_ms_ = 0;
          relaxed_inc(rx_reopens_);
          continue;
        }
        rx_backoff_ms_ = std::min(std::max(rx_backoff_ms_ * 2, retry_initial_ms_), retry_max_ms_);
        rx_next_retry_ms_ = now + rx_backoff_ms_;
      }
      const int until_retry = static_cast<int>(rx_next_retry_ms_ - now);
      const int sleep_ms = wait < 0 ? until_retry : std::min(wait, until_retry);
      if (deadline >= 0 && sleep_ms >= wait) {
        ops_.poll(nullptr, 0, wait);
        return RxResult::kTimeout;
      }
      ops_.poll(nullptr, 0, sleep_ms);
      continue;
    }
    pollfd p{rx_fd_, POLLIN, 0};
    const int r = ops_.poll(&p, 1, wait);
    if (r == 0) return RxResult::kTimeout;
    if (r == -EINTR) continue;
    if (r < 0) {
      format_error(rx_error_, "%s: poll failed: %s (%s)", iface_.c_str(), errno_name(-r),
                   errno_text(-r));
      return RxResult::kError;
    }
    canfd_frame cf{};
    const ssize_t n = ops_.read(rx_fd_, &cf, sizeof cf);
    if (n == -EINTR || n == -EAGAIN || n == -EWOULDBLOCK) continue;
    if (n < 0) {
      const int e = static_cast<int>(-n);
      if (is_link_error(e)) {
        format_error(rx_error_, "%s: read: %s (%s): interface down or gone; reopening",
                     iface_.c_str(), errno_name(e), errno_text(e));
        ops_.close(rx_fd_);
        rx_fd_ = -1;
        rx_backoff_ms_ = retry_initial_ms_;
        rx_next_retry_ms_ = now + retry_initial_ms_;
        continue;
      }
      format_error(rx_error_, "%s: read failed: %s (%s)", iface_.c_str(), errno_name(e),
                   errno_text(e));
      return RxResult::kError;
    }
    if (n != CAN_MTU && n != CANFD_MTU) continue;
    if ((cf.can_id & (CAN_ERR_FLAG | CAN_RTR_FLAG)) != 0) {
      relaxed_inc(rx_skipped_);
      continue;
    }
    CanFrame& f = out.frame;
    f.extended = (cf.can_id & CAN_EFF_FLAG) != 0;
    f.id = f.extended ? (cf.can_id & CAN_EFF_MASK) : (cf.can_id & CAN_SFF_MASK);
    f.fd = n == CANFD_MTU;
    f.brs = f.fd && (cf.flags & CANFD_BRS) != 0;
    f.len = f.fd ? std::min<std::uint8_t>(cf.len, CANFD_MAX_DLEN)
                 : std::min<std::uint8_t>(cf.len, CAN_MAX_DLEN);
    std::memcpy(f.data.data(), cf.data, f.len);
    std::memset(f.data.data() + f.len, 0, f.data.size() - f.len);
    out.time_us = realtime_us();
    relaxed_inc(rx_frames_);
    return RxResult::kFrame;
  }
}

}  // namespace tacse3::hal::can
