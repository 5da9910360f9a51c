// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: candump -L over a Unix socket: frames both ways, several peers, malformed and
// oversized lines, a peer that stops reading, hangs up or half-closes, reconnects, the socket
// file's life, and a sending and a receiving thread at once.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "tacse3/hal/can/unix_channel.hpp"
#include "tacse3/protocol/candump.hpp"

namespace can = tacse3::hal::can;
namespace fs = std::filesystem;
using Channel = can::UnixSocketChannel;

namespace {

can::CanFrame frame(std::uint32_t id, std::uint8_t first) {
  can::CanFrame f;
  f.id = id;
  f.len = 2;
  f.data[0] = first;
  f.data[1] = 0xA5;
  return f;
}

// A raw client, to write what tacse3-ctl never would.
int raw_connect(const std::string& path) {
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::snprintf(a.sun_path, sizeof a.sun_path, "%s", path.c_str());
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

void write_all(int fd, const std::string& s) {
  ASSERT_EQ(::write(fd, s.data(), s.size()), static_cast<ssize_t>(s.size()));
}

// Receives until a frame arrives or `ms` pass.
can::RxResult receive_for(Channel& ch, can::RxFrame& out, int ms) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
  for (;;) {
    const can::RxResult r = ch.receive(out, 20);
    if (r != can::RxResult::kTimeout || std::chrono::steady_clock::now() >= end) return r;
  }
}

// Lets the server notice connects and hang-ups: receive() accepts and reaps, service() lets go.
void settle(Channel& server, int rounds = 10) {
  for (int i = 0; i < rounds; ++i) {
    can::RxFrame f;
    server.service();
    (void)server.receive(f, 5);
  }
}

class UnixCanChannel : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tacse3-unixcan-" + std::to_string(getpid()));
    fs::create_directories(dir_);
    path_ = (dir_ / "can.sock").string();
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
  std::string path_;
};

}  // namespace

TEST_F(UnixCanChannel, FramesGoBothWaysAsCandumpLines) {
  std::string e;
  auto server = Channel::listen(path_, e, "vcan3");
  ASSERT_NE(server, nullptr) << e;
  EXPECT_TRUE(fs::is_socket(path_));
  auto client = Channel::connect(path_, e);
  ASSERT_NE(client, nullptr) << e;
  settle(*server);
  EXPECT_EQ(server->counters().peers, 1u);

  ASSERT_TRUE(server->send(frame(0x021, 7)));
  can::RxFrame got;
  ASSERT_EQ(receive_for(*client, got, 2000), can::RxResult::kFrame);
  EXPECT_EQ(got.frame.id, 0x021u);
  EXPECT_EQ(got.frame.len, 2u);
  EXPECT_EQ(got.frame.data[0], 7u);
  EXPECT_EQ(got.frame.data[1], 0xA5u);

  ASSERT_TRUE(client->send(frame(0x030, 9)));
  ASSERT_EQ(receive_for(*server, got, 2000), can::RxResult::kFrame);
  EXPECT_EQ(got.frame.id, 0x030u);
  EXPECT_EQ(got.frame.data[0], 9u);
  EXPECT_EQ(server->stats().rx_frames, 1u);
  EXPECT_EQ(server->stats().tx_frames, 1u);

  // What a peer reads is candump -L with the server's interface name.
  const int raw = raw_connect(path_);
  ASSERT_GE(raw, 0);
  settle(*server);
  ASSERT_TRUE(server->send(frame(0x123, 1)));
  char buf[256] = {};
  const ssize_t n = ::read(raw, buf, sizeof buf - 1);
  ASSERT_GT(n, 0);
  const std::string line(buf, static_cast<std::size_t>(n));
  EXPECT_NE(line.find(" vcan3 123#01A5\n"), std::string::npos) << line;
  ::close(raw);
}

