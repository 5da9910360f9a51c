// SPDX-License-Identifier: Apache-2.0
// tacse3-calkeys: prints the calibration key table of docs/calibration.md from the dsp schema
// (dsp::kCalibrationFields), so the reference cannot drift from what the reader accepts.
#include <charconv>
#include <cstdio>
#include <cstring>
#include <string>

#include "tacse3/dsp/calibration_fields.hpp"

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
  if (argc == 2 && std::strcmp(argv[1], "--markdown") == 0) {
    print_markdown();
    return std::ferror(stdout) || std::fflush(stdout) != 0 ? 1 : 0;
  }
  if (argc == 2 && std::strcmp(argv[1], "--help") == 0) {
    std::puts(
        "Usage: tacse3-calkeys --markdown\n"
        "Prints the calibration key table of docs/calibration.md from the dsp schema.");
    return 0;
  }
  std::fputs("usage: tacse3-calkeys --markdown (see --help)\n", stderr);
  return 2;
}
