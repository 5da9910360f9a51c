// SPDX-License-Identifier: Apache-2.0
// tacse3 python tests: frames written and read by the C++ codec, as JSON lines, for the Python
// package to reproduce byte for byte and value for value (test_cxx_vectors.py).
//
// Each line is one case: the encoder's input, the frames the C++ encoder wrote (or "rejected"
// for a command it refuses) and what the C++ decoder reads from every frame. Cases: the worked
// example of docs/can-protocol.md, random cycles and status groups over and beyond the field
// ranges (classic / CAN FD, 11 / 29-bit), every command with valid and out-of-range arguments,
// ACKs, NACKs and query replies, and random payloads with a valid CRC under every message id.
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}
std::string boolean(bool b) {
  return b ? "true" : "false";
}
template <typename E>
std::string name(E e) {
  const char* s = tp::to_string(e);
  return s != nullptr ? "\"" + std::string(s) + "\"" : std::to_string(static_cast<unsigned>(e));
}
std::string vec(const tp::Vec3& v) {
  return "[" + num(v.x) + "," + num(v.y) + "," + num(v.z) + "]";
}
std::string sat(const tp::Saturation& s) {
  return "[" + boolean(s.x) + "," + boolean(s.y) + "," + boolean(s.z) + "]";
}
std::string quat(const tp::Quaternion& q) {
  return "[" + num(q.w) + "," + num(q.x) + "," + num(q.y) + "," + num(q.z) + "]";
}
std::string bytes(const std::uint8_t* d, std::size_t n) {
  std::string s = "\"";
  char b[3];
  for (std::size_t i = 0; i < n; ++i) {
    std::snprintf(b, sizeof b, "%02X", d[i]);
    s += b;
  }
  return s + "\"";
}
std::string frame_json(const tp::CanFrame& f) {
  return "{\"id\":" + std::to_string(f.id) + ",\"extended\":" + boolean(f.extended) +
         ",\"fd\":" + boolean(f.fd) + ",\"brs\":" + boolean(f.brs) +
         ",\"data\":" + bytes(f.data.data(), f.len) + "}";
}

std::string cycle_json(const tp::Cycle& c) {
  return "{\"t_us\":" + std::to_string(c.timestamp_us) + ",\"valid\":" + boolean(c.estimate_valid) +
         ",\"single_sensor\":" + boolean(c.single_sensor) +
         ",\"pose_reset\":" + boolean(c.pose_reset) + ",\"saturated\":" + boolean(c.saturated) +
         ",\"counter\":" + std::to_string(c.counter) + ",\"w\":" + vec(c.angular) +
         ",\"v\":" + vec(c.linear) + ",\"q\":" + quat(c.orientation) + ",\"p\":" + vec(c.position) +
         ",\"sat_w\":" + sat(c.angular_saturated) + ",\"sat_v\":" + sat(c.linear_saturated) +
         ",\"sat_p\":" + sat(c.position_saturated) + "}";
}

