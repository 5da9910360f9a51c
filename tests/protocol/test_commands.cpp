// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: command validation: every rejection reason is caught, counted and NACKed.
#include <gtest/gtest.h>

#include <type_traits>
#include <vector>

#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;

namespace {

using Bytes = std::vector<std::uint8_t>;

// A command frame to node 1 from hand-written bytes 0..6; the CRC is appended.
tp::CanFrame cmd(const Bytes& b7, std::uint32_t id = 0x030) {
  tp::CanFrame f;
  f.id = id;
  f.len = 8;
  std::copy(b7.begin(), b7.end(), f.data.begin());
  f.data[7] = tp::frame_crc(f);
  return f;
}

tp::AckCode code_of(const tp::CanFrame& f) {
  return tp::validate_command(f, tp::Endpoint{}).code;
}

}  // namespace

TEST(Commands, ValidCommandsAreAccepted) {
  EXPECT_EQ(code_of(cmd({0x01, 0x01, 0, 0, 0, 0, 0xF0})), tp::AckCode::kAck);
  EXPECT_EQ(code_of(cmd({0x03, 0x01, 0x64, 0x00, 0, 0, 0})), tp::AckCode::kAck);  // 1 mm
  EXPECT_EQ(code_of(cmd({0x03, 0x01, 0xA8, 0x61, 0, 0, 0})), tp::AckCode::kAck);  // 250 mm
  EXPECT_EQ(code_of(cmd({0x05, 0x01, 120, 0, 0, 0, 0})), tp::AckCode::kAck);
  EXPECT_EQ(code_of(cmd({0x06, 0x01, 1, 0, 0, 0, 0})), tp::AckCode::kAck);
  EXPECT_EQ(code_of(cmd({0x07, 0x01, 4, 0, 0, 0, 0})), tp::AckCode::kAck);
  EXPECT_EQ(code_of(cmd({0x08, 0x01, 0, 0, 0, 0, 0})), tp::AckCode::kAck);        // recording 0
  EXPECT_EQ(code_of(cmd({0x08, 0x01, 0xFF, 0xFF, 0, 0, 0})), tp::AckCode::kAck);  // 65535
  EXPECT_EQ(code_of(cmd({0x09, 0x01, 0, 0, 0, 0, 0})), tp::AckCode::kAck);
}

TEST(Commands, UnknownCommand) {
  for (int code : {0x00, 0x0A, 0x10, 0xFF}) {
    const tp::CommandResult r = tp::validate_command(
        cmd({static_cast<std::uint8_t>(code), 0x01, 0, 0, 0, 0, 0x20}), tp::Endpoint{});
    EXPECT_TRUE(r.addressed);
    EXPECT_EQ(r.code, tp::AckCode::kUnknownCommand);
    const tp::Ack a = tp::make_ack(r);
    EXPECT_EQ(static_cast<int>(a.command), code);
    EXPECT_EQ(a.sequence, 2);
  }
}

TEST(Commands, WrongLength) {
  for (std::uint8_t len = 0; len < 8; ++len) {
    tp::CanFrame f = cmd({0x01, 0x01, 0, 0, 0, 0, 0x70});
    f.len = len;
    const tp::CommandResult r = tp::validate_command(f, tp::Endpoint{});
    EXPECT_TRUE(r.addressed);
    EXPECT_EQ(r.code, tp::AckCode::kBadLength);
    EXPECT_EQ(r.echo_code, len >= 1 ? 0x01 : 0x00);
    EXPECT_EQ(r.echo_sequence, len >= 7 ? 7 : 0);
  }
  tp::CanFrame fd = cmd({0x01, 0x01, 0, 0, 0, 0, 0});
  fd.fd = true;
  fd.len = 12;
  EXPECT_EQ(code_of(fd), tp::AckCode::kBadLength);
  // An FD frame of length 8 is a valid command (CAN FD buses).
  tp::CanFrame fd8 = cmd({0x01, 0x01, 0, 0, 0, 0, 0});
  fd8.fd = true;
  EXPECT_EQ(code_of(fd8), tp::AckCode::kAck);
}

