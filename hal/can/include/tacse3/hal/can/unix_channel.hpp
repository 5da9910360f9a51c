// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: candump -L lines both ways over a Unix stream socket (commands on a host
// without CAN).
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "tacse3/hal/can/channel.hpp"

namespace tacse3::hal::can {

// A bus made of one Unix stream socket: the daemon listens on a path, peers (tacse3-ctl, a
// monitor, socat) connect. Every frame sent goes to every connected peer as a `candump -L` line;
// every line a peer writes is parsed and returned by receive(). Peers do not hear each other.
//
// The sending side never blocks and never allocates after open: each peer has a fixed output
// buffer; a frame that does not fit is dropped for that peer (tx_dropped), so a slow or stuck
// peer never holds up the sender and never gets a line cut in half. The receiving side owns the
// peers' lifetimes: it accepts, reads, and closes a peer that hung up, once the sending thread
// has let go of its descriptor.
class UnixSocketChannel final : public Channel {
 public:
  static constexpr std::size_t kMaxPeers = 8;
  // Longest accepted input line, newline included. A candump -L line is at most
  // protocol::kCandumpLineMax characters; a longer one is discarded up to its newline.
  static constexpr std::size_t kLineMax = 256;
  static constexpr std::size_t kPeerTxBuffer = 16384;  // per peer, ~90 classic frames

  // Server: create the socket at `path` and listen. A stale socket file (nobody listening) is
  // replaced; a live one, or a path that is not a socket, is an error. The file is removed when
  // the channel is destroyed.
  static std::unique_ptr<UnixSocketChannel> listen(const std::string& path, std::string& error,
                                                   std::string iface_name = "can0");
  // Client: connect to a listening channel. receive() returns kEnd once the server hangs up.
  static std::unique_ptr<UnixSocketChannel> connect(const std::string& path, std::string& error,
                                                    std::string iface_name = "can0");
  ~UnixSocketChannel() override;

  bool send(const CanFrame& f) override;
  RxResult receive(RxFrame& out, int timeout_ms) override;
  const std::string& last_error() const override;
  // tx_frames: frames formatted and offered to the peers (also with no peer connected);
  // tx_dropped: frame copies dropped because a peer's buffer was full; tx_errors: invalid
  // frames; rx_frames: frames parsed from peers; error_frames: error frames peers wrote.
  ChannelStats stats() const override;
  // Flushes the peers' buffers and lets go of peers that hung up. Sending thread.
  void service() override;

  struct Counters {
    std::uint64_t accepted = 0;      // peers connected
    std::uint64_t refused = 0;       // connections closed at once: kMaxPeers already connected
    std::uint64_t disconnected = 0;  // peers that hung up (or failed)
    std::uint64_t bad_lines = 0;     // input lines that are not candump -L (oversized included)
    std::uint64_t long_lines = 0;    // of those, longer than kLineMax
    std::uint64_t skipped = 0;       // remote and error frames read
    std::uint32_t peers = 0;         // connected now
  };
  Counters counters() const;  // any thread
  // The first bad input line (cut to 80 characters), for a message logged once; empty until
  // there is one. Any thread.
  std::string first_bad_line() const;
  const std::string& path() const noexcept { return path_; }
  bool is_server() const noexcept { return listen_fd_ >= 0; }

 private:
  enum PeerState : std::uint8_t { kFree, kOpen, kClosing, kReleased };
  struct Peer {
    std::atomic<int> fd{-1};
    // kFree -> kOpen (receiving thread: accepted) -> kClosing (receiving: hung up, fd shut
    // down) -> kReleased (sending thread: it will not touch fd again) -> kFree (receiving:
    // closed). So the fd is never closed while the other thread may write to it.
    std::atomic<std::uint8_t> state{kFree};
    // Receiving thread only.
    std::array<char, kLineMax> in{};
    std::size_t in_len = 0;
    bool discarding = false;  // inside an oversized line, up to its newline
    bool read_eof = false;    // the peer shut down its writing side; it may still read
    // Sending thread only.
    std::unique_ptr<char[]> out;
    std::size_t out_head = 0;
    std::size_t out_len = 0;
    bool tx_attached = false;  // the sending thread has seen this connection (kOpen)
    bool tx_broken = false;    // a write failed for good (EPIPE): write nothing more
  };

  UnixSocketChannel(std::string path, std::string iface, int listen_fd);
  void attach_peer(int fd);
  void tx_visit(Peer& p);
  void flush(Peer& p);
  void enqueue(Peer& p, const char* line, std::size_t n);
  void reap();
  bool slot_coming_free() const;
  void accept_peers();
  void hang_up(Peer& p);
  bool read_peer(Peer& p, short revents);
  bool next_frame(Peer& p, RxFrame& out);
  void bad_line(const char* line, std::size_t n, bool oversized);
  void set_rx_error(const char* fmt, ...) __attribute__((format(printf, 2, 3)));
  void set_tx_error(const char* fmt, ...) __attribute__((format(printf, 2, 3)));

  std::string path_;
  std::string iface_;
  int listen_fd_ = -1;
  std::array<Peer, kMaxPeers> peers_;
  std::atomic<std::thread::id> rx_thread_{};
  std::string tx_error_;
  std::string rx_error_;
  std::array<char, 81> first_bad_{};
  std::atomic<bool> have_bad_{false};
  std::atomic<std::uint64_t> tx_frames_{0}, tx_dropped_{0}, tx_errors_{0}, rx_frames_{0},
      error_frames_{0};
  std::atomic<std::uint64_t> accepted_{0}, refused_{0}, disconnected_{0}, bad_lines_{0},
      long_lines_{0}, skipped_{0};
  std::atomic<std::uint32_t> peer_count_{0};
};

}  // namespace tacse3::hal::can