// The C++ decoder's reading of one frame: {"status": "...", "node", "message", "value": {...}}.
struct PayloadJson {
  std::string operator()(const tp::TimestampMsg& m) const {
    return "{\"t_us\":" + std::to_string(m.timestamp_us) +
           ",\"valid\":" + boolean(m.estimate_valid) +
           ",\"single_sensor\":" + boolean(m.single_sensor) +
           ",\"pose_reset\":" + boolean(m.pose_reset) + ",\"saturated\":" + boolean(m.saturated) +
           ",\"counter\":" + std::to_string(m.counter) + "}";
  }
  std::string operator()(const tp::AngularMsg& m) const {
    return v3(m.angular, m.saturated, m.counter);
  }
  std::string operator()(const tp::LinearMsg& m) const {
    return v3(m.linear, m.saturated, m.counter);
  }
  std::string operator()(const tp::PositionMsg& m) const {
    return v3(m.position, m.saturated, m.counter);
  }
  std::string operator()(const tp::OrientationMsg& m) const {
    return "{\"q\":" + quat(m.orientation) + ",\"counter\":" + std::to_string(m.counter) + "}";
  }
  std::string operator()(const tp::Cycle& c) const { return cycle_json(c); }
  std::string operator()(const tp::StatusMsg& m) const {
    return "{\"counter\":" + std::to_string(m.counter) + ",\"state\":" + name(m.state) +
           ",\"health_left\":" + name(m.health_left) + ",\"health_right\":" + name(m.health_right) +
           ",\"contact_left\":" + boolean(m.contact_left) +
           ",\"contact_right\":" + boolean(m.contact_right) +
           ",\"slip_left\":" + boolean(m.slip_left) + ",\"slip_right\":" + boolean(m.slip_right) +
           ",\"stream_enabled\":" + boolean(m.stream_enabled) + ",\"fusion\":" + name(m.fusion) +
           ",\"velocity_mode\":" + name(m.velocity_mode) + ",\"confidence\":" + num(m.confidence) +
           ",\"rate_divider\":" + std::to_string(m.rate_divider) + ",\"fault\":" + name(m.fault) +
           ",\"rejected_commands\":" + std::to_string(m.rejected_commands) +
           ",\"calibrated\":" + boolean(m.calibrated) + "}";
  }
  std::string operator()(const tp::ContactMsg& m) const {
    return "{\"counter\":" + std::to_string(m.counter) + ",\"area_left\":" + num(m.area_left_m2) +
           ",\"area_right\":" + num(m.area_right_m2) +
           ",\"confidence_left\":" + num(m.confidence_left) +
           ",\"confidence_right\":" + num(m.confidence_right) + "}";
  }
  std::string operator()(const tp::TimingMsg& m) const {
    return "{\"counter\":" + std::to_string(m.counter) + ",\"dsp_time\":" + num(m.dsp_time_s) +
           ",\"latency_p50\":" + num(m.latency_p50_s) + ",\"latency_p99\":" + num(m.latency_p99_s) +
           "}";
  }
  std::string operator()(const tp::CountersMsg& m) const {
    return "{\"counter\":" + std::to_string(m.counter) +
           ",\"dropped_left\":" + std::to_string(m.dropped_left) +
           ",\"dropped_right\":" + std::to_string(m.dropped_right) +
           ",\"can_tx_dropped\":" + std::to_string(m.can_tx_dropped) + "}";
  }
  std::string operator()(const tp::Command& c) const {
    std::string a;
    switch (c.code) {
      case tp::CommandCode::kSetFingerSeparation:
        a = "\"FingerSeparation\":" + num(c.finger_separation_m);
        break;
      case tp::CommandCode::kSetFusion:
        a = "\"FusionMethod\":" + name(c.fusion) + ",\"VelocityMode\":" + name(c.velocity_mode);
        break;
      case tp::CommandCode::kSetRateDivider:
        a = "\"RateDivider\":" + std::to_string(c.rate_divider);
        break;
      case tp::CommandCode::kSetStream:
        a = "\"StreamEnable\":" + std::to_string(c.stream_enabled ? 1 : 0);
        break;
      case tp::CommandCode::kQuery:
        a = "\"QueryItem\":" + name(c.query);
        break;
      case tp::CommandCode::kStartRecording:
        a = "\"RecordingNumber\":" + std::to_string(c.recording_number);
        break;
      default:
        break;
    }
    return "{\"command\":" + name(c.code) + ",\"target_node\":" + std::to_string(c.target_node) +
           ",\"sequence\":" + std::to_string(c.sequence) + ",\"arguments\":{" + a +
           "},\"args\":" + bytes(c.args.data(), c.args.size()) + "}";
  }
  std::string operator()(const tp::Ack& a) const {
    std::string reply = "null";
    tp::QueryReply r;
    if (tp::decode_query_reply(a, r) == tp::Status::kOk) {
      reply = "{\"item\":" + name(r.item) + ",\"version\":[" + std::to_string(r.version.major) +
              "," + std::to_string(r.version.minor) + "," + std::to_string(r.version.patch) +
              "],\"finger_separation\":" + num(r.finger_separation_m) +
              ",\"fusion\":" + name(r.fusion) + ",\"velocity_mode\":" + name(r.velocity_mode) +
              ",\"stream_enabled\":" + boolean(r.stream_enabled) +
              ",\"rate_divider\":" + std::to_string(r.rate_divider) +
              ",\"fd_mode\":" + boolean(r.fd_mode) +
              ",\"extended_ids\":" + boolean(r.extended_ids) + "}";
    }
    return "{\"command\":" + name(a.command) + ",\"result\":" + name(a.result) +
           ",\"sequence\":" + std::to_string(a.sequence) +
           ",\"data\":" + bytes(a.data.data(), a.data.size()) + ",\"query_reply\":" + reply + "}";
  }
  static std::string v3(const tp::Vec3& v, const tp::Saturation& s, unsigned counter) {
    return "{\"v\":" + vec(v) + ",\"sat\":" + sat(s) + ",\"counter\":" + std::to_string(counter) +
           "}";
  }
};