TEST(Commands, BadCrc) {
  tp::CanFrame f = cmd({0x02, 0x01, 0, 0, 0, 0, 0});
  f.data[7] ^= 0x01;
  EXPECT_EQ(code_of(f), tp::AckCode::kBadCrc);
}

TEST(Commands, WrongNode) {
  // Payload addresses node 2 but the identifier is node 1's Command id.
  EXPECT_EQ(code_of(cmd({0x01, 0x02, 0, 0, 0, 0, 0})), tp::AckCode::kWrongNode);
  EXPECT_EQ(code_of(cmd({0x01, 0x00, 0, 0, 0, 0, 0})), tp::AckCode::kWrongNode);
  // A command for node 2 is not addressed to node 1 at all (no NACK, counted as other_node).
  tp::CommandReceiver rx{tp::Endpoint{}};
  const tp::CommandResult r = rx.receive(cmd({0x01, 0x02, 0, 0, 0, 0, 0}, 0x050));
  EXPECT_FALSE(r.addressed);
  EXPECT_EQ(rx.stats().other_node, 1u);
  EXPECT_EQ(rx.stats().rejected(), 0u);
}

TEST(Commands, ReservedBitsMustBeZero) {
  EXPECT_EQ(code_of(cmd({0x01, 0x01, 0x01, 0, 0, 0, 0})), tp::AckCode::kReservedNotZero);
  EXPECT_EQ(code_of(cmd({0x02, 0x01, 0, 0, 0, 0x80, 0})), tp::AckCode::kReservedNotZero);
  EXPECT_EQ(code_of(cmd({0x03, 0x01, 0x34, 0x21, 0x01, 0, 0})), tp::AckCode::kReservedNotZero);
  EXPECT_EQ(code_of(cmd({0x04, 0x01, 0, 0, 0, 0x01, 0})), tp::AckCode::kReservedNotZero);
  EXPECT_EQ(code_of(cmd({0x05, 0x01, 2, 1, 0, 0, 0})), tp::AckCode::kReservedNotZero);
  EXPECT_EQ(code_of(cmd({0x06, 0x01, 1, 0, 1, 0, 0})), tp::AckCode::kReservedNotZero);
  EXPECT_EQ(code_of(cmd({0x07, 0x01, 0, 0, 0, 1, 0})), tp::AckCode::kReservedNotZero);
  EXPECT_EQ(code_of(cmd({0x08, 0x01, 7, 0, 1, 0, 0})), tp::AckCode::kReservedNotZero);
  EXPECT_EQ(code_of(cmd({0x09, 0x01, 7, 0, 0, 0, 0})), tp::AckCode::kReservedNotZero);
  EXPECT_EQ(code_of(cmd({0x01, 0x01, 0, 0, 0, 0, 0x01})), tp::AckCode::kReservedNotZero);
}

TEST(Commands, OutOfRange) {
  EXPECT_EQ(code_of(cmd({0x03, 0x01, 0x63, 0x00, 0, 0, 0})), tp::AckCode::kOutOfRange);  // 0.99 mm
  EXPECT_EQ(code_of(cmd({0x03, 0x01, 0xA9, 0x61, 0, 0, 0})), tp::AckCode::kOutOfRange);  // 250.01
  EXPECT_EQ(code_of(cmd({0x04, 0x01, 2, 0, 0, 0, 0})), tp::AckCode::kOutOfRange);
  EXPECT_EQ(code_of(cmd({0x04, 0x01, 0, 3, 0, 0, 0})), tp::AckCode::kOutOfRange);
  EXPECT_EQ(code_of(cmd({0x05, 0x01, 0, 0, 0, 0, 0})), tp::AckCode::kOutOfRange);
  EXPECT_EQ(code_of(cmd({0x05, 0x01, 121, 0, 0, 0, 0})), tp::AckCode::kOutOfRange);
  EXPECT_EQ(code_of(cmd({0x06, 0x01, 2, 0, 0, 0, 0})), tp::AckCode::kOutOfRange);
  EXPECT_EQ(code_of(cmd({0x07, 0x01, 5, 0, 0, 0, 0})), tp::AckCode::kOutOfRange);
}

