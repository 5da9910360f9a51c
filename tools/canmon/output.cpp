// SPDX-License-Identifier: Apache-2.0
// tacse3 canmon: CSV, JSON-lines and live terminal outputs.
#include "output.hpp"

#include <time.h>

#include <cinttypes>
#include <cmath>
#include <string_view>
#include <variant>

namespace tacse3::canmon {
namespace {

// Decimals matching each field's LSB (docs/can-protocol.md).
constexpr int kDecAngular = 3;     // 0.001 rad/s
constexpr int kDecLinear = 4;      // 0.0001 m/s
constexpr int kDecQuat = 5;        // 0.00025
constexpr int kDecPosition = 5;    // 0.00002 m
constexpr int kDecConfidence = 3;  // 0.004
constexpr int kDecArea = 7;        // 1e-7 m^2
constexpr int kDecTime = 6;        // 1e-6 s

std::int64_t wall_ms() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000 + ts.tv_nsec / 1000000;
}

const char* b(bool v) {
  return v ? "true" : "false";
}

std::string json_num(double v, int decimals) {
  if (std::isnan(v)) return "null";
  return fixed(v, decimals);
}

// Strings are built with append only: GCC 12 at -O3 reports false -Wrestrict warnings for
// chains of operator+ on std::string.
template <typename E>
std::string enum_json(E e) {
  const char* s = tp::to_string(e);
  std::string out;
  if (s == nullptr) return std::to_string(static_cast<unsigned>(e));
  out += '"';
  out += s;
  out += '"';
  return out;
}

template <typename E>
std::string enum_text(E e) {
  const char* s = tp::to_string(e);
  if (s != nullptr) return s;
  std::string out = "UNKNOWN(";
  out += std::to_string(static_cast<unsigned>(e));
  out += ')';
  return out;
}

std::string sat_json(const tp::Saturation& s) {
  std::string out = "[";
  out += b(s.x);
  out += ',';
  out += b(s.y);
  out += ',';
  out += b(s.z);
  out += ']';
  return out;
}

void field(std::string& row, std::string_view v) {
  row += ',';
  row += v;
}

std::string time_json(std::uint64_t t) {
  return t == tp::kTimestampInvalid ? "null" : std::to_string(t);
}

}  // namespace

AngleAxisDeg angle_axis_deg(const tp::Quaternion& q) {
  // The decoded quaternion is only nearly unit (0.00025 LSB): normalise, and take w >= 0 so the
  // angle is the shorter one.
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  AngleAxisDeg r;
  if (!(n > 0.0)) return r;
  const double sign = q.w < 0.0 ? -1.0 : 1.0;
  const double w = sign * q.w / n;
  const double v[3] = {sign * q.x / n, sign * q.y / n, sign * q.z / n};
  const double s = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  const double angle = 2.0 * std::atan2(s, w);
  if (angle < 1e-9) return r;
  r.angle_deg = angle * 180.0 / M_PI;
  for (int i = 0; i < 3; ++i) r.axis[i] = v[i] / s;
  return r;
}