const char* status_name(tp::Status s) {
  switch (s) {
    case tp::Status::kOk:
      return "ok";
    case tp::Status::kUnknownId:
      return "unknown_id";
    case tp::Status::kBadLength:
      return "length";
    case tp::Status::kBadCrc:
      return "crc";
    case tp::Status::kBadCounter:
      return "counter";
    default:
      return "other";
  }
}

std::string decoded_json(const tp::CanFrame& f, const tp::IdLayout& layout) {
  tp::Decoded d;
  const tp::Status s = tp::decode(f, layout, d);
  std::string out = std::string("{\"status\":\"") + status_name(s) + "\"";
  if (s == tp::Status::kOk) {
    out += ",\"node\":" + std::to_string(d.node_id) + ",\"message\":\"" +
           std::string(tp::message_def(d.message).name) +
           "\",\"value\":" + std::visit(PayloadJson{}, d.payload);
  }
  return out + "}";
}

std::string tx_json(const tp::TxConfig& tx) {
  return "\"node\":" + std::to_string(tx.endpoint.node_id) +
         ",\"extended\":" + boolean(tx.endpoint.layout.mode == tp::IdMode::kExtended) +
         ",\"extended_base\":" + std::to_string(tx.endpoint.layout.extended_base) +
         ",\"fd\":" + boolean(tx.frame_mode == tp::FrameMode::kFd) + ",\"brs\":" + boolean(tx.brs);
}

void emit(const char* kind, const std::string& input, const tp::TxConfig& tx,
          const std::vector<tp::CanFrame>& frames) {
  std::string fs, ds;
  for (const tp::CanFrame& f : frames) {
    fs += (fs.empty() ? "" : ",") + frame_json(f);
    ds += (ds.empty() ? "" : ",") + decoded_json(f, tx.endpoint.layout);
  }
  std::printf("{\"kind\":\"%s\",%s,\"input\":%s,\"frames\":[%s],\"decoded\":[%s]}\n", kind,
              tx_json(tx).c_str(), input.c_str(), fs.c_str(), ds.c_str());
}

}  // namespace

namespace {

struct Gen {
  std::mt19937_64 rng{20261127};
  double uniform(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  }
  std::int64_t integer(std::int64_t lo, std::int64_t hi) {
    return std::uniform_int_distribution<std::int64_t>(lo, hi)(rng);
  }
  bool chance(double p) { return uniform(0.0, 1.0) < p; }
  // A field value: mostly inside [-lim, lim], sometimes beyond it (saturation) or NaN.
  double value(double lim) { return chance(0.08) ? kNaN : uniform(-1.3 * lim, 1.3 * lim); }

