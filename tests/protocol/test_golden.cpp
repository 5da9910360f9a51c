// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: hand-written golden byte vectors of every message (docs/can-protocol.md).
//
// Each vector was derived from the spec tables (bit positions, LSBs, invalid markers), not from
// the encoder: fields were placed by hand in little-endian order, and the CRC byte is CRC-8/
// SAE-J1850 over the 4-byte identifier word + bytes 0..6 (or 0..62), computed with the bitwise
// reference below. The tests check both directions: encode(values) == bytes and
// decode(bytes) == values.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <variant>
#include <vector>

#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;

namespace {

using Bytes = std::vector<std::uint8_t>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

tp::TxConfig node1() {
  return tp::TxConfig{};
}

Bytes payload(const tp::CanFrame& f) {
  return Bytes(f.data.begin(), f.data.begin() + f.len);
}

tp::CanFrame frame(std::uint32_t id, const Bytes& b, bool fd = false, bool ext = false) {
  tp::CanFrame f;
  f.id = id;
  f.extended = ext;
  f.fd = fd;
  f.brs = fd;
  f.len = static_cast<std::uint8_t>(b.size());
  std::copy(b.begin(), b.end(), f.data.begin());
  return f;
}

// Bitwise CRC-8/SAE-J1850, the textbook shift register, independent of the table-driven one.
std::uint8_t crc8_bitwise(const Bytes& bytes) {
  std::uint8_t c = 0xFF;
  for (std::uint8_t b : bytes) {
    c ^= b;
    for (int i = 0; i < 8; ++i) {
      c = (c & 0x80) != 0 ? static_cast<std::uint8_t>((c << 1) ^ 0x1D)
                          : static_cast<std::uint8_t>(c << 1);
    }
  }
  return static_cast<std::uint8_t>(c ^ 0xFF);
}

// The cycle of the classic golden vectors (docs/can-protocol.md, "Worked example").
tp::Cycle golden_cycle() {
  tp::Cycle c;
  c.timestamp_us = 1234567890;
  c.estimate_valid = true;
  c.angular = {1.234, -0.5, 30.0};
  c.linear = {5.0, -2.0, kNaN};  // x saturates at +3.2767 m/s, z is "not available"
  c.orientation = {0.5, 0.5, -0.5, 0.5};
  c.position = {0.01, -0.02, 0.5};
  return c;
}

const Bytes kTimestamp = {0xD2, 0x02, 0x96, 0x49, 0x00, 0x00, 0x59, 0x48};
const Bytes kAngular = {0xD2, 0x04, 0x0C, 0xFE, 0x30, 0x75, 0x50, 0x89};
const Bytes kLinear = {0xFF, 0x7F, 0xE0, 0xB1, 0x00, 0x80, 0x51, 0xA7};
const Bytes kOrientation = {0xD0, 0x07, 0xFA, 0xC0, 0x60, 0xE8, 0x53, 0xB6};
const Bytes kPosition = {0xF4, 0x01, 0x18, 0xFC, 0xA8, 0x61, 0x50, 0x87};

template <typename T>
const T& payload_as(const tp::Decoded& d) {
  const T* p = std::get_if<T>(&d.payload);
  EXPECT_NE(p, nullptr);
  static const T empty{};
  return p != nullptr ? *p : empty;
}

}  // namespace

