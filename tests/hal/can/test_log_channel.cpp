// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: the log channel round trip and the SocketCAN failure message.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <string>

#include "tacse3/hal/can/log_channel.hpp"
#include "tacse3/hal/can/socketcan.hpp"
#include "tacse3/protocol/protocol.hpp"

namespace can = tacse3::hal::can;
namespace tp = tacse3::protocol;

TEST(LogChannel, WritesAndReadsBackEveryFrameKind) {
  std::FILE* tmp = std::tmpfile();
  ASSERT_NE(tmp, nullptr);
  can::LogChannel writer(nullptr, tmp, "vcan0");
  std::uint64_t now = 1700000000000001ull;
  writer.set_clock([&] { return now++; });
  tp::CycleFrames classic, fd;
  tp::TxConfig tx;
  ASSERT_EQ(tp::encode_cycle(tp::Cycle{}, 1, tx, classic), tp::Status::kOk);
  tx.frame_mode = tp::FrameMode::kFd;
  tx.endpoint.layout.mode = tp::IdMode::kExtended;
  ASSERT_EQ(tp::encode_cycle(tp::Cycle{}, 2, tx, fd), tp::Status::kOk);
  for (std::size_t i = 0; i < classic.count; ++i) ASSERT_TRUE(writer.send(classic.frames[i]));
  ASSERT_TRUE(writer.send(fd.frames[0]));
  std::fputs("garbage line\n(1.0) can0 7FF#R\n", tmp);
  std::rewind(tmp);

  can::LogChannel reader(tmp, nullptr);
  can::RxFrame rx;
  for (std::size_t i = 0; i < classic.count; ++i) {
    ASSERT_EQ(reader.receive(rx, 0), can::RxResult::kFrame);
    EXPECT_EQ(rx.time_us, 1700000000000001ull + i);
    EXPECT_EQ(rx.frame.id, classic.frames[i].id);
    EXPECT_EQ(rx.frame.len, 8);
    EXPECT_EQ(rx.frame.data, classic.frames[i].data);
  }
  ASSERT_EQ(reader.receive(rx, 0), can::RxResult::kFrame);
  EXPECT_TRUE(rx.frame.fd);
  EXPECT_TRUE(rx.frame.brs);
  EXPECT_TRUE(rx.frame.extended);
  EXPECT_EQ(rx.frame.len, 64);
  EXPECT_EQ(rx.frame.data, fd.frames[0].data);
  EXPECT_EQ(reader.receive(rx, 0), can::RxResult::kEnd);
  EXPECT_EQ(reader.bad_lines(), 1u);
  EXPECT_EQ(reader.skipped_frames(), 1u);  // the remote frame
  std::fclose(tmp);
}

TEST(LogChannel, ReportsMissingFiles) {
  std::string error;
  EXPECT_EQ(can::LogChannel::open("/nonexistent/tacse3.log", "", error), nullptr);
  EXPECT_NE(error.find("cannot open log"), std::string::npos);
  can::LogChannel none(nullptr, nullptr);
  EXPECT_FALSE(none.send(tp::CanFrame{}));
  can::RxFrame rx;
  EXPECT_EQ(none.receive(rx, 0), can::RxResult::kEnd);
}

// An input log that is a directory or a device is refused at open, naming the path: /dev/zero
// would otherwise be read forever (no newline, no end). A FIFO is a live log and is accepted.
TEST(LogChannel, RefusesDirectoriesAndDevicesAsInput) {
  std::string error;
  EXPECT_EQ(can::LogChannel::open("/dev/zero", "", error), nullptr);
  EXPECT_EQ(error, "log '/dev/zero' is a device, expected a candump -L log file (or - for stdin)");
  EXPECT_EQ(can::LogChannel::open("/", "", error), nullptr);
  EXPECT_NE(error.find("log '/' is a directory"), std::string::npos) << error;
  const std::string fifo = testing::TempDir() + "tacse3-log-fifo-" + std::to_string(::getpid());
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const int writer =
      ::open(fifo.c_str(), O_RDWR);  // keeps the FIFO open: the reader's open returns
  ASSERT_GE(writer, 0);
  const char line[] = "(1.000000) can0 021#D202964900005948\n";
  ASSERT_EQ(::write(writer, line, sizeof line - 1), static_cast<ssize_t>(sizeof line - 1));
  auto ch = can::LogChannel::open(fifo, "", error);
  ASSERT_NE(ch, nullptr) << error;
  can::RxFrame rx;
  EXPECT_EQ(ch->receive(rx, 0), can::RxResult::kFrame);
  EXPECT_EQ(rx.frame.id, 0x021u);
  ::close(writer);
  ::unlink(fifo.c_str());
}

