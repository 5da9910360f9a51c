// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: writes a deterministic candump -L log with the encoder and the expected decode.
//
// The scenario: node 1 streams classic frames for 2 s (a rotation about z with a wobble, status
// every 100 ms with state changes, some "not available" fields, a saturated burst), node 2
// streams CAN FD cycle frames for 1 s, a controller sends a TARE to node 1 which ACKs it, and a
// foreign device (id 0x00A) sends a frame every 100 ms. Faults injected into node 1: a corrupted
// CRC (cycle 50), a truncated cycle (cycle 100 without PosePosition), a lost cycle (150) and a
// repeated cycle (200). The expected decode (--truth) lists every cycle a correct decoder must
// emit, as JSON lines in tacse3-canmon's format.
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>

#include "tacse3/hal/can/log_channel.hpp"
#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::uint64_t kStartUs = 1700000000000000ull;
constexpr std::uint64_t kPeriodUs = 8333;
constexpr std::uint64_t kFrameGapUs = 270;  // one 8-byte frame at 500 kbit/s

std::string num(double v, int dec) {
  if (std::isnan(v)) return "null";
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", dec, v);
  std::string s = b;
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

void truth_line(std::FILE* f, unsigned node, const tp::Cycle& c) {
  std::fprintf(
      f,
      "{\"type\":\"cycle\",\"node\":%u,\"counter\":%u,\"t_us\":%" PRIu64
      ",\"valid\":%s,\"single_sensor\":%s,\"pose_reset\":%s,\"saturated\":%s,"
      "\"wx\":%s,\"wy\":%s,\"wz\":%s,\"vx\":%s,\"vy\":%s,\"vz\":%s,\"qw\":%s,\"qx\":%s,"
      "\"qy\":%s,\"qz\":%s,\"px\":%s,\"py\":%s,\"pz\":%s}\n",
      node, unsigned{c.counter}, c.timestamp_us, c.estimate_valid ? "true" : "false",
      c.single_sensor ? "true" : "false", c.pose_reset ? "true" : "false",
      c.saturated ? "true" : "false", num(c.angular.x, 3).c_str(), num(c.angular.y, 3).c_str(),
      num(c.angular.z, 3).c_str(), num(c.linear.x, 4).c_str(), num(c.linear.y, 4).c_str(),
      num(c.linear.z, 4).c_str(), num(c.orientation.w, 5).c_str(), num(c.orientation.x, 5).c_str(),
      num(c.orientation.y, 5).c_str(), num(c.orientation.z, 5).c_str(),
      num(c.position.x, 5).c_str(), num(c.position.y, 5).c_str(), num(c.position.z, 5).c_str());
}

tp::Cycle scenario_cycle(int k, unsigned node) {
  const double t = static_cast<double>(k) / 120.0;
  tp::Cycle c;
  c.timestamp_us = 5000000 + static_cast<std::uint64_t>(k) * kPeriodUs + node * 17;
  c.estimate_valid = k >= 12;
  c.single_sensor = k >= 180 && k < 190;
  c.pose_reset = k == 120;
  const double wz = 0.5 + 0.2 * std::sin(2.0 * M_PI * 1.5 * t);
  c.angular = {0.05 * std::sin(2.0 * M_PI * t), -0.03 * std::cos(2.0 * M_PI * t), wz};
  if (k >= 60 && k < 64) c.angular.x = 40.0;  // saturated burst
  c.linear = {0.002 * std::sin(2.0 * M_PI * 0.5 * t), 0.001, (k % 30 == 0) ? kNaN : 0.0};
  const double angle = 0.5 * t + 0.2 / (2.0 * M_PI * 1.5) * (1.0 - std::cos(2.0 * M_PI * 1.5 * t));
  c.orientation = {std::cos(angle / 2), 0.0, 0.0, std::sin(angle / 2)};
  if (k < 12) c.orientation = {kNaN, kNaN, kNaN, kNaN};
  c.position = {0.0005 * std::sin(2.0 * M_PI * 0.5 * t), -0.0002 * t, 0.0};
  return c;
}

tp::StatusGroup scenario_status(int k) {
  tp::StatusGroup g;
  g.status.state =
      k < 6 ? tp::State::kBooting : (k < 12 ? tp::State::kNoContact : tp::State::kTracking);
  if (k >= 180 && k < 190) g.status.state = tp::State::kDegradedSingleSensor;
  g.status.health_left = tp::SensorHealth::kOk;
  g.status.health_right = (k >= 180 && k < 190) ? tp::SensorHealth::kLost : tp::SensorHealth::kOk;
  g.status.contact_left = k >= 12;
  g.status.contact_right = k >= 12 && !(k >= 180 && k < 190);
  g.status.slip_left = k >= 96 && k < 108;
  g.status.confidence = k < 12 ? kNaN : 0.5 + 0.002 * (k % 200);
  g.status.rejected_commands = 0;
  g.status.calibrated = k >= 6;  // both values of the flag in the log
  g.contact.area_left_m2 = k < 12 ? 0.0 : 0.00012 + 1e-7 * k;
  g.contact.area_right_m2 = k < 12 ? 0.0 : 0.00011;
  g.contact.confidence_left = 0.8;
  g.contact.confidence_right = k >= 180 && k < 190 ? kNaN : 0.75;
  g.timing.dsp_time_s = 0.0031 + 1e-6 * (k % 7);
  g.timing.latency_p50_s = 0.0042;
  g.timing.latency_p99_s = 0.0061;
  g.counters.dropped_left = static_cast<std::uint16_t>(k / 100);
  g.counters.dropped_right = static_cast<std::uint16_t>(k >= 190 ? 3 : 0);
  return g;
}

}  // namespace