TEST_F(UnixCanChannel, EveryPeerHearsTheServerAndOneTooManyIsRefused) {
  std::string e;
  auto server = Channel::listen(path_, e);
  ASSERT_NE(server, nullptr) << e;
  std::vector<std::unique_ptr<Channel>> peers;
  for (std::size_t i = 0; i < Channel::kMaxPeers; ++i) {
    peers.push_back(Channel::connect(path_, e));
    ASSERT_NE(peers.back(), nullptr) << e;
  }
  settle(*server);
  EXPECT_EQ(server->counters().peers, Channel::kMaxPeers);
  auto extra = Channel::connect(path_, e);  // connect succeeds (backlog), then the server closes
  ASSERT_NE(extra, nullptr) << e;
  settle(*server);
  EXPECT_EQ(server->counters().refused, 1u);
  can::RxFrame got;
  EXPECT_EQ(receive_for(*extra, got, 2000), can::RxResult::kEnd);

  ASSERT_TRUE(server->send(frame(0x042, 3)));
  for (auto& p : peers) {
    ASSERT_EQ(receive_for(*p, got, 2000), can::RxResult::kFrame);
    EXPECT_EQ(got.frame.id, 0x042u);
  }
}

TEST_F(UnixCanChannel, MalformedAndOversizedLinesAreCountedAndSkipped) {
  std::string e;
  auto server = Channel::listen(path_, e);
  ASSERT_NE(server, nullptr) << e;
  const int raw = raw_connect(path_);
  ASSERT_GE(raw, 0);
  const std::string huge(5000, 'F');
  write_all(raw, "garbage\x01 line\r\n");            // not candump (control char shown as '?')
  write_all(raw, "(1.000000) can0 " + huge + "\n");  // oversized: skipped up to its newline
  write_all(raw, "\n");                              // empty: ignored, not counted
  write_all(raw, "(1.000000) can0 030#R\n");         // remote frame: skipped
  write_all(raw, "(1.000000) can0 030#0102\r\n");    // good, CRLF
  write_all(raw, "(1.000000) can0 03");              // a good line split over two writes
  can::RxFrame got;
  ASSERT_EQ(receive_for(*server, got, 2000), can::RxResult::kFrame);
  EXPECT_EQ(got.frame.id, 0x030u);
  EXPECT_EQ(got.frame.len, 2u);
  EXPECT_EQ(receive_for(*server, got, 100), can::RxResult::kTimeout);
  write_all(raw, "1#FF\n");
  ASSERT_EQ(receive_for(*server, got, 2000), can::RxResult::kFrame);
  EXPECT_EQ(got.frame.id, 0x031u);
  EXPECT_EQ(got.frame.data[0], 0xFFu);

  const Channel::Counters c = server->counters();
  EXPECT_EQ(c.bad_lines, 2u);
  EXPECT_EQ(c.long_lines, 1u);
  EXPECT_EQ(c.skipped, 1u);
  EXPECT_EQ(server->first_bad_line(), "garbage? line");
  EXPECT_EQ(server->stats().rx_frames, 2u);
  ::close(raw);
}

