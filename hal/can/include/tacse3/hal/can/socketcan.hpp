// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: the SocketCAN raw channel: TX queue policy, error frames, bus-off and recovery.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "tacse3/hal/can/channel.hpp"
#include "tacse3/hal/can/socket_ops.hpp"
#include "tacse3/protocol/ids.hpp"

namespace tacse3::hal::can {

struct SocketCanFilter {
  std::uint32_t id = 0;    // SocketCAN can_id incl. CAN_EFF_FLAG for 29-bit ids
  std::uint32_t mask = 0;  // SocketCAN can_mask
};

// The kernel filter list that delivers exactly the command frames addressed to `endpoint`
// (its node id under its 11- or 29-bit layout): data frames only (RTR in the mask), and only
// of the layout's frame format (EFF flag in the mask).
std::vector<SocketCanFilter> command_filters(const protocol::Endpoint& endpoint);

// Bit-rate switch on sent CAN FD frames.
enum class BrsPolicy : std::uint8_t {
  kFromFrame,  // CanFrame::brs decides (the protocol encoder sets it in FD mode)
  kAlways,     // every FD frame switches to the data bit rate ([can] data_bitrate configured)
  kNever,      // never (a bus whose nodes cannot do the data bit rate)
};

struct SocketCanOptions {
  bool fd = false;                        // CAN_RAW_FD_FRAMES: send and receive FD frames
  BrsPolicy brs = BrsPolicy::kFromFrame;  // FD frames only
  std::vector<SocketCanFilter> filters;   // RX kernel filters; empty: receive everything
  std::uint32_t tx_queue = 64;            // bounded TX queue capacity, frames (1..4096)
  std::uint32_t retry_initial_ms = 100;   // first reopen attempt after the interface went down
  std::uint32_t retry_max_ms = 2000;      // backoff doubles up to this
  SocketOps* ops = nullptr;               // nullptr: system_socket_ops(); must outlive the channel
};

// Counters beyond ChannelStats, for the status frame and diagnostics. Read from any thread.
struct SocketCanCounters {
  std::uint64_t tx_deferred = 0;       // writes the kernel refused for now (ENOBUFS + EAGAIN)
  std::uint64_t enobufs = 0;           // of which ENOBUFS (qdisc / driver queue full)
  std::uint64_t gap_dropped = 0;       // frames dropped while bus-off or down (all gaps)
  std::uint64_t last_gap_dropped = 0;  // frames dropped in the most recent, finished gap
  std::uint64_t warning_events = 0;    // transitions into error-warning
  std::uint64_t passive_events = 0;    // transitions into error-passive
  std::uint64_t down_events = 0;       // interface down / gone (ENETDOWN, ENXIO, ENODEV)
  std::uint64_t reopen_attempts = 0;   // TX socket reopen attempts while down
  std::uint64_t rx_reopens = 0;        // RX socket reopened after its interface went away
  std::uint64_t rx_skipped = 0;        // remote frames (and stray error frames) not returned
  std::uint8_t tx_error_counter = 0;   // controller TEC/REC from the last CAN_ERR_CNT frame
  std::uint8_t rx_error_counter = 0;
};

// A raw SocketCAN channel (classic or FD) with two non-blocking sockets on one interface:
// - the TX socket belongs to the sending thread (send/service): it writes data frames and reads
//   only error frames (no data filter), so bus state is tracked even if nobody calls receive();
// - the RX socket belongs to the receiving thread: it carries the kernel filters.
// Each thread reopens only its own socket, so no fd is ever closed under another thread's poll.
//
// TX policy: send() appends to a bounded ring allocated at open and writes as far as the kernel
// accepts. ENOBUFS/EAGAIN leave the frame queued; a full ring drops its OLDEST frame (counted in
// tx_dropped): the controller acts on the latest state, and a fresh twist/pose is worth more
// than an old one that would also delay every frame behind it. While bus-off or down nothing is
// written (no spinning), the ring keeps the newest frames, and they go out after recovery.
class SocketCanChannel final : public Channel {
 public:
  // Open both sockets bound to `iface`. nullptr on failure with `error` set (names the
  // interface, the call, errno and the cause); when the kernel has no AF_CAN support the error
  // says so explicitly. An interface that exists but is down opens fine in state kDown and is
  // picked up when it comes up.
  static std::unique_ptr<SocketCanChannel> open(const std::string& iface,
                                                const SocketCanOptions& options,
                                                std::string& error);
  ~SocketCanChannel() override;

  bool send(const CanFrame& f) override;
  RxResult receive(RxFrame& out, int timeout_ms) override;
  // The TX side's last error, or the RX side's when called from the thread that calls receive().
  const std::string& last_error() const override;
  ChannelStats stats() const override;
  void service() override;

  const std::string& tx_error() const { return tx_error_; }  // sending thread only
  const std::string& rx_error() const { return rx_error_; }  // receiving thread only
  SocketCanCounters counters() const;
  std::uint32_t tx_queue_capacity() const { return capacity_; }
  const std::string& interface_name() const { return iface_; }
  std::uint64_t skipped_frames() const { return counters().rx_skipped; }

 private:
  struct TxSlot;
  enum class Role : std::uint8_t { kTx, kRx };

  SocketCanChannel(SocketOps& ops, std::string iface, const SocketCanOptions& options);
  int open_socket(Role role, bool require_up, std::string& error);
  void set_state(BusState s);
  void enter_gap(BusState s);
  void leave_gap();
  void enter_down(int err, const char* call);
  void try_reopen_tx();
  void drain_error_frames();
  void handle_error_frame(std::uint32_t can_id, const std::uint8_t* data);
  void flush();
  void drop_head();

  SocketOps& ops_;
  const std::string iface_;
  const bool fd_enabled_;
  const BrsPolicy brs_;
  const std::vector<SocketCanFilter> filters_;
  const std::uint32_t retry_initial_ms_;
  const std::uint32_t retry_max_ms_;

  // Sending thread.
  int tx_fd_ = -1;
  std::unique_ptr<TxSlot[]> ring_;
  std::uint32_t capacity_ = 0;
  std::uint32_t head_ = 0;
  std::uint32_t count_ = 0;
  std::int64_t tx_next_retry_ms_ = 0;
  std::uint32_t tx_backoff_ms_ = 0;
  std::uint64_t gap_start_dropped_ = 0;
  std::string tx_error_;

  // Receiving thread.
  int rx_fd_ = -1;
  std::int64_t rx_next_retry_ms_ = 0;
  std::uint32_t rx_backoff_ms_ = 0;
  std::string rx_error_;
  std::atomic<std::thread::id> rx_thread_{};

  // Written by their owning thread, read by stats()/counters() from anywhere.
  std::atomic<std::uint64_t> tx_frames_{0}, tx_dropped_{0}, tx_errors_{0}, rx_frames_{0},
      error_frames_{0}, bus_off_events_{0}, restarts_{0};
  std::atomic<std::uint64_t> tx_deferred_{0}, enobufs_{0}, gap_dropped_{0}, last_gap_dropped_{0},
      warning_events_{0}, passive_events_{0}, down_events_{0}, reopen_attempts_{0}, rx_reopens_{0},
      rx_skipped_{0};
  std::atomic<std::uint32_t> depth_{0};
  std::atomic<std::uint8_t> tec_{0}, rec_{0};
  std::atomic<BusState> state_{BusState::kErrorActive};
};

}  // namespace tacse3::hal::can