  tp::TxConfig tx() {
    tp::TxConfig t;
    t.endpoint.node_id = static_cast<std::uint8_t>(integer(1, 63));
    if (chance(0.3)) {
      t.endpoint.layout.mode = tp::IdMode::kExtended;
      t.endpoint.layout.extended_base = static_cast<std::uint32_t>(integer(1, 0x3FFFF)) << 11;
    }
    t.frame_mode = chance(0.3) ? tp::FrameMode::kFd : tp::FrameMode::kClassic;
    t.brs = chance(0.7);
    return t;
  }
  tp::Cycle cycle() {
    tp::Cycle c;
    c.timestamp_us = static_cast<std::uint64_t>(integer(0, (std::int64_t{1} << 48) + 10));
    c.estimate_valid = chance(0.5);
    c.single_sensor = chance(0.2);
    c.pose_reset = chance(0.1);
    c.angular = {value(32.767), value(32.767), value(32.767)};
    c.linear = {value(3.2767), value(3.2767), value(3.2767)};
    c.position = {value(0.65534), value(0.65534), value(0.65534)};
    const double s = chance(0.1) ? uniform(0.1, 3.0) : 1.0;  // sometimes far from unit norm
    c.orientation = {value(s), value(s), value(s), value(s)};
    return c;
  }
  tp::StatusGroup status() {
    tp::StatusGroup g;
    g.status.state = static_cast<tp::State>(integer(0, 6));
    g.status.health_left = static_cast<tp::SensorHealth>(integer(0, 3));
    g.status.health_right = static_cast<tp::SensorHealth>(integer(0, 3));
    g.status.contact_left = chance(0.5);
    g.status.contact_right = chance(0.5);
    g.status.slip_left = chance(0.2);
    g.status.slip_right = chance(0.2);
    g.status.stream_enabled = chance(0.8);
    g.status.fusion = static_cast<tp::FusionMethod>(integer(0, 1));
    g.status.velocity_mode = static_cast<tp::VelocityMode>(integer(0, 3));
    g.status.confidence = chance(0.1) ? kNaN : uniform(-0.2, 1.3);
    g.status.rate_divider = static_cast<std::uint8_t>(integer(0, 255));
    g.status.fault = static_cast<tp::FaultCode>(integer(0, 9));
    g.status.rejected_commands = static_cast<std::uint8_t>(integer(0, 255));
    g.status.calibrated = chance(0.5);
    g.contact = {value(0.004), value(0.004), value(0.6) + 0.5, value(0.6) + 0.5, 0};
    g.timing = {value(0.04) + 0.03, value(0.04) + 0.03, value(0.04) + 0.03, 0};
    g.counters = {static_cast<std::uint16_t>(integer(0, 65535)),
                  static_cast<std::uint16_t>(integer(0, 65535)),
                  static_cast<std::uint16_t>(integer(0, 65535)), 0};
    return g;
  }
};

void cycle_case(const tp::Cycle& in, std::uint8_t counter, const tp::TxConfig& tx) {
  tp::CycleFrames out;
  if (tp::encode_cycle(in, counter, tx, out) != tp::Status::kOk) return;
  std::vector<tp::CanFrame> frames(out.frames.begin(), out.frames.begin() + out.count);
  emit("cycle",
       "{\"cycle\":" + cycle_json(in) + ",\"counter\":" + std::to_string(counter) +
           ",\"sent\":" + cycle_json(out.sent) + "}",
       tx, frames);
}

void status_case(const tp::StatusGroup& g, std::uint8_t counter, tp::TxConfig tx) {
  tx.frame_mode = tp::FrameMode::kClassic;
  std::array<tp::CanFrame, 4> out{};
  if (tp::encode_status_group(g, counter, tx, out) != tp::Status::kOk) return;
  const PayloadJson j;
  emit("status",
       "{\"status\":" + j(g.status) + ",\"contact\":" + j(g.contact) +
           ",\"timing\":" + j(g.timing) + ",\"counters\":" + j(g.counters) +
           ",\"counter\":" + std::to_string(counter) + "}",
       tx, std::vector<tp::CanFrame>(out.begin(), out.end()));
}

// The Python keyword arguments of encode_command for `c`.
std::string command_arguments(const tp::Command& c) {
  switch (c.code) {
    case tp::CommandCode::kSetFingerSeparation:
      return "{\"finger_separation\":" + num(c.finger_separation_m) + "}";
    case tp::CommandCode::kSetFusion:
      return "{\"fusion\":" + name(c.fusion) + ",\"velocity_mode\":" + name(c.velocity_mode) + "}";
    case tp::CommandCode::kSetRateDivider:
      return "{\"rate_divider\":" + std::to_string(c.rate_divider) + "}";
    case tp::CommandCode::kSetStream:
      return "{\"stream\":" + std::to_string(c.stream_enabled ? 1 : 0) + "}";
    case tp::CommandCode::kQuery:
      return "{\"query\":" + name(c.query) + "}";
    case tp::CommandCode::kStartRecording:
      return "{\"recording\":" + std::to_string(c.recording_number) + "}";
    default:
      return "{}";
  }
}

void command_case(const tp::Command& c, tp::TxConfig tx) {
  tx.frame_mode = tp::FrameMode::kClassic;
  tp::CanFrame f;
  const bool ok = tp::encode(c, tx, f) == tp::Status::kOk;
  emit("command",
       "{\"command\":" + name(c.code) + ",\"sequence\":" + std::to_string(c.sequence) +
           ",\"arguments\":" + command_arguments(c) + ",\"rejected\":" + boolean(!ok) + "}",
       tx, ok ? std::vector<tp::CanFrame>{f} : std::vector<tp::CanFrame>{});
}

void ack_case(const tp::Ack& a, tp::TxConfig tx) {
  tx.frame_mode = tp::FrameMode::kClassic;
  tp::CanFrame f;
  if (tp::encode(a, tx, f) != tp::Status::kOk) return;
  emit("ack",
       "{\"command\":" + std::to_string(static_cast<unsigned>(a.command)) +
           ",\"result\":" + std::to_string(static_cast<unsigned>(a.result)) + ",\"sequence\":" +
           std::to_string(a.sequence) + ",\"data\":" + bytes(a.data.data(), a.data.size()) + "}",
       tx, {f});
}

void commands(Gen& g) {
  for (int i = 0; i < 40; ++i) {
    for (unsigned code = 1; code <= 9; ++code) {
      tp::Command c;
      c.code = static_cast<tp::CommandCode>(code);
      c.sequence = static_cast<std::uint8_t>(g.integer(0, 15));
      c.finger_separation_m = g.chance(0.05) ? kNaN : g.uniform(-0.01, 0.3);
      c.fusion = static_cast<tp::FusionMethod>(g.integer(0, 2));
      c.velocity_mode = static_cast<tp::VelocityMode>(g.integer(0, 3));
      c.rate_divider = static_cast<std::uint8_t>(g.integer(0, 130));
      c.stream_enabled = g.chance(0.5);
      c.query = static_cast<tp::QueryItem>(g.integer(0, 5));
      c.recording_number = static_cast<std::uint16_t>(g.integer(0, 65535));
      command_case(c, g.tx());
    }
    tp::Ack a;
    a.command = static_cast<tp::CommandCode>(g.integer(1, 11));
    a.result = static_cast<tp::AckCode>(g.integer(0, 14));
    a.sequence = static_cast<std::uint8_t>(g.integer(0, 15));
    for (auto& b : a.data) b = static_cast<std::uint8_t>(g.integer(0, 255));
    ack_case(a, g.tx());
    tp::Command q;
    q.code = tp::CommandCode::kQuery;
    q.sequence = a.sequence;
    tp::QueryReply r;
    r.item = static_cast<tp::QueryItem>(i % 5);
    r.version = {static_cast<std::uint8_t>(g.integer(0, 255)),
                 static_cast<std::uint8_t>(g.integer(0, 255)),
                 static_cast<std::uint8_t>(g.integer(0, 255))};
    r.finger_separation_m = g.uniform(0.001, 0.25);
    r.fusion = static_cast<tp::FusionMethod>(g.integer(0, 1));
    r.velocity_mode = static_cast<tp::VelocityMode>(g.integer(0, 2));
    r.stream_enabled = g.chance(0.5);
    r.rate_divider = static_cast<std::uint8_t>(g.integer(1, 120));
    r.fd_mode = g.chance(0.5);
    r.extended_ids = g.chance(0.5);
    ack_case(tp::make_query_reply(q, r), g.tx());
  }
}

// Random payloads under every message id with a valid CRC, then with one bit flipped, and with
// a wrong length: both decoders must read (or refuse) them alike.
void raw_frames(Gen& g) {
  for (int i = 0; i < 30; ++i) {
    for (const tp::MessageDef& m : tp::kMessages) {
      tp::TxConfig tx = g.tx();
      tx.frame_mode = m.fd_only ? tp::FrameMode::kFd : tx.frame_mode;
      tp::CanFrame f;
      (void)tp::prepare_frame(m.id, tx, f);
      f.len = m.length;
      for (std::size_t b = 0; b < f.len; ++b)
        f.data[b] = static_cast<std::uint8_t>(g.integer(0, 255));
      tp::finish_frame(f);
      tp::CanFrame flipped = f;
      const auto bit = static_cast<std::size_t>(g.integer(0, 8 * f.len - 1));
      flipped.data[bit / 8] = static_cast<std::uint8_t>(flipped.data[bit / 8] ^ (1u << (bit % 8)));
      tp::CanFrame shortened = f;
      shortened.len = static_cast<std::uint8_t>(g.integer(0, 7));
      emit("raw", "{}", tx, {f, flipped, shortened});
    }
  }
}

}  // namespace