std::string fixed(double v, int decimals) {
  if (std::isnan(v)) return "";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  // "-0.000" -> "0.000": the same quantised value always prints the same text.
  std::string s = buf;
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

// ---- CSV ---------------------------------------------------------------------------------------
void CsvSink::header() {
  std::fputs(
      "t_us,node,counter,valid,single_sensor,pose_reset,saturated,wx,wy,wz,vx,vy,vz,qw,qx,qy,qz,"
      "px,py,pz,state,health_left,health_right,contact_left,contact_right,slip_left,slip_right,"
      "confidence\n",
      out_);
}

void CsvSink::on_cycle(std::uint8_t node, std::uint64_t, const tp::Cycle& c) {
  const NodeView& n = monitor_.node(node);
  std::string row;
  if (c.timestamp_us != tp::kTimestampInvalid) row += std::to_string(c.timestamp_us);
  field(row, std::to_string(node));
  field(row, std::to_string(c.counter));
  for (bool f : {c.estimate_valid, c.single_sensor, c.pose_reset, c.saturated}) {
    field(row, f ? "1" : "0");
  }
  for (double v : {c.angular.x, c.angular.y, c.angular.z}) field(row, fixed(v, kDecAngular));
  for (double v : {c.linear.x, c.linear.y, c.linear.z}) field(row, fixed(v, kDecLinear));
  for (double v : {c.orientation.w, c.orientation.x, c.orientation.y, c.orientation.z}) {
    field(row, fixed(v, kDecQuat));
  }
  for (double v : {c.position.x, c.position.y, c.position.z}) field(row, fixed(v, kDecPosition));
  if (n.status) {
    const tp::StatusMsg& s = *n.status;
    field(row, enum_text(s.state));
    field(row, enum_text(s.health_left));
    field(row, enum_text(s.health_right));
    for (bool f : {s.contact_left, s.contact_right, s.slip_left, s.slip_right}) {
      field(row, f ? "1" : "0");
    }
    field(row, fixed(s.confidence, kDecConfidence));
  } else {
    row += ",,,,,,,,";
  }
  row += '\n';
  std::fputs(row.c_str(), out_);
}

// ---- JSON lines -------------------------------------------------------------------------------
void JsonSink::on_cycle(std::uint8_t node, std::uint64_t rx_time_us, const tp::Cycle& c) {
  std::fprintf(
      out_,
      "{\"type\":\"cycle\",\"node\":%u,\"rx_us\":%" PRIu64
      ",\"counter\":%u,\"t_us\":%s,\"valid\":%s,\"single_sensor\":%s,\"pose_reset\":%s,"
      "\"saturated\":%s,\"wx\":%s,\"wy\":%s,\"wz\":%s,\"vx\":%s,\"vy\":%s,\"vz\":%s,"
      "\"qw\":%s,\"qx\":%s,\"qy\":%s,\"qz\":%s,\"px\":%s,\"py\":%s,\"pz\":%s,"
      "\"sat_w\":%s,\"sat_v\":%s,\"sat_p\":%s}\n",
      unsigned{node}, rx_time_us, unsigned{c.counter}, time_json(c.timestamp_us).c_str(),
      b(c.estimate_valid), b(c.single_sensor), b(c.pose_reset), b(c.saturated),
      json_num(c.angular.x, kDecAngular).c_str(), json_num(c.angular.y, kDecAngular).c_str(),
      json_num(c.angular.z, kDecAngular).c_str(), json_num(c.linear.x, kDecLinear).c_str(),
      json_num(c.linear.y, kDecLinear).c_str(), json_num(c.linear.z, kDecLinear).c_str(),
      json_num(c.orientation.w, kDecQuat).c_str(), json_num(c.orientation.x, kDecQuat).c_str(),
      json_num(c.orientation.y, kDecQuat).c_str(), json_num(c.orientation.z, kDecQuat).c_str(),
      json_num(c.position.x, kDecPosition).c_str(), json_num(c.position.y, kDecPosition).c_str(),
      json_num(c.position.z, kDecPosition).c_str(), sat_json(c.angular_saturated).c_str(),
      sat_json(c.linear_saturated).c_str(), sat_json(c.position_saturated).c_str());
}

void JsonSink::on_message(std::uint8_t node, std::uint64_t rx_time_us, const tp::Decoded& d) {
  const unsigned nd = node;
  if (const auto* s = std::get_if<tp::StatusMsg>(&d.payload)) {
    std::fprintf(out_,
                 "{\"type\":\"status\",\"node\":%u,\"rx_us\":%" PRIu64
                 ",\"counter\":%u,\"state\":%s,\"health_left\":%s,\"health_right\":%s,"
                 "\"contact_left\":%s,\"contact_right\":%s,\"slip_left\":%s,\"slip_right\":%s,"
                 "\"stream_enabled\":%s,\"fusion\":%s,\"velocity_mode\":%s,\"confidence\":%s,"
                 "\"rate_divider\":%u,\"fault\":%s,\"rejected_commands\":%u,\"calibrated\":%s}\n",
                 nd, rx_time_us, unsigned{s->counter}, enum_json(s->state).c_str(),
                 enum_json(s->health_left).c_str(), enum_json(s->health_right).c_str(),
                 b(s->contact_left), b(s->contact_right), b(s->slip_left), b(s->slip_right),
                 b(s->stream_enabled), enum_json(s->fusion).c_str(),
                 enum_json(s->velocity_mode).c_str(),
                 json_num(s->confidence, kDecConfidence).c_str(), unsigned{s->rate_divider},
                 enum_json(s->fault).c_str(), unsigned{s->rejected_commands}, b(s->calibrated));
  } else if (const auto* c = std::get_if<tp::ContactMsg>(&d.payload)) {
    std::fprintf(out_,
                 "{\"type\":\"status_contact\",\"node\":%u,\"rx_us\":%" PRIu64
                 ",\"counter\":%u,\"area_left\":%s,\"area_right\":%s,\"confidence_left\":%s,"
                 "\"confidence_right\":%s}\n",
                 nd, rx_time_us, unsigned{c->counter}, json_num(c->area_left_m2, kDecArea).c_str(),
                 json_num(c->area_right_m2, kDecArea).c_str(),
                 json_num(c->confidence_left, kDecConfidence).c_str(),
                 json_num(c->confidence_right, kDecConfidence).c_str());
  } else if (const auto* t = std::get_if<tp::TimingMsg>(&d.payload)) {
    std::fprintf(out_,
                 "{\"type\":\"status_timing\",\"node\":%u,\"rx_us\":%" PRIu64
                 ",\"counter\":%u,\"dsp_time\":%s,\"latency_p50\":%s,\"latency_p99\":%s}\n",
                 nd, rx_time_us, unsigned{t->counter}, json_num(t->dsp_time_s, kDecTime).c_str(),
                 json_num(t->latency_p50_s, kDecTime).c_str(),
                 json_num(t->latency_p99_s, kDecTime).c_str());
  } else if (const auto* n = std::get_if<tp::CountersMsg>(&d.payload)) {
    std::fprintf(out_,
                 "{\"type\":\"status_counters\",\"node\":%u,\"rx_us\":%" PRIu64
                 ",\"counter\":%u,\"dropped_left\":%u,\"dropped_right\":%u,"
                 "\"can_tx_dropped\":%u}\n",
                 nd, rx_time_us, unsigned{n->counter}, unsigned{n->dropped_left},
                 unsigned{n->dropped_right}, unsigned{n->can_tx_dropped});
  } else if (const auto* a = std::get_if<tp::Ack>(&d.payload)) {
    std::fprintf(out_,
                 "{\"type\":\"ack\",\"node\":%u,\"rx_us\":%" PRIu64
                 ",\"command\":%s,\"result\":%s,\"sequence\":%u,\"data\":[%u,%u,%u,%u]}\n",
                 nd, rx_time_us, enum_json(a->command).c_str(), enum_json(a->result).c_str(),
                 unsigned{a->sequence}, unsigned{a->data[0]}, unsigned{a->data[1]},
                 unsigned{a->data[2]}, unsigned{a->data[3]});
  } else if (const auto* m = std::get_if<tp::Command>(&d.payload)) {
    std::fprintf(out_,
                 "{\"type\":\"command\",\"node\":%u,\"rx_us\":%" PRIu64
                 ",\"command\":%s,\"target_node\":%u,\"sequence\":%u,\"args\":[%u,%u,%u,%u]}\n",
                 nd, rx_time_us, enum_json(m->code).c_str(), unsigned{m->target_node},
                 unsigned{m->sequence}, unsigned{m->args[0]}, unsigned{m->args[1]},
                 unsigned{m->args[2]}, unsigned{m->args[3]});
  }
}

void JsonSink::on_error(std::uint64_t rx_time_us, const tp::CanFrame& f, tp::Status s) {
  std::fprintf(out_,
               "{\"type\":\"error\",\"rx_us\":%" PRIu64
               ",\"id\":\"%0*X\",\"extended\":%s,\"error\":\"%s\"}\n",
               rx_time_us, f.extended ? 8 : 3, static_cast<unsigned>(f.id), b(f.extended),
               tp::to_string(s));
}

void JsonSink::on_window(std::uint64_t) {
  stats("stats");
}

void JsonSink::stats(const char* type) {
  const Totals& t = monitor_.totals();
  const BusLoadMeter& bus = monitor_.bus();
  std::string nodes;
  for (unsigned id = 1; id < 64; ++id) {
    const NodeView& n = monitor_.node(static_cast<std::uint8_t>(id));
    if (!n.seen) continue;
    const tp::ReassemblerStats& r = n.reassembler.stats();
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "%s\"%u\":{\"cycles\":%u,\"crc_errors\":%" PRIu64 ",\"length_errors\":%" PRIu64
                  ",\"counter_gaps\":%u,\"repeated\":%u,\"incomplete\":%u,\"stale\":%u,"
                  "\"fd_counter_errors\":%u,\"status_counter_gaps\":%u}",
                  nodes.empty() ? "" : ",", id, r.samples, n.stats.crc_errors,
                  n.stats.length_errors, r.counter_gaps, r.repeated, r.incomplete, r.stale,
                  r.counter_errors, n.stats.status_counter_gaps);
    nodes += buf;
  }
  std::fprintf(out_,
               "{\"type\":\"%s\",\"rx_us\":%" PRIu64 ",\"frames\":%" PRIu64
               ",\"tacse3_frames\":%" PRIu64 ",\"foreign_frames\":%" PRIu64
               ",\"crc_errors\":%" PRIu64 ",\"length_errors\":%" PRIu64
               ",\"bus_load\":%.4f,\"bus_load_peak\":%.4f,\"bus_load_average\":%.4f,"
               "\"bitrate\":%.0f,\"nodes\":{%s}}\n",
               type, bus.last_us, t.frames, t.tacse3_frames, t.foreign_frames, t.crc_errors,
               t.length_errors, bus.last_window_load, bus.peak_load, monitor_.average_load(),
               monitor_.options().timing.nominal_bps, nodes.c_str());
  std::fflush(out_);
}