// /dev/full fails every write with ENOSPC, as a full disk does: the first failure is kept with the
// file and the cause, and nothing more is written after it.
TEST(LogChannel, ReportsAWriteErrorWithTheFileAndTheCause) {
  std::string error;
  auto ch = can::LogChannel::open("", "/dev/full", error);
  ASSERT_NE(ch, nullptr) << error;
  EXPECT_FALSE(ch->write_failed());
  EXPECT_FALSE(ch->send(tp::CanFrame{}));
  ASSERT_TRUE(ch->write_failed());
  EXPECT_EQ(ch->write_error(), "CAN log /dev/full: write failed: No space left on device");
  EXPECT_FALSE(ch->send(tp::CanFrame{}));
  EXPECT_EQ(ch->write_error(), "CAN log /dev/full: write failed: No space left on device");
  EXPECT_EQ(ch->stats().tx_errors, 2u);
  EXPECT_EQ(ch->stats().tx_frames, 0u);
}

// This host's kernel has no AF_CAN; on a CAN-capable host the interface does not exist. Either
// way open() fails with a message that says what is wrong.
TEST(SocketCan, FailsWithAClearError) {
  std::string error;
  auto ch = can::SocketCanChannel::open("tacse3nope0", can::SocketCanOptions{}, error);
  EXPECT_EQ(ch, nullptr);
  const bool no_af_can = error.find("SocketCAN is not available on this host") != std::string::npos;
  const bool no_iface = error.find("no CAN interface 'tacse3nope0'") != std::string::npos;
  EXPECT_TRUE(no_af_can || no_iface) << error;
  error.clear();
  EXPECT_EQ(can::SocketCanChannel::open("", can::SocketCanOptions{}, error), nullptr);
  EXPECT_FALSE(error.empty());
}

// A full disk, simulated with RLIMIT_FSIZE (writes past the limit fail with EFBIG once SIGXFSZ is
// ignored) in a child process: the log stops with the error and ends at a whole line, every line
// of it a candump line.
TEST(LogChannel, FullDiskLeavesWholeLines) {
  const std::string path = testing::TempDir() + "tacse3-log-full-" + std::to_string(::getpid());
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit lim{1000, 1000};
    if (::setrlimit(RLIMIT_FSIZE, &lim) != 0) ::_exit(3);
    std::string error;
    auto ch = can::LogChannel::open("", path, error);
    if (ch == nullptr) ::_exit(4);
    tp::CanFrame f{};
    f.id = 0x021;
    f.len = 8;
    for (int i = 0; i < 100; ++i) {
      if (!ch->send(f)) break;
    }
    const bool stopped = ch->write_failed() && ch->write_error().find(path) != std::string::npos;
    ::_exit(stopped ? 0 : 5);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "3 setrlimit, 4 open, 5 no write error reported";
  std::string text(2000, '\0');
  std::FILE* in = std::fopen(path.c_str(), "rb");
  ASSERT_NE(in, nullptr);
  text.resize(std::fread(text.data(), 1, text.size(), in));
  std::fclose(in);
  ::unlink(path.c_str());
  ASSERT_GT(text.size(), 500u);
  EXPECT_LE(text.size(), 1000u);
  EXPECT_EQ(text.back(), '\n');
  std::size_t lines = 0;
  for (std::size_t at = 0; at < text.size(); ++lines) {
    const std::size_t end = text.find('\n', at);
    tp::LogRecord r;
    EXPECT_EQ(tp::parse_candump_line(std::string_view(text).substr(at, end - at), r),
              tp::Status::kOk);
    at = end + 1;
  }
  EXPECT_GT(lines, 10u);
}