TEST(Crc8, CatalogueCheckValue) {
  const std::uint8_t msg[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(tp::crc8(msg, sizeof msg), 0x4B);
  EXPECT_EQ(crc8_bitwise(Bytes(msg, msg + 9)), 0x4B);
}

TEST(Crc8, CoversIdentifierWordAndPayload) {
  // Timestamp frame of node 1: id word 0x00000021 little-endian, then bytes 0..6.
  Bytes covered = {0x21, 0x00, 0x00, 0x00};
  covered.insert(covered.end(), kTimestamp.begin(), kTimestamp.begin() + 7);
  EXPECT_EQ(crc8_bitwise(covered), kTimestamp[7]);
  EXPECT_EQ(tp::frame_crc(frame(0x021, kTimestamp)), kTimestamp[7]);
  // The same payload under another identifier has another CRC.
  EXPECT_NE(tp::frame_crc(frame(0x041, kTimestamp)), kTimestamp[7]);
  // 29-bit: bit 31 of the id word is set, so 0x1ACE0041 std/ext can never alias.
  EXPECT_EQ(tp::crc_id_word(frame(0x1ACE0041, kTimestamp, false, true)), 0x9ACE0041u);
}

TEST(Golden, ClassicCycleEncodes) {
  tp::CycleFrames out;
  ASSERT_EQ(tp::encode_cycle(golden_cycle(), 5, node1(), out), tp::Status::kOk);
  ASSERT_EQ(out.count, 5u);
  const std::uint32_t ids[] = {0x021, 0x022, 0x023, 0x024, 0x025};
  const Bytes* want[] = {&kTimestamp, &kAngular, &kLinear, &kOrientation, &kPosition};
  for (std::size_t i = 0; i < 5; ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(out.frames[i].id, ids[i]);
    EXPECT_FALSE(out.frames[i].extended);
    EXPECT_FALSE(out.frames[i].fd);
    EXPECT_EQ(payload(out.frames[i]), *want[i]);
  }
  EXPECT_TRUE(out.sent.saturated);
  EXPECT_TRUE(out.sent.linear_saturated.x);
  EXPECT_FALSE(out.sent.linear_saturated.y);
  EXPECT_DOUBLE_EQ(out.sent.linear.x, 3.2767);
  EXPECT_TRUE(std::isnan(out.sent.linear.z));
}

TEST(Golden, ClassicCycleDecodes) {
  const tp::IdLayout std_ids;
  tp::Decoded d;
  ASSERT_EQ(tp::decode(frame(0x021, kTimestamp), std_ids, d), tp::Status::kOk);
  EXPECT_EQ(d.message, tp::MessageId::kTimestamp);
  EXPECT_EQ(d.node_id, 1);
  const auto& ts = payload_as<tp::TimestampMsg>(d);
  EXPECT_EQ(ts.timestamp_us, 1234567890u);
  EXPECT_TRUE(ts.estimate_valid);
  EXPECT_FALSE(ts.single_sensor);
  EXPECT_FALSE(ts.pose_reset);
  EXPECT_TRUE(ts.saturated);
  EXPECT_EQ(ts.counter, 5);

  ASSERT_EQ(tp::decode(frame(0x022, kAngular), std_ids, d), tp::Status::kOk);
  const auto& a = payload_as<tp::AngularMsg>(d);
  EXPECT_DOUBLE_EQ(a.angular.x, 1.234);
  EXPECT_DOUBLE_EQ(a.angular.y, -0.5);
  EXPECT_DOUBLE_EQ(a.angular.z, 30.0);
  EXPECT_FALSE(a.saturated.any());

  ASSERT_EQ(tp::decode(frame(0x023, kLinear), std_ids, d), tp::Status::kOk);
  const auto& l = payload_as<tp::LinearMsg>(d);
  EXPECT_DOUBLE_EQ(l.linear.x, 3.2767);
  EXPECT_DOUBLE_EQ(l.linear.y, -2.0);
  EXPECT_TRUE(std::isnan(l.linear.z));
  EXPECT_TRUE(l.saturated.x);

  ASSERT_EQ(tp::decode(frame(0x024, kOrientation), std_ids, d), tp::Status::kOk);
  const auto& o = payload_as<tp::OrientationMsg>(d);
  EXPECT_DOUBLE_EQ(o.orientation.w, 0.5);
  EXPECT_DOUBLE_EQ(o.orientation.x, 0.5);
  EXPECT_DOUBLE_EQ(o.orientation.y, -0.5);
  EXPECT_DOUBLE_EQ(o.orientation.z, 0.5);
  EXPECT_EQ(o.counter, 5);

  ASSERT_EQ(tp::decode(frame(0x025, kPosition), std_ids, d), tp::Status::kOk);
  const auto& p = payload_as<tp::PositionMsg>(d);
  EXPECT_DOUBLE_EQ(p.position.x, 0.01);
  EXPECT_DOUBLE_EQ(p.position.y, -0.02);
  EXPECT_DOUBLE_EQ(p.position.z, 0.5);
}

TEST(Golden, CanFdCycle) {
  Bytes fd;
  for (const Bytes* b : {&kTimestamp, &kAngular, &kLinear, &kOrientation, &kPosition}) {
    fd.insert(fd.end(), b->begin(), b->begin() + 7);
  }
  fd.resize(63, 0x00);
  fd.push_back(0x08);
  ASSERT_EQ(fd.size(), 64u);

  tp::TxConfig tx;
  tx.frame_mode = tp::FrameMode::kFd;
  tp::CycleFrames out;
  ASSERT_EQ(tp::encode_cycle(golden_cycle(), 5, tx, out), tp::Status::kOk);
  ASSERT_EQ(out.count, 1u);
  EXPECT_EQ(out.frames[0].id, 0x026u);
  EXPECT_TRUE(out.frames[0].fd);
  EXPECT_TRUE(out.frames[0].brs);
  EXPECT_EQ(payload(out.frames[0]), fd);

  tp::Decoded d;
  ASSERT_EQ(tp::decode(frame(0x026, fd, true), tp::IdLayout{}, d), tp::Status::kOk);
  const auto& c = payload_as<tp::Cycle>(d);
  EXPECT_EQ(c.timestamp_us, 1234567890u);
  EXPECT_EQ(c.counter, 5);
  EXPECT_DOUBLE_EQ(c.angular.z, 30.0);
  EXPECT_DOUBLE_EQ(c.linear.x, 3.2767);
  EXPECT_TRUE(std::isnan(c.linear.z));
  EXPECT_DOUBLE_EQ(c.orientation.y, -0.5);
  EXPECT_DOUBLE_EQ(c.position.z, 0.5);

  // A classic (non-FD) frame with that id, or one with disagreeing counters, is rejected.
  EXPECT_EQ(tp::decode(frame(0x026, Bytes(kTimestamp)), tp::IdLayout{}, d), tp::Status::kBadLength);
  tp::CanFrame bf = frame(0x026, fd, true);
  bf.data[13] = 0x60;  // angular block counter 6 instead of 5
  bf.data[63] = tp::frame_crc(bf);
  EXPECT_EQ(tp::decode(bf, tp::IdLayout{}, d), tp::Status::kBadCounter);
}

TEST(Golden, ExtendedIdentifiers) {
  tp::TxConfig tx;
  tx.endpoint.node_id = 2;
  tx.endpoint.layout.mode = tp::IdMode::kExtended;
  tp::CycleFrames out;
  ASSERT_EQ(tp::encode_cycle(golden_cycle(), 5, tx, out), tp::Status::kOk);
  EXPECT_EQ(out.frames[0].id, 0x1ACE0041u);
  EXPECT_TRUE(out.frames[0].extended);
  EXPECT_EQ(payload(out.frames[0]), (Bytes{0xD2, 0x02, 0x96, 0x49, 0x00, 0x00, 0x59, 0x12}));
  tp::Decoded d;
  EXPECT_EQ(tp::decode(out.frames[0], tx.endpoint.layout, d), tp::Status::kOk);
  EXPECT_EQ(d.node_id, 2);
  // Under the standard layout a 29-bit frame is not ours.
  EXPECT_EQ(tp::decode(out.frames[0], tp::IdLayout{}, d), tp::Status::kUnknownId);
}

TEST(Golden, StatusGroup) {
  tp::StatusGroup g;
  g.status.state = tp::State::kTracking;
  g.status.health_left = tp::SensorHealth::kOk;
  g.status.health_right = tp::SensorHealth::kStale;
  g.status.contact_left = true;
  g.status.contact_right = true;
  g.status.slip_left = false;
  g.status.slip_right = true;
  g.status.stream_enabled = true;
  g.status.fusion = tp::FusionMethod::kPaper;
  g.status.velocity_mode = tp::VelocityMode::kDisplacement;
  g.status.confidence = 0.9;
  g.status.rate_divider = 2;
  g.status.fault = tp::FaultCode::kNone;
  g.status.rejected_commands = 3;
  g.contact.area_left_m2 = 0.0002;
  g.contact.area_right_m2 = kNaN;
  g.contact.confidence_left = 1.0;
  g.contact.confidence_right = 0.5;
  g.timing.dsp_time_s = 0.00325;
  g.timing.latency_p50_s = 0.0041;
  g.timing.latency_p99_s = 0.1;  // above 65.534 ms: saturates
  g.counters.dropped_left = 1;
  g.counters.dropped_right = 513;
  g.counters.can_tx_dropped = 65535;
  std::array<tp::CanFrame, 4> f;
  ASSERT_EQ(tp::encode_status_group(g, 7, node1(), f), tp::Status::kOk);
  EXPECT_EQ(f[0].id, 0x028u);
  EXPECT_EQ(payload(f[0]), (Bytes{0x42, 0xBB, 0xE1, 0x02, 0x00, 0x03, 0x70, 0x72}));
  EXPECT_EQ(f[1].id, 0x029u);
  EXPECT_EQ(payload(f[1]), (Bytes{0xD0, 0x07, 0xFF, 0xFF, 0xFA, 0x7D, 0x70, 0x87}));
  EXPECT_EQ(f[2].id, 0x02Au);
  EXPECT_EQ(payload(f[2]), (Bytes{0xB2, 0x0C, 0x04, 0x10, 0xFE, 0xFF, 0x70, 0xDD}));
  EXPECT_EQ(f[3].id, 0x02Bu);
  EXPECT_EQ(payload(f[3]), (Bytes{0x01, 0x00, 0x01, 0x02, 0xFF, 0xFF, 0x70, 0xEE}));

  tp::Decoded d;
  ASSERT_EQ(tp::decode(f[0], tp::IdLayout{}, d), tp::Status::kOk);
  const auto& s = payload_as<tp::StatusMsg>(d);
  EXPECT_EQ(s.state, tp::State::kTracking);
  EXPECT_EQ(s.health_right, tp::SensorHealth::kStale);
  EXPECT_TRUE(s.slip_right);
  EXPECT_FALSE(s.slip_left);
  EXPECT_EQ(s.fusion, tp::FusionMethod::kPaper);
  EXPECT_EQ(s.velocity_mode, tp::VelocityMode::kDisplacement);
  EXPECT_DOUBLE_EQ(s.confidence, 0.9);
  EXPECT_EQ(s.rate_divider, 2);
  EXPECT_EQ(s.rejected_commands, 3);
  EXPECT_FALSE(s.calibrated);
  EXPECT_EQ(s.counter, 7);
  ASSERT_EQ(tp::decode(f[1], tp::IdLayout{}, d), tp::Status::kOk);
  const auto& c = payload_as<tp::ContactMsg>(d);
  EXPECT_DOUBLE_EQ(c.area_left_m2, 0.0002);
  EXPECT_TRUE(std::isnan(c.area_right_m2));
  EXPECT_DOUBLE_EQ(c.confidence_left, 1.0);
  EXPECT_DOUBLE_EQ(c.confidence_right, 0.5);
  ASSERT_EQ(tp::decode(f[2], tp::IdLayout{}, d), tp::Status::kOk);
  const auto& t = payload_as<tp::TimingMsg>(d);
  EXPECT_DOUBLE_EQ(t.dsp_time_s, 0.00325);
  EXPECT_DOUBLE_EQ(t.latency_p50_s, 0.0041);
  EXPECT_DOUBLE_EQ(t.latency_p99_s, 0.065534);
  ASSERT_EQ(tp::decode(f[3], tp::IdLayout{}, d), tp::Status::kOk);
  const auto& n = payload_as<tp::CountersMsg>(d);
  EXPECT_EQ(n.dropped_left, 1);
  EXPECT_EQ(n.dropped_right, 513);
  EXPECT_EQ(n.can_tx_dropped, 65535);
}

// Calibrated is bit 48 (byte 6 bit 0, below the counter): the StatusGroup Status with it set.
TEST(Golden, StatusCalibratedFlag) {
  const Bytes clear = {0x42, 0xBB, 0xE1, 0x02, 0x00, 0x03, 0x70, 0x72};
  const Bytes set = {0x42, 0xBB, 0xE1, 0x02, 0x00, 0x03, 0x71, 0x6F};
  for (const Bytes& b : {clear, set}) {
    const bool calibrated = b[6] & 1u;
    SCOPED_TRACE(calibrated);
    tp::Decoded d;
    ASSERT_EQ(tp::decode(frame(0x028, b), tp::IdLayout{}, d), tp::Status::kOk);
    tp::StatusMsg s = payload_as<tp::StatusMsg>(d);
    EXPECT_EQ(s.calibrated, calibrated);
    EXPECT_EQ(s.state, tp::State::kTracking);
    EXPECT_EQ(s.rejected_commands, 3);
    EXPECT_EQ(s.counter, 7);
    tp::CanFrame f;
    ASSERT_EQ(tp::encode(s, node1(), f), tp::Status::kOk);
    EXPECT_EQ(payload(f), b);
  }
}

TEST(Golden, Commands) {
  struct Case {
    tp::Command cmd;
    Bytes bytes;
  };
  auto cmd = [](tp::CommandCode code, std::uint8_t seq) {
    tp::Command c;
    c.code = code;
    c.sequence = seq;
    return c;
  };
  std::vector<Case> cases;
  cases.push_back({cmd(tp::CommandCode::kTare, 3), {0x01, 0x01, 0, 0, 0, 0, 0x30, 0x5E}});
  cases.push_back({cmd(tp::CommandCode::kResetPose, 0), {0x02, 0x01, 0, 0, 0, 0, 0x00, 0xF3}});
  tp::Command sep = cmd(tp::CommandCode::kSetFingerSeparation, 1);
  sep.finger_separation_m = 0.085;
  cases.push_back({sep, {0x03, 0x01, 0x34, 0x21, 0, 0, 0x10, 0x2E}});
  tp::Command fus = cmd(tp::CommandCode::kSetFusion, 2);
  fus.fusion = tp::FusionMethod::kPaper;
  fus.velocity_mode = tp::VelocityMode::kDisplacement;
  cases.push_back({fus, {0x04, 0x01, 0x01, 0x02, 0, 0, 0x20, 0xEA}});
  tp::Command div = cmd(tp::CommandCode::kSetRateDivider, 4);
  div.rate_divider = 4;
  cases.push_back({div, {0x05, 0x01, 0x04, 0, 0, 0, 0x40, 0xDB}});
  tp::Command str = cmd(tp::CommandCode::kSetStream, 5);
  str.stream_enabled = false;
  cases.push_back({str, {0x06, 0x01, 0x00, 0, 0, 0, 0x50, 0x44}});
  tp::Command q = cmd(tp::CommandCode::kQuery, 6);
  q.query = tp::QueryItem::kStream;
  cases.push_back({q, {0x07, 0x01, 0x04, 0, 0, 0, 0x60, 0xE6}});
  tp::Command rec = cmd(tp::CommandCode::kStartRecording, 7);
  rec.recording_number = 12345;
  cases.push_back({rec, {0x08, 0x01, 0x39, 0x30, 0, 0, 0x70, 0x9F}});
  cases.push_back({cmd(tp::CommandCode::kStopRecording, 8), {0x09, 0x01, 0, 0, 0, 0, 0x80, 0xE0}});

  for (const Case& c : cases) {
    SCOPED_TRACE(tp::to_string(c.cmd.code));
    tp::CanFrame f;
    ASSERT_EQ(tp::encode(c.cmd, node1(), f), tp::Status::kOk);
    EXPECT_EQ(f.id, 0x030u);
    EXPECT_EQ(payload(f), c.bytes);
    // Gripper side: the hand-written bytes validate and decode to the same command.
    const tp::CommandResult r = tp::validate_command(frame(0x030, c.bytes), tp::Endpoint{});
    EXPECT_TRUE(r.addressed);
    EXPECT_EQ(r.code, tp::AckCode::kAck);
    EXPECT_EQ(r.command.code, c.cmd.code);
    EXPECT_EQ(r.command.sequence, c.cmd.sequence);
  }
  const tp::CommandResult r = tp::validate_command(frame(0x030, cases[2].bytes), tp::Endpoint{});
  EXPECT_DOUBLE_EQ(r.command.finger_separation_m, 0.085);
  const tp::CommandResult rr = tp::validate_command(frame(0x030, cases[7].bytes), tp::Endpoint{});
  EXPECT_EQ(rr.command.recording_number, 12345);
}

// The recording commands' answers: ACK echoes the number, the NACK reasons have their own codes.
TEST(Golden, RecordingAcks) {
  struct Case {
    Bytes bytes;
    tp::CommandCode command;
    tp::AckCode result;
  };
  const Case cases[] = {
      {{0x08, 0x00, 0x39, 0x30, 0, 0, 0x70, 0x27},
       tp::CommandCode::kStartRecording,
       tp::AckCode::kAck},
      {{0x08, 0x09, 0x39, 0x30, 0, 0, 0x70, 0x6B},
       tp::CommandCode::kStartRecording,
       tp::AckCode::kAlreadyRecording},
      {{0x09, 0x0A, 0, 0, 0, 0, 0x80, 0xDE},
       tp::CommandCode::kStopRecording,
       tp::AckCode::kNotRecording},
  };
  for (const Case& c : cases) {
    tp::Decoded d;
    ASSERT_EQ(tp::decode(frame(0x031, c.bytes), tp::IdLayout{}, d), tp::Status::kOk);
    const auto& a = payload_as<tp::Ack>(d);
    EXPECT_EQ(a.command, c.command);
    EXPECT_EQ(a.result, c.result);
    tp::CanFrame f;
    ASSERT_EQ(tp::encode(a, node1(), f), tp::Status::kOk);
    EXPECT_EQ(payload(f), c.bytes);
  }
  // The gripper's ACK to the golden START_RECORDING 12345 is the first line.
  const tp::CommandResult r =
      tp::validate_command(frame(0x030, {0x08, 0x01, 0x39, 0x30, 0, 0, 0x70, 0x9F}), {});
  ASSERT_EQ(r.code, tp::AckCode::kAck);
  tp::CanFrame f;
  ASSERT_EQ(tp::encode(tp::make_ack(r), node1(), f), tp::Status::kOk);
  EXPECT_EQ(payload(f), cases[0].bytes);
}

TEST(Golden, Acks) {
  tp::Ack ack;
  ack.command = tp::CommandCode::kTare;
  ack.sequence = 3;
  tp::CanFrame f;
  ASSERT_EQ(tp::encode(ack, node1(), f), tp::Status::kOk);
  EXPECT_EQ(f.id, 0x031u);
  EXPECT_EQ(payload(f), (Bytes{0x01, 0x00, 0, 0, 0, 0, 0x30, 0xE6}));

  // NACK of SET_RATE_DIVIDER 200 (out of range), seq 9: argument bytes echoed.
  const Bytes nack = {0x05, 0x05, 0xC8, 0, 0, 0, 0x90, 0xA6};
  tp::Decoded d;
  ASSERT_EQ(tp::decode(frame(0x031, nack), tp::IdLayout{}, d), tp::Status::kOk);
  const auto& a = payload_as<tp::Ack>(d);
  EXPECT_EQ(a.command, tp::CommandCode::kSetRateDivider);
  EXPECT_EQ(a.result, tp::AckCode::kOutOfRange);
  EXPECT_EQ(a.sequence, 9);
  EXPECT_EQ(a.data[0], 200);

  // The gripper's NACK for that command, built from the command frame, is exactly those bytes.
  const Bytes bad_div = {0x05, 0x01, 0xC8, 0, 0, 0, 0x90, 0x00};
  tp::CanFrame cf = frame(0x030, bad_div);
  cf.data[7] = tp::frame_crc(cf);
  const tp::CommandResult r = tp::validate_command(cf, tp::Endpoint{});
  EXPECT_EQ(r.code, tp::AckCode::kOutOfRange);
  ASSERT_EQ(tp::encode(tp::make_ack(r), node1(), f), tp::Status::kOk);
  EXPECT_EQ(payload(f), nack);

  // QUERY STREAM reply: enabled, divider 2, classic, 11-bit ids.
  tp::Command q;
  q.code = tp::CommandCode::kQuery;
  q.sequence = 6;
  q.query = tp::QueryItem::kStream;
  tp::QueryReply rep;
  rep.item = tp::QueryItem::kStream;
  rep.stream_enabled = true;
  rep.rate_divider = 2;
  ASSERT_EQ(tp::encode(tp::make_query_reply(q, rep), node1(), f), tp::Status::kOk);
  EXPECT_EQ(payload(f), (Bytes{0x07, 0x00, 0x04, 0x01, 0x02, 0x00, 0x60, 0xC0}));
  ASSERT_EQ(tp::decode(f, tp::IdLayout{}, d), tp::Status::kOk);
  tp::QueryReply back;
  ASSERT_EQ(tp::decode_query_reply(payload_as<tp::Ack>(d), back), tp::Status::kOk);
  EXPECT_TRUE(back.stream_enabled);
  EXPECT_EQ(back.rate_divider, 2);
  EXPECT_FALSE(back.fd_mode);
}

TEST(Golden, CandumpLines) {
  tp::LogRecord r;
  ASSERT_EQ(tp::parse_candump_line("(1700000000.123456) can0 021#D2029649000059480", r),
            tp::Status::kParseError);  // odd number of hex digits
  ASSERT_EQ(tp::parse_candump_line("(1700000000.123456) can0 021#D202964900005948", r),
            tp::Status::kOk);
  EXPECT_EQ(r.time_us, 1700000000123456u);
  EXPECT_STREQ(r.iface.data(), "can0");
  EXPECT_EQ(r.frame.id, 0x021u);
  EXPECT_EQ(payload(r.frame), kTimestamp);
  char buf[tp::kCandumpLineMax];
  ASSERT_GT(tp::format_candump_line(r, buf, sizeof buf), 0u);
  EXPECT_STREQ(buf, "(1700000000.123456) can0 021#D202964900005948");

  ASSERT_EQ(tp::parse_candump_line("(0.5) vcan0 1ACE0041#D202964900005912", r), tp::Status::kOk);
  EXPECT_TRUE(r.frame.extended);
  EXPECT_EQ(r.frame.id, 0x1ACE0041u);
  EXPECT_EQ(r.time_us, 500000u);
  ASSERT_GT(tp::format_candump_line(r, buf, sizeof buf), 0u);
  EXPECT_STREQ(buf, "(0000000000.500000) vcan0 1ACE0041#D202964900005912");

  ASSERT_EQ(tp::parse_candump_line("(1.000000) can0 026##1" + std::string(126, '0') + "08", r),
            tp::Status::kOk);
  EXPECT_TRUE(r.frame.fd);
  EXPECT_TRUE(r.frame.brs);
  EXPECT_EQ(r.frame.len, 64);
  EXPECT_EQ(r.frame.data[63], 0x08);

  ASSERT_EQ(tp::parse_candump_line("(1.000000) can0 030#R", r), tp::Status::kOk);
  EXPECT_TRUE(r.rtr);
  ASSERT_EQ(tp::parse_candump_line("(1.000000) can0 20000080#0000000000000000", r),
            tp::Status::kOk);
  EXPECT_TRUE(r.error_frame);
  EXPECT_EQ(tp::parse_candump_line("(1.000000) can0 0210#00", r), tp::Status::kParseError);
  EXPECT_EQ(tp::parse_candump_line("(1.000000) can0 021#001122334455667788", r),
            tp::Status::kParseError);  // 9 bytes classic
  EXPECT_EQ(tp::parse_candump_line("can0 021#00", r), tp::Status::kParseError);
  // Found by fuzz_candump: control characters in the interface name are rejected.
  EXPECT_EQ(tp::parse_candump_line(std::string_view("(1.0) ca\0n0 030#R8", 19), r),
            tp::Status::kParseError);
  ASSERT_EQ(tp::parse_candump_line("(1.0) can0 030#R8", r), tp::Status::kOk);
  EXPECT_EQ(r.frame.len, 8);
  ASSERT_GT(tp::format_candump_line(r, buf, sizeof buf), 0u);
  EXPECT_STREQ(buf, "(0000000001.000000) can0 030#R8");
}
