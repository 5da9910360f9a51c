// SPDX-License-Identifier: Apache-2.0
// tacse3-calkeys: prints the calibration key table of docs/calibration.md from the dsp schema
// (dsp::kCalibrationFields), so the reference cannot drift from what the reader accepts.
#include <charconv>
#include <cstdio>
#include <string>

#include "tacse3/dsp/calibration_fields.hpp"
#include "tacse3/tools/cli.hpp"

namespace {

using tacse3::dsp::CalibrationField;
using Kind = CalibrationField::Kind;

std::string num(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

std::string range(const CalibrationField& f) {
  if (f.kind == Kind::kProxy) {
    std::string s;
    for (const auto& n : tacse3::dsp::kVelocityProxyNames) {
      s += std::string(s.empty() ? "" : ", ") + "`" + n.name + "`";
    }
    return s;
  }
  if (f.kind == Kind::kInt) return "[" + num(f.lo) + ", " + num(f.hi) + "]";
  return std::string(f.lo_open ? "(" : "[") + num(f.lo) + ", " + num(f.hi) +
         (f.hi_open ? ")" : "]");
}

std::string default_value(const CalibrationField& f) {
  const tacse3::dsp::Calibration c;
  switch (f.kind) {
    case Kind::kReal:
      return num(c.*(f.real));
    case Kind::kInt:
      return num(c.*(f.integer));
    case Kind::kVec3: {
      const auto& v = c.*(f.vec);
      return "[" + num(v[0]) + ", " + num(v[1]) + ", " + num(v[2]) + "]";
    }
    case Kind::kProxy:
      for (const auto& n : tacse3::dsp::kVelocityProxyNames) {
        if (n.value == c.velocity_proxy) return std::string("`") + n.name + "`";
      }
  }
  return "?";
}

void print_markdown() {
  std::puts("| key | unit | range | default | meaning |");
  std::puts("|---|---|---|---|---|");
  for (const auto& f : tacse3::dsp::kCalibrationFields) {
    std::printf("| `%s` | %s | %s | %s | %s |\n", f.key, f.unit, range(f).c_str(),
                default_value(f).c_str(), f.doc);
  }
  std::puts("");
  std::puts("Rules over two keys, checked on each sensor table:");
  std::puts("");
  for (const auto& r : tacse3::dsp::kCalibrationRules) {
    std::printf("- `%s` %s `%s`%s.\n", r.key, r.relation, r.other, r.note);
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Prints the calibration key table of docs/calibration.md from the dsp schema."};
  bool markdown = false;
  app.add_flag("--markdown", markdown, "print the table as Markdown (the only output)")->required();
  if (const int rc = tacse3::tools::parse_command_line(app, argc, argv); rc >= 0) return rc;
  print_markdown();
  return tacse3::tools::finish_stdout("tacse3-calkeys", 0);
}