TEST(Commands, EncoderRefusesOutOfRangeArguments) {
  tp::CanFrame f;
  tp::Command c;
  c.code = tp::CommandCode::kSetFingerSeparation;
  c.finger_separation_m = 0.3;
  EXPECT_EQ(tp::encode(c, tp::TxConfig{}, f), tp::Status::kBadArgument);
  c.finger_separation_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(tp::encode(c, tp::TxConfig{}, f), tp::Status::kBadArgument);
  c.code = tp::CommandCode::kSetRateDivider;
  c.rate_divider = 0;
  EXPECT_EQ(tp::encode(c, tp::TxConfig{}, f), tp::Status::kBadArgument);
  c.code = static_cast<tp::CommandCode>(0x42);
  EXPECT_EQ(tp::encode(c, tp::TxConfig{}, f), tp::Status::kBadArgument);
  tp::TxConfig bad;
  bad.endpoint.node_id = 0;
  c.code = tp::CommandCode::kTare;
  EXPECT_EQ(tp::encode(c, bad, f), tp::Status::kBadArgument);
  bad.endpoint.node_id = 64;
  EXPECT_EQ(tp::encode(c, bad, f), tp::Status::kBadArgument);
}

TEST(Commands, ReceiverCountsEveryRejection) {
  tp::CommandReceiver rx{tp::Endpoint{}};
  tp::CanFrame short_frame = cmd({0x01, 0x01, 0, 0, 0, 0, 0});
  short_frame.len = 3;
  tp::CanFrame bad_crc = cmd({0x01, 0x01, 0, 0, 0, 0, 0});
  bad_crc.data[7] ^= 0x80;
  const std::vector<tp::CanFrame> frames = {
      cmd({0x01, 0x01, 0, 0, 0, 0, 0}),    // ok
      cmd({0x0A, 0x01, 0, 0, 0, 0, 0}),    // unknown
      short_frame,                         // length
      bad_crc,                             // crc
      cmd({0x01, 0x05, 0, 0, 0, 0, 0}),    // wrong node
      cmd({0x05, 0x01, 200, 0, 0, 0, 0}),  // out of range
      cmd({0x02, 0x01, 0, 0, 7, 0, 0}),    // reserved
      cmd({0x06, 0x01, 0, 0, 0, 0, 0}),    // ok
  };
  int acks = 0;
  for (const tp::CanFrame& f : frames) {
    const tp::CommandResult r = rx.receive(f);
    ASSERT_TRUE(r.addressed);
    if (r.code == tp::AckCode::kAck) ++acks;
  }
  const tp::CommandStats& s = rx.stats();
  EXPECT_EQ(acks, 2);
  EXPECT_EQ(s.accepted, 2u);
  EXPECT_EQ(s.unknown_command, 1u);
  EXPECT_EQ(s.bad_length, 1u);
  EXPECT_EQ(s.bad_crc, 1u);
  EXPECT_EQ(s.wrong_node, 1u);
  EXPECT_EQ(s.out_of_range, 1u);
  EXPECT_EQ(s.reserved_not_zero, 1u);
  EXPECT_EQ(s.rejected(), 6u);
}

namespace {

// protocol::Status and config::Status share one convention: `!s` is a failure, no bool.
static_assert(!std::is_constructible_v<bool, tacse3::protocol::Status>);
static_assert((!tacse3::protocol::Status::kOk) == false);
static_assert((!tacse3::protocol::Status::kBadCrc) == true);

}  // namespace