int main() {
  Gen g;
  // The worked example of docs/can-protocol.md, classic and CAN FD, 11-bit and 29-bit (node 2).
  tp::Cycle golden;
  golden.timestamp_us = 1234567890;
  golden.estimate_valid = true;
  golden.angular = {1.234, -0.5, 30.0};
  golden.linear = {5.0, -2.0, kNaN};
  golden.orientation = {0.5, 0.5, -0.5, 0.5};
  golden.position = {0.01, -0.02, 0.5};
  tp::TxConfig tx;
  cycle_case(golden, 5, tx);
  tx.frame_mode = tp::FrameMode::kFd;
  cycle_case(golden, 5, tx);
  tx = tp::TxConfig{};
  tx.endpoint.node_id = 2;
  tx.endpoint.layout.mode = tp::IdMode::kExtended;
  cycle_case(golden, 5, tx);
  for (int i = 0; i < 300; ++i) {
    cycle_case(g.cycle(), static_cast<std::uint8_t>(g.integer(0, 31)), g.tx());
  }
  for (int i = 0; i < 100; ++i) {
    status_case(g.status(), static_cast<std::uint8_t>(g.integer(0, 31)), g.tx());
  }
  commands(g);
  raw_frames(g);
  return std::fflush(stdout) == 0 ? 0 : 1;
}
