// SPDX-License-Identifier: Apache-2.0
// tacse3 viewer: JSON for the live viewer. A fixed schema of numbers, booleans and a few known
// strings, so it is written directly, each number at the precision it needs: the fields go out at
// four digits (about 70 kB per snapshot), where nlohmann::json (which parses the command
// bodies) prints every double in full. Non-finite numbers become null (JSON has no NaN).
#include "tacse3/viewer/view_json.hpp"

#include <cmath>
#include <cstdio>

#include "tacse3/protocol/types.hpp"

namespace tacse3::viewer {

namespace {

void num(std::string& s, double v, const char* fmt = "%.9g") {
  if (!std::isfinite(v)) {
    s += "null";
    return;
  }
  char buf[40];
  std::snprintf(buf, sizeof(buf), fmt, v);
  s += buf;
}

void integer(std::string& s, long long v) {
  char buf[24];
  std::snprintf(buf, sizeof(buf), "%lld", v);
  s += buf;
}

template <typename A>
void array(std::string& s, const A& a, const char* fmt = "%.9g") {
  s += '[';
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (i > 0) s += ',';
    num(s, static_cast<double>(a[i]), fmt);
  }
  s += ']';
}

const char* boolean(bool b) {
  return b ? "true" : "false";
}

void pad_state(std::string& s, const ViewPad& p) {
  s += "{\"configured\":";
  s += boolean(p.configured);
  s += ",\"present\":";
  s += boolean(p.present);
  s += ",\"health\":\"";
  s += protocol::to_string(static_cast<protocol::SensorHealth>(p.health));
  s += "\",\"contact\":";
  s += boolean(p.contact);
  s += ",\"slipping\":";
  s += boolean(p.slipping);
  s += ",\"contact_area_m2\":";
  num(s, p.contact_area_m2);
  s += ",\"tracked_fraction\":";
  num(s, p.tracked_fraction);
  s += ",\"frames\":";
  integer(s, static_cast<long long>(p.frames));
  s += ",\"dropped\":";
  integer(s, static_cast<long long>(p.dropped));
  s += '}';
}

void pad_fields(std::string& s, const ViewPad& p) {
  s += "{\"mask\":[";
  for (std::size_t i = 0; i < p.mask.size(); ++i) {
    if (i > 0) s += ',';
    s += p.mask[i] != 0 ? '1' : '0';
  }
  s += "],\"shear_x\":";
  array(s, p.shear_x, "%.4g");
  s += ",\"shear_y\":";
  array(s, p.shear_y, "%.4g");
  s += ",\"fz\":";
  array(s, p.fz, "%.4g");
  s += '}';
}

}  // namespace

std::string view_state_json(const ViewSnapshot& v, const ViewTruth* truth) {
  std::string s;
  s.reserve(1024);
  s += "{\"cycle\":";
  integer(s, static_cast<long long>(v.cycle));
  s += ",\"t_us\":";
  integer(s, v.t_us);
  s += ",\"state\":\"";
  s += protocol::to_string(static_cast<protocol::State>(v.state));
  s += "\",\"valid\":";
  s += boolean(v.valid);
  s += ",\"single_sensor\":";
  s += boolean(v.single_sensor);
  s += ",\"calibrated\":";
  s += boolean(v.calibrated);
  s += ",\"twist\":{\"w\":";
  array(s, v.w);
  s += ",\"v\":";
  array(s, v.v);
  s += "},\"pose\":{\"q\":";
  array(s, v.q);
  s += ",\"p\":";
  array(s, v.p);
  s += "},\"confidence\":";
  num(s, v.confidence);
  s += ",\"dsp_us\":";
  integer(s, v.dsp_us);
  s += ",\"latency_us\":";
  integer(s, v.latency_us);
  s += ",\"counters\":{\"cycles_sent\":";
  integer(s, static_cast<long long>(v.counters.cycles_sent));
  s += ",\"can_send_failures\":";
  integer(s, static_cast<long long>(v.counters.can_send_failures));
  s += ",\"can_tx_dropped\":";
  integer(s, static_cast<long long>(v.counters.can_tx_dropped));
  s += ",\"commands\":";
  integer(s, static_cast<long long>(v.counters.commands));
  s += ",\"rejected_commands\":";
  integer(s, v.counters.rejected_commands);
  s += "},\"sensors\":{\"left\":";
  pad_state(s, v.pads[0]);
  s += ",\"right\":";
  pad_state(s, v.pads[1]);
  s += '}';
  if (truth != nullptr) {
    s += ",\"truth\":{\"q\":";
    array(s, truth->q);
    s += ",\"p\":";
    array(s, truth->p);
    s += '}';
  }
  s += '}';
  return s;
}

std::string json_quote(std::string_view text) {
  std::string s(1, '"');
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      s += '\\';
      s += c;
    } else if (u < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\u%04x", u);
      s += buf;
    } else {
      s += c;
    }
  }
  s += '"';
  return s;
}

std::string view_info_json(const ViewInfo& info) {
  std::string s = "{\"version\":";
  s += json_quote(info.version);
  s += ",\"board\":";
  s += json_quote(info.board);
  s += ",\"board_file\":";
  s += json_quote(info.board_file);
  s += ",\"calibration\":";
  s += info.calibration.empty() ? std::string("null") : json_quote(info.calibration);
  s += ",\"controls\":";
  s += info.controls_off.empty() ? "true" : "false";
  s += ",\"controls_off\":";
  s += info.controls_off.empty() ? std::string("null") : json_quote(info.controls_off);
  if (!info.recording.empty()) {
    s += ",\"recording\":";
    s += json_quote(info.recording);
  }
  s += '}';
  return s;
}

std::string view_fields_json(const ViewSnapshot& v) {
  std::string s;
  s.reserve(64 * 1024);
  s += "{\"cycle\":";
  integer(s, static_cast<long long>(v.cycle));
  s += ",\"grid\":{\"width\":";
  integer(s, dsp::kGridWidth);
  s += ",\"height\":";
  integer(s, dsp::kGridHeight);
  s += ",\"image_width\":";
  integer(s, dsp::kWorkWidth);
  s += ",\"image_height\":";
  integer(s, dsp::kWorkHeight);
  s += "},\"left\":";
  pad_fields(s, v.pads[0]);
  s += ",\"right\":";
  pad_fields(s, v.pads[1]);
  s += '}';
  return s;
}

}  // namespace tacse3::viewer