TEST_F(UnixCanChannel, APeerThatStopsReadingLosesFramesButNeverHalfALine) {
  std::string e;
  auto server = Channel::listen(path_, e);
  ASSERT_NE(server, nullptr) << e;
  const int raw = raw_connect(path_);
  ASSERT_GE(raw, 0);
  settle(*server);
  // Far more than the kernel's socket buffer plus the channel's: send() must not block.
  const auto start = std::chrono::steady_clock::now();
  for (std::uint32_t i = 0; i < 50000; ++i) ASSERT_TRUE(server->send(frame(0x100, i & 0xFF)));
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  const can::ChannelStats s = server->stats();
  EXPECT_EQ(s.tx_frames, 50000u);
  EXPECT_GT(s.tx_dropped, 0u);
  EXPECT_LT(s.tx_dropped, 50000u);

  // Drain: every line the peer got parses, and their count is what was not dropped.
  server->service();
  std::string text;
  char buf[65536];
  for (;;) {
    server->service();
    const ssize_t n = ::recv(raw, buf, sizeof buf, MSG_DONTWAIT);
    if (n <= 0) break;
    text.append(buf, static_cast<std::size_t>(n));
  }
  std::size_t lines = 0;
  for (std::size_t pos = 0; pos < text.size();) {
    const std::size_t nl = text.find('\n', pos);
    ASSERT_NE(nl, std::string::npos) << "a line cut in half at the end";
    tacse3::protocol::LogRecord r;
    ASSERT_EQ(tacse3::protocol::parse_candump_line(std::string_view(text).substr(pos, nl - pos), r),
              tacse3::protocol::Status::kOk);
    ++lines;
    pos = nl + 1;
  }
  EXPECT_EQ(lines + s.tx_dropped, 50000u);
  ::close(raw);
}

TEST_F(UnixCanChannel, APeerGoesAwayAndAnotherComesBack) {
  std::string e;
  auto server = Channel::listen(path_, e);
  ASSERT_NE(server, nullptr) << e;
  {
    auto client = Channel::connect(path_, e);
    ASSERT_NE(client, nullptr) << e;
    settle(*server);
    ASSERT_EQ(server->counters().peers, 1u);
  }  // hung up
  settle(*server);
  EXPECT_EQ(server->counters().peers, 0u);
  EXPECT_EQ(server->counters().disconnected, 1u);
  EXPECT_TRUE(server->send(frame(0x021, 1)));  // nobody listening: still fine

  // A peer killed mid-write: the server keeps its good lines and drops the half one.
  int raw = raw_connect(path_);
  ASSERT_GE(raw, 0);
  write_all(raw, "(1.000000) can0 030#01\n(1.000000) can0 030#0");
  ::close(raw);
  can::RxFrame got;
  ASSERT_EQ(receive_for(*server, got, 2000), can::RxResult::kFrame);
  EXPECT_EQ(got.frame.len, 1u);
  settle(*server);
  EXPECT_EQ(server->counters().peers, 0u);
  EXPECT_EQ(server->counters().disconnected, 2u);

  // A peer that shuts down its writing side still hears the replies.
  raw = raw_connect(path_);
  ASSERT_GE(raw, 0);
  write_all(raw, "(1.000000) can0 030#02\n");
  ::shutdown(raw, SHUT_WR);
  ASSERT_EQ(receive_for(*server, got, 2000), can::RxResult::kFrame);
  settle(*server);
  EXPECT_EQ(server->counters().peers, 1u);
  ASSERT_TRUE(server->send(frame(0x028, 5)));
  char buf[128] = {};
  ASSERT_GT(::read(raw, buf, sizeof buf - 1), 0);
  EXPECT_NE(std::string(buf).find("028#05A5"), std::string::npos) << buf;
  ::close(raw);

  // The client's side: the server going away ends its receive().
  auto client = Channel::connect(path_, e);
  ASSERT_NE(client, nullptr) << e;
  settle(*server);
  server.reset();
  EXPECT_FALSE(fs::exists(path_));
  EXPECT_EQ(receive_for(*client, got, 2000), can::RxResult::kEnd);
}

