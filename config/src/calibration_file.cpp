// SPDX-License-Identifier: Apache-2.0
// tacse3 config: TOML calibration file reader/writer with per-key validation (toml++, no throws).
#include "tacse3/config/calibration_file.hpp"

// Header-only toml++ without exceptions: parse errors come back as values, so nothing can escape
// from a SIGHUP reload. No header of config/ exposes toml++.
#define TOML_HEADER_ONLY 1
#define TOML_EXCEPTIONS 0
#define TOML_ENABLE_FORMATTERS 0
// toml++ 3.3.0 asserts internal parser invariants that malformed input can break (a flipped byte
// in a key: parser.inl parse_key). An assert would abort the daemon on a bad file, so the checks
// are compiled out as in a release build; the parser then reports the malformed input as an error
// (tests/config/test_calibration_file.cpp flips every byte under ASan/UBSan).
#define TOML_ASSERT(expr) static_assert(true)
#include <toml++/toml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <optional>

#include "tacse3/config/toml_names.hpp"
#include "tacse3/dsp/calibration_fields.hpp"
#include "tacse3/fileio/file_io.hpp"

namespace tacse3::config {
namespace {

using dsp::Calibration;

// The schema (keys, members, ranges, rules) is dsp's:
// dsp/include/tacse3/dsp/calibration_fields.hpp.
using Field = dsp::CalibrationField;
using Kind = dsp::CalibrationField::Kind;
constexpr const auto& kFields = dsp::kCalibrationFields;

std::string fmt_real(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  std::string s(buf, r.ptr);
  // TOML needs a '.' or an exponent to read a float; integers are accepted too, but keep the
  // written type unambiguous.
  if (s.find_first_of(".eE") == std::string::npos && s.find_first_of("ni") == std::string::npos) {
    s += ".0";
  }
  return s;
}

std::string range_text(const Field& f) {
  std::string s = f.lo_open ? "(" : "[";
  s += fmt_real(f.lo) + ", " + fmt_real(f.hi);
  s += f.hi_open ? ")" : "]";
  if (f.kind == Kind::kInt) {
    s = "[" + std::to_string(static_cast<long long>(f.lo)) + ", " +
        std::to_string(static_cast<long long>(f.hi)) + "]";
  }
  return s;
}

std::string quote(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
          char buf[8];
          std::snprintf(buf, sizeof(buf), "\\u%04x", static_cast<unsigned>(c));
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

// "FILE:LINE: " prefix for a node (line only when toml++ knows it).
std::string where(const std::string& origin, const toml::node& n) {
  const auto& b = n.source().begin;
  if (b.line > 0) return origin + ":" + std::to_string(b.line) + ": ";
  return origin + ": ";
}

// A real number: TOML float or integer.
bool get_real(const toml::node& n, double* v) {
  if (!n.is_floating_point() && !n.is_integer()) return false;
  const std::optional<double> d = n.value<double>();
  if (!d.has_value()) return false;
  *v = *d;
  return true;
}

std::string describe(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return fmt_real(v);
}

// Applies one sensor-table key to `cal`. `path` is the dotted key for messages.
Status apply_field(const Field& f, const toml::node& n, const std::string& path,
                   const std::string& origin, Calibration* cal) {
  const std::string at = where(origin, n) + "key \"" + path + "\" ";
  switch (f.kind) {
    case Kind::kReal: {
      double v = 0.0;
      if (!get_real(n, &v)) return Status::error(at + "must be a number, got " + type_name(n));
      if (!dsp::field_in_range(f, v)) {
        return Status::error(at + "must be in " + range_text(f) + ", got " + describe(v));
      }
      cal->*(f.real) = v;
      return {};
    }
    case Kind::kInt: {
      const auto* i = n.as_integer();
      if (i == nullptr) return Status::error(at + "must be an integer, got " + type_name(n));
      const auto v = i->get();
      if (v < static_cast<std::int64_t>(f.lo) || v > static_cast<std::int64_t>(f.hi)) {
        return Status::error(at + "must be an integer in " + range_text(f) + ", got " +
                             std::to_string(v));
      }
      cal->*(f.integer) = static_cast<int>(v);
      return {};
    }
    case Kind::kVec3: {
      const auto* a = n.as_array();
      if (a == nullptr) {
        return Status::error(at + "must be an array of 3 numbers, got " + type_name(n));
      }
      if (a->size() != 3) {
        return Status::error(at + "must have 3 elements (x, y, z), got " +
                             std::to_string(a->size()));
      }
      std::array<double, 3> v{};
      for (std::size_t k = 0; k < 3; ++k) {
        const toml::node* e = a->get(k);
        if (e == nullptr || !get_real(*e, &v[k])) {
          return Status::error(at + "element " + std::to_string(k) + " must be a number, got " +
                               (e ? type_name(*e) : std::string("nothing")));
        }
        if (!dsp::field_in_range(f, v[k])) {
          return Status::error(at + "element " + std::to_string(k) + " must be in " +
                               range_text(f) + ", got " + describe(v[k]));
        }
      }
      cal->*(f.vec) = v;
      return {};
    }
    case Kind::kProxy: {
      const auto* s = n.as_string();
      if (s == nullptr) return Status::error(at + "must be a string, got " + type_name(n));
      dsp::VelocityProxy p{};
      if (!parse_proxy_name(s->get(), &p)) {
        std::string names;
        for (const auto& pn : dsp::kVelocityProxyNames)
          names += std::string(names.empty() ? "" : ", ") + pn.name;
        return Status::error(at + "must be one of " + names + ", got \"" + s->get() + "\"");
      }
      cal->velocity_proxy = p;
      return {};
    }
  }
  return Status::error(at + "has an unknown kind");
}

const Field* find_field(std::string_view key) {
  for (const auto& f : kFields) {
    if (key == f.key) return &f;
  }
  return nullptr;
}

std::string unknown_key_message(const std::string& origin, const toml::node& n,
                                const std::string& path, const std::string& allowed) {
  return where(origin, n) + "unknown key \"" + path + "\" (allowed here: " + allowed + ")";
}

std::string sensor_key_list() {
  std::string s;
  for (const auto& f : kFields) s += std::string(s.empty() ? "" : ", ") + f.key;
  return s;
}

// Applies a sensor table ([sensor], [left], [right]) to the calibrations in `targets`.
Status apply_sensor_table(const toml::table& t, const std::string& name, const std::string& origin,
                          const std::vector<Calibration*>& targets) {
  for (auto&& [k, v] : t) {
    const std::string key(k.str());
    const std::string path = name + "." + key;
    const Field* f = find_field(key);
    if (f == nullptr) {
      return Status::error(unknown_key_message(origin, v, path, sensor_key_list()));
    }
    for (Calibration* c : targets) {
      if (Status s = apply_field(*f, v, path, origin, c); !s) return s;
    }
  }
  return {};
}

Status apply_paper_keys(const toml::table& t, const std::string& name, const std::string& origin,
                        const std::vector<PaperScales*>& targets, bool allow_subtables) {
  static const Field& rot = *find_field("rotation_scale");
  for (auto&& [k, v] : t) {
    const std::string key(k.str());
    const std::string path = name + "." + key;
    if (allow_subtables && (key == "left" || key == "right")) continue;
    if (key != "rotation_scale" && key != "translation_scale") {
      return Status::error(unknown_key_message(
          origin, v, path,
          allow_subtables ? "rotation_scale, translation_scale, [paper.left], [paper.right]"
                          : "rotation_scale, translation_scale"));
    }
    for (PaperScales* p : targets) {
      Calibration scratch;
      if (Status s = apply_field(rot, v, path, origin, &scratch); !s) return s;
      (key == "rotation_scale" ? p->rotation_scale : p->translation_scale) = scratch.rotation_scale;
    }
  }
  return {};
}

Status parse_meta(const toml::table& t, const std::string& origin, CalibrationMeta* meta) {
  for (auto&& [k, v] : t) {
    const std::string key(k.str());
    const std::string path = "meta." + key;
    if (key == "generator" || key == "created" || key == "note") {
      const auto* s = v.as_string();
      if (s == nullptr) {
        return Status::error(where(origin, v) + "key \"" + path + "\" must be a string, got " +
                             type_name(v));
      }
      (key == "generator" ? meta->generator
       : key == "created" ? meta->created
                          : meta->note) = s->get();
    } else if (key == "recordings") {
      const auto* a = v.as_array();
      if (a == nullptr) {
        return Status::error(where(origin, v) + "key \"" + path +
                             "\" must be an array of strings, got " + type_name(v));
      }
      meta->recordings.clear();
      for (const auto& e : *a) {
        const auto* s = e.as_string();
        if (s == nullptr) {
          return Status::error(where(origin, e) + "key \"" + path +
                               "\" must hold only strings, got " + type_name(e));
        }
        meta->recordings.push_back(s->get());
      }
    } else {
      return Status::error(
          unknown_key_message(origin, v, path, "generator, created, note, recordings"));
    }
  }
  return {};
}

const toml::table* sub_table(const toml::table& root, std::string_view key,
                             const std::string& origin, const std::string& path, Status* err) {
  const toml::node* n = root.get(key);
  if (n == nullptr) return nullptr;
  const auto* t = n->as_table();
  if (t == nullptr) {
    *err = Status::error(where(origin, *n) + "key \"" + path + "\" must be a table, got " +
                         type_name(*n));
  }
  return t;
}

Status parse_impl(std::string_view text, const std::string& origin, CalibrationSet* out) {
  if (std::string bad = check_toml_characters(text, origin); !bad.empty()) {
    return Status::error(std::move(bad));
  }
  toml::parse_result parsed = toml::parse(text, origin);
  if (!parsed) {
    const toml::parse_error& e = parsed.error();
    const auto& b = e.source().begin;
    return Status::error(origin + ":" + std::to_string(b.line) + ":" + std::to_string(b.column) +
                         ": TOML syntax error: " + std::string(e.description()));
  }
  const toml::table& root = parsed.table();

  // format and version first: a file of another kind or a newer version is reported as such
  // rather than as a pile of unknown keys.
  const toml::node* fmt = root.get("format");
  if (fmt == nullptr) {
    return Status::error(origin + ": missing required key \"format\" (must be \"" +
                         std::string(kCalibrationFormat) + "\")");
  }
  if (fmt->as_string() == nullptr || fmt->as_string()->get() != kCalibrationFormat) {
    return Status::error(where(origin, *fmt) + "key \"format\" must be \"" +
                         std::string(kCalibrationFormat) + "\"" +
                         (fmt->as_string() ? ", got \"" + fmt->as_string()->get() + "\""
                                           : ", got " + type_name(*fmt)));
  }
  const toml::node* ver = root.get("version");
  if (ver == nullptr) {
    return Status::error(origin + ": missing required key \"version\" (must be " +
                         std::to_string(kCalibrationVersion) + ")");
  }
  if (ver->as_integer() == nullptr) {
    return Status::error(where(origin, *ver) + "key \"version\" must be an integer, got " +
                         type_name(*ver));
  }
  if (ver->as_integer()->get() != kCalibrationVersion) {
    return Status::error(where(origin, *ver) + "version " +
                         std::to_string(ver->as_integer()->get()) +
                         " is not supported (this reader knows version " +
                         std::to_string(kCalibrationVersion) + ")");
  }
  for (auto&& [k, v] : root) {
    const std::string key(k.str());
    if (key != "format" && key != "version" && key != "meta" && key != "sensor" && key != "left" &&
        key != "right" && key != "paper") {
      return Status::error(unknown_key_message(
          origin, v, key, "format, version, [meta], [sensor], [left], [right], [paper]"));
    }
  }

  CalibrationSet set;  // defaults
  Status err;
  if (const auto* t = sub_table(root, "meta", origin, "meta", &err)) {
    if (Status s = parse_meta(*t, origin, &set.meta); !s) return s;
  }
  if (!err) return err;
  if (const auto* t = sub_table(root, "sensor", origin, "sensor", &err)) {
    set.fitted = true;
    if (Status s =
            apply_sensor_table(*t, "sensor", origin, {&set.sensor[kLeft], &set.sensor[kRight]});
        !s) {
      return s;
    }
  }
  if (!err) return err;
  const char* names[2] = {"left", "right"};
  for (std::size_t i = 0; i < 2; ++i) {
    if (const auto* t = sub_table(root, names[i], origin, names[i], &err)) {
      set.fitted = true;
      if (Status s = apply_sensor_table(*t, names[i], origin, {&set.sensor[i]}); !s) return s;
    }
    if (!err) return err;
  }
  // Paper scales default to the (merged) sensor scales, then [paper], then [paper.left/right].
  for (std::size_t i = 0; i < 2; ++i) {
    set.paper[i].rotation_scale = set.sensor[i].rotation_scale;
    set.paper[i].translation_scale = set.sensor[i].translation_scale;
  }
  if (const auto* t = sub_table(root, "paper", origin, "paper", &err)) {
    if (Status s =
            apply_paper_keys(*t, "paper", origin, {&set.paper[kLeft], &set.paper[kRight]}, true);
        !s) {
      return s;
    }
    for (std::size_t i = 0; i < 2; ++i) {
      const std::string path = std::string("paper.") + names[i];
      if (const auto* st = sub_table(*t, names[i], origin, path, &err)) {
        if (Status s = apply_paper_keys(*st, path, origin, {&set.paper[i]}, false); !s) return s;
      }
      if (!err) return err;
    }
  }
  if (!err) return err;
  if (Status s = validate(set, origin); !s) return s;
  *out = std::move(set);
  return {};
}

bool same(const Calibration& a, const Calibration& b, const Field& f) {
  switch (f.kind) {
    case Kind::kReal:
      return a.*(f.real) == b.*(f.real);
    case Kind::kInt:
      return a.*(f.integer) == b.*(f.integer);
    case Kind::kVec3:
      return a.*(f.vec) == b.*(f.vec);
    case Kind::kProxy:
      return a.velocity_proxy == b.velocity_proxy;
  }
  return false;
}

std::string value_text(const Calibration& c, const Field& f) {
  switch (f.kind) {
    case Kind::kReal:
      return fmt_real(c.*(f.real));
    case Kind::kInt:
      return std::to_string(c.*(f.integer));
    case Kind::kVec3: {
      const auto& v = c.*(f.vec);
      return "[" + fmt_real(v[0]) + ", " + fmt_real(v[1]) + ", " + fmt_real(v[2]) + "]";
    }
    case Kind::kProxy:
      return quote(proxy_name(c.velocity_proxy));
  }
  return "";
}

// Why the calibration file could not be read, and what to give instead.
std::string read_error_message(const std::string& name, const fileio::ReadResult& r) {
  switch (r.error) {
    case fileio::ReadError::kNone:
      break;
    case fileio::ReadError::kNotFound:
      return name + ": no such file";
    case fileio::ReadError::kOpen:
      return name + ": cannot open for reading" + fileio::os_error(r.os_errno);
    case fileio::ReadError::kNotRegular:
      return name + ": is " + r.kind +
             ", expected a calibration file (a regular file); give the path of one";
    case fileio::ReadError::kTooLarge:
      return name + ": file is larger than " + fileio::size_text(kMaxCalibrationBytes) +
             "; not a calibration file";
    case fileio::ReadError::kRead:
      return name + ": read error" + fileio::os_error(r.os_errno);
  }
  return name + ": unexpected error while reading";
}

// A rule's operand (rules name real fields: tests/dsp/test_calibration_fields.cpp).
double rule_operand(const Calibration& c, const char* key) {
  const Field* f = dsp::find_calibration_field(key);
  return f != nullptr && f->real != nullptr ? c.*(f->real) : std::nan("");
}

std::string vec_text(const std::array<double, 3>& v) {
  return "[" + fmt_real(v[0]) + ", " + fmt_real(v[1]) + ", " + fmt_real(v[2]) + "]";
}

}  // namespace

const char* proxy_name(dsp::VelocityProxy p) noexcept {
  for (const auto& pn : dsp::kVelocityProxyNames) {
    if (pn.value == p) return pn.name;
  }
  return "unknown";
}

bool parse_proxy_name(std::string_view name, dsp::VelocityProxy* out) noexcept {
  for (const auto& pn : dsp::kVelocityProxyNames) {
    if (name == pn.name) {
      *out = pn.value;
      return true;
    }
  }
  return false;
}

std::vector<std::string> sensor_keys() {
  std::vector<std::string> k;
  for (const auto& f : kFields) k.emplace_back(f.key);
  return k;
}

std::array<dsp::Calibration, 2> CalibrationSet::for_method(dsp::FusionMethod method) const {
  std::array<dsp::Calibration, 2> c = sensor;
  if (method == dsp::FusionMethod::kPaper) {
    for (std::size_t i = 0; i < 2; ++i) {
      c[i].rotation_scale = paper[i].rotation_scale;
      c[i].translation_scale = paper[i].translation_scale;
    }
  }
  return c;
}

Status validate(const CalibrationSet& set, const std::string& origin) noexcept {
  try {
    const char* names[2] = {"left", "right"};
    for (std::size_t i = 0; i < 2; ++i) {
      const Calibration& c = set.sensor[i];
      for (const auto& f : kFields) {
        const std::string at = origin + ": key \"" + names[i] + "." + f.key + "\" ";
        switch (f.kind) {
          case Kind::kReal:
            if (!dsp::field_in_range(f, c.*(f.real))) {
              return Status::error(at + "must be in " + range_text(f) + ", got " +
                                   describe(c.*(f.real)));
            }
            break;
          case Kind::kInt:
            if (!dsp::field_in_range(f, c.*(f.integer))) {
              return Status::error(at + "must be an integer in " + range_text(f) + ", got " +
                                   std::to_string(c.*(f.integer)));
            }
            break;
          case Kind::kVec3:
            for (double v : c.*(f.vec)) {
              if (!dsp::field_in_range(f, v)) {
                return Status::error(at + "elements must be in " + range_text(f) + ", got " +
                                     describe(v));
              }
            }
            break;
          case Kind::kProxy:
            if (!dsp::field_valid(f, c)) {
              return Status::error(at + "has an unknown value " +
                                   std::to_string(static_cast<int>(c.velocity_proxy)));
            }
            break;
        }
      }
      for (const auto& r : dsp::kCalibrationRules) {
        if (r.holds(c)) continue;
        const double a = rule_operand(c, r.key);
        const double b = rule_operand(c, r.other);
        return Status::error(origin + ": key \"" + names[i] + "." + r.key + "\" (" + fmt_real(a) +
                             ") " + r.relation + " \"" + names[i] + "." + r.other + "\" (" +
                             fmt_real(b) + ")" + r.note);
      }
      const Field& rot = *find_field("rotation_scale");
      for (const auto* v : {&set.paper[i].rotation_scale, &set.paper[i].translation_scale}) {
        for (double x : *v) {
          if (!dsp::field_in_range(rot, x)) {
            return Status::error(
                origin + ": key \"paper." + names[i] + "." +
                (v == &set.paper[i].rotation_scale ? "rotation_scale" : "translation_scale") +
                "\" elements must be in " + range_text(rot) + ", got " + describe(x));
          }
        }
      }
    }
    // The pipeline's own check, for both fusion methods (catches any rule added in dsp/).
    for (auto method : {dsp::FusionMethod::kJoint, dsp::FusionMethod::kPaper}) {
      const auto cals = set.for_method(method);
      for (std::size_t i = 0; i < 2; ++i) {
        if (dsp::validate(cals[i]) != dsp::Status::kOk) {
          return Status::error(origin + ": the " + names[i] +
                               " calibration is rejected by dsp::validate (" +
                               dsp::to_string(dsp::validate(cals[i])) + ")");
        }
      }
    }
    return {};
  } catch (...) {
    return Status::error(origin + ": out of memory while validating");
  }
}

Status parse_calibration(std::string_view text, const std::string& origin,
                         CalibrationSet* out) noexcept {
  if (out == nullptr) return Status::error(origin + ": null output");
  try {
    return parse_impl(text, origin, out);
  } catch (const std::exception& e) {
    return Status::error(origin + ": " + e.what());
  } catch (...) {
    return Status::error(origin + ": unexpected error while parsing");
  }
}

Status load_calibration(const std::filesystem::path& file, CalibrationSet* out) noexcept {
  try {
    std::string text;
    const fileio::ReadResult r = fileio::read_regular_file(file, kMaxCalibrationBytes, &text);
    if (!r.ok()) return Status::error(read_error_message(file.string(), r));
    return parse_calibration(text, file.string(), out);
  } catch (...) {
    return Status::error(file.string() + ": unexpected error while reading");
  }
}

bool format_calibration(const CalibrationSet& set, std::string* text, std::string* error) noexcept {
  try {
    if (Status s = validate(set, "calibration"); !s) {
      if (error) *error = s.message();
      return false;
    }
    std::string o;
    o += "# tacse3 calibration file, format version 1 (docs/calibration.md).\n";
    o += "# Units are SI. [sensor] applies to both pads; [left] / [right] override single keys.\n";
    o += "format = " + quote(kCalibrationFormat) + "\n";
    o += "version = " + std::to_string(kCalibrationVersion) + "\n\n";
    o += "[meta]\n";
    o += "generator = " + quote(set.meta.generator) + "\n";
    o += "created = " + quote(set.meta.created) + "\n";
    o += "note = " + quote(set.meta.note) + "\n";
    o += "recordings = [";
    for (std::size_t i = 0; i < set.meta.recordings.size(); ++i) {
      o += (i ? ", " : "") + quote(set.meta.recordings[i]);
    }
    o += "]\n\n";
    const Calibration& l = set.sensor[kLeft];
    const Calibration& r = set.sensor[kRight];
    o += "[sensor]\n";
    for (const auto& f : kFields) {
      if (same(l, r, f)) o += std::string(f.key) + " = " + value_text(l, f) + "\n";
    }
    const char* names[2] = {"left", "right"};
    for (std::size_t i = 0; i < 2; ++i) {
      o += std::string("\n[") + names[i] + "]\n";
      for (const auto& f : kFields) {
        if (!same(l, r, f)) o += std::string(f.key) + " = " + value_text(set.sensor[i], f) + "\n";
      }
    }
    o += "\n# Per-axis scales used instead of the ones above with the paper fusion (--method "
         "paper).\n[paper]\n";
    const PaperScales& pl = set.paper[kLeft];
    const PaperScales& pr = set.paper[kRight];
    if (pl.rotation_scale == pr.rotation_scale) {
      o += "rotation_scale = " + vec_text(pl.rotation_scale) + "\n";
    }
    if (pl.translation_scale == pr.translation_scale) {
      o += "translation_scale = " + vec_text(pl.translation_scale) + "\n";
    }
    for (std::size_t i = 0; i < 2; ++i) {
      o += std::string("\n[paper.") + names[i] + "]\n";
      if (pl.rotation_scale != pr.rotation_scale) {
        o += "rotation_scale = " + vec_text(set.paper[i].rotation_scale) + "\n";
      }
      if (pl.translation_scale != pr.translation_scale) {
        o += "translation_scale = " + vec_text(set.paper[i].translation_scale) + "\n";
      }
    }
    *text = std::move(o);
    return true;
  } catch (...) {
    if (error) *error = "out of memory while formatting the calibration";
    return false;
  }
}

Status check_calibration_output(const std::filesystem::path& file) noexcept {
  try {
    std::string error;
    if (!fileio::check_output_file(file, &error)) return Status::error(error);
    return {};
  } catch (...) {
    return Status::error(file.string() + ": unexpected error while checking the output file");
  }
}

Status save_calibration(const std::filesystem::path& file, const CalibrationSet& set) noexcept {
  try {
    const std::string origin = file.string();
    std::string text, error;
    if (!format_calibration(set, &text, &error)) return Status::error(origin + ": " + error);
    // Round trip: the writer must produce a file the reader accepts and reads back identically.
    CalibrationSet back;
    if (Status s = parse_calibration(text, origin, &back); !s) {
      return Status::error("internal error: written calibration does not parse: " + s.message());
    }
    if (!fileio::write_file_atomically(file, text, &error)) return Status::error(error);
    return {};
  } catch (...) {
    return Status::error(file.string() + ": unexpected error while writing");
  }
}

namespace {

// The lexical state of TOML text that decides where non-ASCII bytes may stand.
class TomlCharacterScan {
 public:
  explicit TomlCharacterScan(std::string_view text) : t_(text) {}

