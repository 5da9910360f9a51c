// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: the calibration plan's CSV as scenarios.
#include "tacse3/sim/plan.hpp"

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace tacse3::sim {

namespace {

// One CSV record from `text` at *pos (RFC 4180 quoting; CRLF or LF). False at the end of text or
// on an unterminated quote (*bad set).
bool next_record(std::string_view text, std::size_t* pos, std::vector<std::string>* fields,
                 bool* bad) {
  fields->clear();
  if (*pos >= text.size()) return false;
  std::string f;
  bool quoted = false;
  std::size_t i = *pos;
  for (; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c != '"') {
        f += c;
      } else if (i + 1 < text.size() && text[i + 1] == '"') {
        f += '"';
        ++i;
      } else {
        quoted = false;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields->push_back(f);
      f.clear();
    } else if (c == '\n') {
      break;
    } else if (c != '\r') {
      f += c;
    }
  }
  if (quoted) {
    *bad = true;
    return false;
  }
  fields->push_back(f);
  *pos = i + 1;
  return true;
}

bool to_number(const std::string& s, double* out) {
  if (s.empty()) return false;
  char* end = nullptr;
  errno = 0;
  *out = std::strtod(s.c_str(), &end);
  return errno == 0 && end == s.c_str() + s.size() && std::isfinite(*out);
}

}  // namespace

bool parse_plan(std::string_view text, const std::string& name, std::vector<PlanMotion>* out,
                std::string* error) {
  out->clear();
  static constexpr std::array<const char*, 7> kColumns{
      "axis", "magnitude", "unit", "regime", "duration_s", "pads_open_s", "hold_s"};
  std::array<int, 7> col{};
  col.fill(-1);
  std::size_t pos = 0;
  bool bad = false;
  std::vector<std::string> f;
  if (!next_record(text, &pos, &f, &bad)) {
    *error = name + ": empty; it must be the CSV of tacse3-calibrate --plan --format csv";
    return false;
  }
  for (std::size_t i = 0; i < f.size(); ++i) {
    for (std::size_t c = 0; c < kColumns.size(); ++c) {
      if (f[i] == kColumns[c]) col[c] = static_cast<int>(i);
    }
  }
  for (std::size_t c = 0; c < kColumns.size(); ++c) {
    if (col[c] < 0) {
      *error = name + " line 1 (header): no column \"" + kColumns[c] +
               "\"; the plan is the CSV of tacse3-calibrate --plan --format csv";
      return false;
    }
  }
  int line = 1;
  while (next_record(text, &pos, &f, &bad)) {
    ++line;
    if (f.size() == 1 && f[0].empty()) continue;  // a blank line
    const std::string at = name + " line " + std::to_string(line) + ": ";
    auto field = [&](std::size_t c) -> const std::string& {
      static const std::string kNone;
      const auto i = static_cast<std::size_t>(col[c]);
      return i < f.size() ? f[i] : kNone;
    };
    PlanMotion m;
    if (!parse_axis(field(0), &m.axis)) {
      *error = at + "axis \"" + field(0) + "\": must be rx, ry, rz, tx or ty";
      return false;
    }
    const char* unit = is_rotation(m.axis) ? "deg" : "mm";
    if (field(2) != unit) {
      *error = at + "unit \"" + field(2) + "\": axis " + field(0) + " is in " + unit;
      return false;
    }
    if (field(3) == "stick") {
      m.regime = Regime::kStick;
    } else if (field(3) == "slide") {
      m.regime = Regime::kSlide;
    } else {
      *error = at + "regime \"" + field(3) + "\": must be stick or slide";
      return false;
    }
    double v[4] = {};
    for (std::size_t c : {1u, 4u, 5u, 6u}) {
      const std::size_t k = c == 1 ? 0 : c - 3;
      if (!to_number(field(c), &v[k])) {
        *error = at + kColumns[c] + " \"" + field(c) + "\": not a number";
        return false;
      }
    }
    m.magnitude = v[0];
    m.duration_s = v[1];
    m.pads_open_s = v[2];
    m.hold_s = v[3];
    ScenarioSpec probe = plan_scenario(m, ScenarioSpec{});
    if (m.duration_s <= 0.0) {
      *error = at + "duration_s " + field(4) + ": must be > 0";
      return false;
    }
    if (std::string e = validate(probe); !e.empty()) {
      *error = at + "the simulator cannot play this motion: " + e;
      return false;
    }
    out->push_back(m);
  }
  if (bad) {
    *error = name + " line " + std::to_string(line + 1) + ": a quoted field does not end";
    return false;
  }
  if (out->empty()) {
    *error = name + ": no motion after the header";
    return false;
  }
  return true;
}

ScenarioSpec plan_scenario(const PlanMotion& m, const ScenarioSpec& base) {
  ScenarioSpec s = base;
  s.axis = m.axis;
  s.magnitude = m.magnitude;
  s.regime = m.regime;
  s.motion_s = m.duration_s;
  s.approach_s = m.pads_open_s;
  s.hold_s = m.hold_s;
  s.loop = false;
  s.release_s = 0.0;
  return s;
}

}  // namespace tacse3::sim