TEST_F(UnixCanChannel, TheSocketFileIsCheckedReplacedAndRemoved) {
  std::string e;
  // No server: the client's message says what to start.
  EXPECT_EQ(Channel::connect(path_, e), nullptr);
  EXPECT_NE(e.find("no tacse3d listens on CAN socket '" + path_ + "'"), std::string::npos) << e;
  EXPECT_NE(e.find("--can-socket " + path_), std::string::npos) << e;
  // A regular file is never replaced.
  std::ofstream(path_) << "keep me\n";
  EXPECT_EQ(Channel::listen(path_, e), nullptr);
  EXPECT_NE(e.find("exists and is not a socket"), std::string::npos) << e;
  fs::remove(path_);
  // A live server's socket is refused; a stale one (left by a killed daemon) is replaced.
  auto first = Channel::listen(path_, e);
  ASSERT_NE(first, nullptr) << e;
  EXPECT_EQ(Channel::listen(path_, e), nullptr);
  EXPECT_NE(e.find("another tacse3d listens on it"), std::string::npos) << e;
  {
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    const std::string stale = (dir_ / "stale.sock").string();
    std::snprintf(a.sun_path, sizeof a.sun_path, "%s", stale.c_str());
    ASSERT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a), 0);
    ::close(fd);  // the file stays, nobody listens
    auto replaced = Channel::listen(stale, e);
    EXPECT_NE(replaced, nullptr) << e;
  }
  EXPECT_EQ(Channel::listen(std::string(200, 'x'), e), nullptr);
  EXPECT_NE(e.find("must have 1..107 characters"), std::string::npos) << e;
  first.reset();
  EXPECT_FALSE(fs::exists(path_));
}

// The daemon's threading: one thread sends and services, another receives, while peers come and
// go. Run under TSan/ASan by the sanitizer preset.
TEST_F(UnixCanChannel, SendingAndReceivingThreadsWithPeersComingAndGoing) {
  std::string e;
  auto server = Channel::listen(path_, e);
  ASSERT_NE(server, nullptr) << e;
  std::atomic<bool> stop{false};
  std::thread tx([&] {
    std::uint32_t i = 0;
    while (!stop.load()) {
      server->send(frame(0x021, i++ & 0xFF));
      server->service();
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  });
  std::atomic<std::uint64_t> received{0};
  std::thread rx([&] {
    while (!stop.load()) {
      can::RxFrame f;
      if (server->receive(f, 10) == can::RxResult::kFrame) received.fetch_add(1);
    }
  });
  for (int round = 0; round < 30; ++round) {
    auto client = Channel::connect(path_, e);
    ASSERT_NE(client, nullptr) << e;
    ASSERT_TRUE(client->send(frame(0x030, static_cast<std::uint8_t>(round))));
    can::RxFrame f;
    ASSERT_EQ(receive_for(*client, f, 2000), can::RxResult::kFrame);  // the stream reaches it
    EXPECT_EQ(f.frame.id, 0x021u);
  }
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while ((received.load() < 30 || server->counters().peers != 0) &&
         std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  stop.store(true);
  tx.join();
  rx.join();
  EXPECT_EQ(received.load(), 30u);
  EXPECT_EQ(server->counters().accepted, 30u);
  EXPECT_EQ(server->counters().disconnected, 30u);
  EXPECT_EQ(server->counters().peers, 0u);
}

// A peer that writes junk without end must not keep receive() past its timeout: the daemon's
// receiving thread checks for stop between calls.
TEST_F(UnixCanChannel, EndlessJunkDoesNotHoldReceivePastItsTimeout) {
  std::string e;
  auto server = Channel::listen(path_, e);
  ASSERT_NE(server, nullptr) << e;
  const int raw = raw_connect(path_);
  ASSERT_GE(raw, 0);
  std::atomic<bool> stop{false};
  std::thread flood([&] {
    const std::string junk(4096, 'x');
    while (!stop.load()) {
      if (::send(raw, junk.data(), junk.size(), MSG_NOSIGNAL) < 0) break;
    }
  });
  can::RxFrame f;
  for (int i = 0; i < 5; ++i) {
    const auto start = std::chrono::steady_clock::now();
    EXPECT_EQ(server->receive(f, 50), can::RxResult::kTimeout);
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(1000));
  }
  EXPECT_EQ(server->counters().long_lines, 1u);  // one endless line: counted once
  stop.store(true);
  ::shutdown(raw, SHUT_RDWR);
  flood.join();
  ::close(raw);
}