// ---- live terminal view -----------------------------------------------------------------------
void TtySink::maybe_draw() {
  const std::int64_t now = wall_ms();
  if (last_draw_ms_ >= 0 && now - last_draw_ms_ < period_ms_) return;
  last_draw_ms_ = now;
  draw();
}

void TtySink::draw() {
  const Totals& t = monitor_.totals();
  const BusLoadMeter& bus = monitor_.bus();
  std::string s = "\x1b[H\x1b[2J";
  char line[256];
  std::snprintf(line, sizeof line,
                "tacse3-canmon  %s  %.0f bit/s  load %.1f%% (peak %.1f%%)  frames %" PRIu64
                "  foreign %" PRIu64 "\n",
                source_.c_str(), monitor_.options().timing.nominal_bps,
                100.0 * bus.last_window_load, 100.0 * bus.peak_load, t.frames, t.foreign_frames);
  s += line;
  for (unsigned id = 1; id < 64; ++id) {
    const NodeView& n = monitor_.node(static_cast<std::uint8_t>(id));
    if (!n.seen) continue;
    s += "\n";
    if (n.status) {
      const tp::StatusMsg& st = *n.status;
      std::snprintf(line, sizeof line,
                    "node %-2u %-22s L:%-6s R:%-6s contact %c%c slip %c%c conf %s  %s/%s  "
                    "div %u  stream %s%s\n",
                    id, enum_text(st.state).c_str(), enum_text(st.health_left).c_str(),
                    enum_text(st.health_right).c_str(), st.contact_left ? 'L' : '-',
                    st.contact_right ? 'R' : '-', st.slip_left ? 'L' : '-',
                    st.slip_right ? 'R' : '-', fixed(st.confidence, 3).c_str(),
                    enum_text(st.fusion).c_str(), enum_text(st.velocity_mode).c_str(),
                    unsigned{st.rate_divider}, st.stream_enabled ? "on" : "off",
                    st.calibrated ? "" : "  UNCALIBRATED");
    } else {
      std::snprintf(line, sizeof line, "node %-2u (no status yet)\n", id);
    }
    s += line;
    const tp::ReassemblerStats& r = n.reassembler.stats();
    if (n.cycle) {
      const tp::Cycle& c = *n.cycle;
      const double span = static_cast<double>(n.last_cycle_time_us - n.first_cycle_time_us) * 1e-6;
      const double rate = span > 0 ? (r.samples - 1) / span : 0.0;
      std::snprintf(line, sizeof line, "  t %.6f s  counter %2u  cycles %u (%.1f Hz)  %s%s%s%s\n",
                    static_cast<double>(c.timestamp_us) * 1e-6, unsigned{c.counter}, r.samples,
                    rate, c.estimate_valid ? "valid" : "INVALID",
                    c.single_sensor ? " single-sensor" : "", c.pose_reset ? " pose-reset" : "",
                    c.saturated ? " SATURATED" : "");
      s += line;
      auto row = [&](const char* name, double x, double y, double z, int dec) {
        std::snprintf(line, sizeof line, "  %-12s %10s %10s %10s\n", name, fixed(x, dec).c_str(),
                      fixed(y, dec).c_str(), fixed(z, dec).c_str());
        s += line;
      };
      row("w [rad/s]", c.angular.x, c.angular.y, c.angular.z, kDecAngular);
      row("v [m/s]", c.linear.x, c.linear.y, c.linear.z, kDecLinear);
      std::snprintf(
          line, sizeof line, "  %-12s %10s %10s %10s %10s\n", "q (w x y z)",
          fixed(c.orientation.w, kDecQuat).c_str(), fixed(c.orientation.x, kDecQuat).c_str(),
          fixed(c.orientation.y, kDecQuat).c_str(), fixed(c.orientation.z, kDecQuat).c_str());
      s += line;
      const AngleAxisDeg aa = angle_axis_deg(c.orientation);
      std::snprintf(line, sizeof line, "  %-12s %10.2f deg about (%.3f, %.3f, %.3f)\n", "rotation",
                    aa.angle_deg, aa.axis[0], aa.axis[1], aa.axis[2]);
      s += line;
      row("p [m]", c.position.x, c.position.y, c.position.z, kDecPosition);
    }
    std::snprintf(line, sizeof line,
                  "  errors: crc %" PRIu64 "  length %" PRIu64
                  "  gaps %u  repeated %u  incomplete %u  stale %u  status gaps %u\n",
                  n.stats.crc_errors, n.stats.length_errors, r.counter_gaps, r.repeated,
                  r.incomplete, r.stale, n.stats.status_counter_gaps);
    s += line;
    if (n.timing || n.counters) {
      std::snprintf(line, sizeof line,
                    "  dsp %s ms  latency p50 %s p99 %s ms  dropped L %u R %u  can tx %u\n",
                    n.timing ? fixed(n.timing->dsp_time_s * 1e3, 3).c_str() : "-",
                    n.timing ? fixed(n.timing->latency_p50_s * 1e3, 3).c_str() : "-",
                    n.timing ? fixed(n.timing->latency_p99_s * 1e3, 3).c_str() : "-",
                    n.counters ? unsigned{n.counters->dropped_left} : 0u,
                    n.counters ? unsigned{n.counters->dropped_right} : 0u,
                    n.counters ? unsigned{n.counters->can_tx_dropped} : 0u);
      s += line;
    }
    if (n.ack) {
      std::snprintf(line, sizeof line, "  last ack: %s %s (seq %u)\n",
                    enum_text(n.ack->command).c_str(), enum_text(n.ack->result).c_str(),
                    unsigned{n.ack->sequence});
      s += line;
    }
  }
  std::fputs(s.c_str(), out_);
  std::fflush(out_);
}