int main(int argc, char** argv) {
  std::string log_path, truth_path;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--log") == 0) log_path = argv[i + 1];
    if (std::strcmp(argv[i], "--truth") == 0) truth_path = argv[i + 1];
  }
  if (log_path.empty() || truth_path.empty()) {
    std::fprintf(stderr, "usage: %s --log FILE --truth FILE\n", argv[0]);
    return 2;
  }
  std::string error;
  auto log = tacse3::hal::can::LogChannel::open("", log_path, error);
  std::FILE* truth = std::fopen(truth_path.c_str(), "w");
  if (!log || truth == nullptr) {
    std::fprintf(stderr, "make_log: cannot write: %s\n", error.c_str());
    return 1;
  }
  std::uint64_t now = kStartUs;
  log->set_clock([&now] { return now; });
  auto send = [&](const tp::CanFrame& f) {
    if (!log->send(f)) std::fprintf(stderr, "make_log: %s\n", log->last_error().c_str());
    now += kFrameGapUs;
  };

  tp::TxConfig n1;  // node 1, classic, 11-bit
  tp::TxConfig n2;
  n2.endpoint.node_id = 2;
  n2.frame_mode = tp::FrameMode::kFd;
  std::uint8_t counter1 = 0, counter2 = 0, status_counter = 0;
  for (int k = 0; k < 240; ++k) {
    now = kStartUs + static_cast<std::uint64_t>(k) * kPeriodUs;
    // node 1 cycle with faults
    tp::CycleFrames f1;
    tp::encode_cycle(scenario_cycle(k, 1), counter1, n1, f1);
    bool emitted = true;
    if (k == 50) {
      f1.frames[2].data[3] ^= 0x04;  // corrupted in transit: CRC no longer matches
      emitted = false;
    }
    if (k == 100) {
      f1.count = 4;  // PosePosition never sent
      emitted = false;
    }
    if (k != 150) {
      for (std::size_t i = 0; i < f1.count; ++i) send(f1.frames[i]);
      if (k == 200) {
        for (std::size_t i = 0; i < f1.count; ++i) send(f1.frames[i]);  // repeated cycle
      }
    } else {
      emitted = false;  // lost
    }
    if (emitted) truth_line(truth, 1, f1.sent);
    counter1 = static_cast<std::uint8_t>((counter1 + 1) & 15);
    // node 2: CAN FD, first second only
    if (k < 120) {
      tp::CycleFrames f2;
      tp::encode_cycle(scenario_cycle(k, 2), counter2, n2, f2);
      send(f2.frames[0]);
      truth_line(truth, 2, f2.sent);
      counter2 = static_cast<std::uint8_t>((counter2 + 1) & 15);
    }
    // node 1 status: 10 Hz group, plus an immediate Status when the state changes
    const bool periodic = k % 12 == 0;
    const bool changed = k == 6 || k == 180 || k == 190;
    if (periodic) {
      std::array<tp::CanFrame, 4> st;
      tp::encode_status_group(scenario_status(k), status_counter, n1, st);
      for (const auto& f : st) send(f);
      status_counter = static_cast<std::uint8_t>((status_counter + 1) & 15);
    } else if (changed) {
      tp::StatusMsg s = scenario_status(k).status;
      s.counter = status_counter;
      tp::CanFrame f;
      tp::encode(s, n1, f);
      send(f);
      status_counter = static_cast<std::uint8_t>((status_counter + 1) & 15);
    }
    // controller: TARE to node 1 at cycle 30, ACK one cycle later
    if (k == 30) {
      tp::Command tare;
      tare.code = tp::CommandCode::kTare;
      tare.sequence = 3;
      tp::CanFrame f;
      tp::encode(tare, n1, f);
      send(f);
    }
    if (k == 31) {
      tp::Ack a;
      a.command = tp::CommandCode::kTare;
      a.sequence = 3;
      tp::CanFrame f;
      tp::encode(a, n1, f);
      send(f);
    }
    // another device on the bus every 100 ms, at an identifier outside every tacse3 node's range
    if (k % 12 == 5) {
      tp::CanFrame f;
      f.id = 0x00A;
      f.len = 1;
      f.data[0] = 0x05;
      send(f);
    }
  }
  std::fclose(truth);
  return 0;
}