  // Index of the first byte toml++ must not see, or npos.
  std::size_t first_bad() {
    while (i_ < t_.size()) {
      const bool bad = state_ == State::kPlain ? plain() : in_string();
      if (bad) return i_;
    }
    return std::string_view::npos;
  }
  // The bad byte follows a backslash in a basic string.
  bool after_backslash() const { return escape_; }

 private:
  enum class State { kPlain, kBasic, kLiteral, kMultiBasic, kMultiLiteral };

  bool starts(std::string_view s) const { return t_.substr(i_, s.size()) == s; }
  static bool ascii(char c) { return static_cast<unsigned char>(c) < 0x80; }

  bool plain() {
    const char c = t_[i_];
    if (!ascii(c)) return true;
    if (c == '#') {
      const std::size_t end = t_.find('\n', i_);
      i_ = end == std::string_view::npos ? t_.size() : end;
    } else if (starts("\"\"\"") || starts("'''")) {
      state_ = c == '"' ? State::kMultiBasic : State::kMultiLiteral;
      i_ += 3;
    } else {
      if (c == '"') state_ = State::kBasic;
      if (c == '\'') state_ = State::kLiteral;
      ++i_;
    }
    return false;
  }

  bool in_string() {
    const char c = t_[i_];
    if ((state_ == State::kBasic || state_ == State::kLiteral) && c == '\n') {
      state_ = State::kPlain;  // an unterminated string: toml++ reports it
    } else if ((state_ == State::kBasic && c == '"') || (state_ == State::kLiteral && c == '\'')) {
      state_ = State::kPlain;
    } else if ((state_ == State::kMultiBasic && starts("\"\"\"")) ||
               (state_ == State::kMultiLiteral && starts("'''"))) {
      state_ = State::kPlain;
      i_ += 2;
    } else if (c == '\\' && (state_ == State::kBasic || state_ == State::kMultiBasic)) {
      // toml++ tests the character after a backslash, and after the blanks that follow one,
      // for whitespace; every TOML escape is ASCII, so a non-ASCII one there is refused here.
      std::size_t j = i_ + 1;
      while (j < t_.size() && (t_[j] == ' ' || t_[j] == '\t' || t_[j] == '\r')) ++j;
      if (j < t_.size() && !ascii(t_[j])) {
        escape_ = true;
        i_ = j;
        return true;
      }
      if (state_ == State::kMultiBasic && line_ending_backslash()) return !ascii(t_[i_]);
      ++i_;  // the escaped character
    }
    ++i_;
    return false;
  }