// ---- summary ---------------------------------------------------------------------------------
void print_summary(std::FILE* out, const Monitor& m) {
  const Totals& t = m.totals();
  const BusLoadMeter& bus = m.bus();
  std::fprintf(out,
               "tacse3-canmon: %" PRIu64 " frames (%" PRIu64 " tacse3, %" PRIu64
               " foreign), %" PRIu64 " CRC errors, %" PRIu64 " length errors\n",
               t.frames, t.tacse3_frames, t.foreign_frames, t.crc_errors, t.length_errors);
  std::fprintf(
      out, "tacse3-canmon: bus load %.2f%% average, %.2f%% peak (1 s windows) at %.0f bit/s%s\n",
      100.0 * m.average_load(), 100.0 * bus.peak_load, m.options().timing.nominal_bps,
      bus.all_exact ? " (exact bit stuffing)" : " (FD frames: worst-case stuffing)");
  for (unsigned id = 1; id < 64; ++id) {
    const NodeView& n = m.node(static_cast<std::uint8_t>(id));
    if (!n.seen) continue;
    const tp::ReassemblerStats& r = n.reassembler.stats();
    std::fprintf(out,
                 "tacse3-canmon: node %u: %u cycles, counter gaps %u, repeated %u, incomplete %u, "
                 "stale %u, CRC errors %" PRIu64 ", status counter gaps %u\n",
                 id, r.samples, r.counter_gaps, r.repeated, r.incomplete, r.stale,
                 n.stats.crc_errors, n.stats.status_counter_gaps);
  }
}

}  // namespace tacse3::canmon