  // At a backslash in a multi-line basic string: if only whitespace follows it on its line, moves
  // to the first character after the whitespace and newlines that follow (toml++ tests that
  // one for whitespace) and returns true.
  bool line_ending_backslash() {
    std::size_t j = i_ + 1;
    while (j < t_.size() && (t_[j] == ' ' || t_[j] == '\t' || t_[j] == '\r')) ++j;
    if (j >= t_.size() || t_[j] != '\n') return false;
    while (j < t_.size() && (t_[j] == ' ' || t_[j] == '\t' || t_[j] == '\r' || t_[j] == '\n')) ++j;
    i_ = j < t_.size() ? j : t_.size() - 1;
    return true;
  }

  std::string_view t_;
  std::size_t i_ = 0;
  State state_ = State::kPlain;
  bool escape_ = false;
};

// toml++'s error paths test the characters after a bad token for whitespace as well, wherever
// they are; the copy of the text with every non-ASCII byte made 'x' has the same syntax errors at
// the same places and reaches none of them. Returns its syntax error, or "" when it parses.
std::string syntax_error_of_ascii_copy(std::string_view text, const std::string& origin) {
  const auto non_ascii = [](char c) { return static_cast<unsigned char>(c) >= 0x80; };
  if (std::none_of(text.begin(), text.end(), non_ascii)) return {};
  std::string copy(text);
  std::replace_if(copy.begin(), copy.end(), non_ascii, 'x');
  const toml::parse_result parsed = toml::parse(copy, origin);
  if (parsed) return {};
  const auto& b = parsed.error().source().begin;
  return origin + ":" + std::to_string(b.line) + ":" + std::to_string(b.column) +
         ": TOML syntax error: " + std::string(parsed.error().description());
}

}  // namespace

std::string check_toml_characters(std::string_view text, const std::string& origin) {
  TomlCharacterScan scan(text);
  const std::size_t bad = scan.first_bad();
  if (bad == std::string_view::npos) return syntax_error_of_ascii_copy(text, origin);
  const std::size_t line_start = text.rfind('\n', bad);
  const std::size_t line =
      1 + static_cast<std::size_t>(
              std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(bad), '\n'));
  const std::size_t column = line_start == std::string_view::npos ? bad + 1 : bad - line_start;
  return origin + ":" + std::to_string(line) + ":" + std::to_string(column) +
         (scan.after_backslash()
              ? ": TOML syntax error: a non-ASCII character after a backslash (no "
                "TOML escape starts with one)"
              : ": TOML syntax error: a non-ASCII character outside a string or comment");
}

std::string type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a float";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::table:
      return "a table";
    default:
      return "a date/time";
  }
}

std::filesystem::path find_sim_calibration(const std::filesystem::path& exe_dir,
                                           const std::filesystem::path& source_file) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!exe_dir.empty()) {
    const fs::path installed =
        (exe_dir / ".." / "share" / "tacse3" / "sim-calibration.toml").lexically_normal();
    if (fs::is_regular_file(installed, ec)) return installed;
  }
  if (!source_file.empty() && fs::is_regular_file(source_file, ec)) return source_file;
  return {};
}

std::filesystem::path executable_dir() {
  std::error_code ec;
  const auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path() : p.parent_path();
}

}  // namespace tacse3::config
