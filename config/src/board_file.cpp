// SPDX-License-Identifier: Apache-2.0
// tacse3 config: board file reader (toml++, no exceptions) with every key validated and named.
#include "tacse3/config/board_file.hpp"

#include "tacse3/config/listen_address.hpp"

// Header-only toml++ without exceptions, as in calibration_file.cpp: a bad board file must come
// back as a message, never as an exception or an assert. No header of config/ exposes toml++.
#define TOML_HEADER_ONLY 1
#define TOML_EXCEPTIONS 0
#define TOML_ENABLE_FORMATTERS 0
#define TOML_ASSERT(expr) static_assert(true)
#include <toml++/toml.h>

#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <limits>
#include <optional>
#include <sstream>
#include <system_error>

#include "tacse3/config/toml_names.hpp"
#include "tacse3/fileio/file_io.hpp"

namespace tacse3::config {

const char* to_string(CameraBackend b) noexcept {
  switch (b) {
    case CameraBackend::kSim:
      return "sim";
    case CameraBackend::kReplay:
      return "replay";
    case CameraBackend::kV4l2:
      return "v4l2";
    case CameraBackend::kLibcamera:
      return "libcamera";
  }
  return "?";
}

namespace {

using config::type_name;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Reads keys of one file, remembering the first error. Every message is
// "FILE:LINE: key \"table.key\" ..." so the user can go straight to the line.
class Reader {
 public:
  explicit Reader(std::string origin) : origin_(std::move(origin)) {}

  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }

  bool fail(const toml::node* n, const std::string& msg) {
    if (!error_.empty()) return false;
    std::string at = origin_;
    if (n != nullptr && n->source().begin.line > 0) {
      at += ":" + std::to_string(n->source().begin.line);
    }
    error_ = at + ": " + msg;
    return false;
  }

  static std::string join(const std::string& table, std::string_view key) {
    return table.empty() ? std::string(key) : table + "." + std::string(key);
  }

  // Every key of `t` must be in `allowed` (typos must not be ignored silently).
  bool only_keys(const toml::table& t, const std::string& table,
                 std::initializer_list<const char*> allowed) {
    for (auto&& [k, v] : t) {
      bool found = false;
      for (const char* a : allowed) found = found || k.str() == a;
      if (!found) {
        std::string list;
        for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
        return fail(&v,
                    "unknown key \"" + join(table, k.str()) + "\" (allowed here: " + list + ")");
      }
    }
    return true;
  }

  const toml::table* table(const toml::table& parent, const char* key, const std::string& path) {
    const toml::node* n = parent.get(key);
    if (n == nullptr) return nullptr;
    if (!n->is_table()) {
      fail(n, "key \"" + join(path, key) + "\" must be a table, got " + type_name(*n));
      return nullptr;
    }
    return n->as_table();
  }

  void integer(const toml::table& t, const char* key, const std::string& path, long long lo,
               long long hi, int* out) {
    long long v = *out;
    integer64(t, key, path, lo, hi, &v);
    *out = static_cast<int>(v);
  }

  void integer64(const toml::table& t, const char* key, const std::string& path, long long lo,
                 long long hi, long long* out) {
    const toml::node* n = t.get(key);
    if (n == nullptr || !ok()) return;
    const auto* i = n->as_integer();
    if (i == nullptr) {
      fail(n, "key \"" + join(path, key) + "\" must be an integer, got " + type_name(*n));
      return;
    }
    const long long v = i->get();
    if (v < lo || v > hi) {
      fail(n, "key \"" + join(path, key) + "\" must be in [" + std::to_string(lo) + ", " +
                  std::to_string(hi) + "], got " + std::to_string(v));
      return;
    }
    *out = v;
  }

  void real(const toml::table& t, const char* key, const std::string& path, double lo, double hi,
            double* out) {
    const toml::node* n = t.get(key);
    if (n == nullptr || !ok()) return;
    if (!n->is_floating_point() && !n->is_integer()) {
      fail(n, "key \"" + join(path, key) + "\" must be a number, got " + type_name(*n));
      return;
    }
    const double v = n->value<double>().value_or(kNaN);
    if (!std::isfinite(v) || v < lo || v > hi) {
      fail(n, "key \"" + join(path, key) + "\" must be in [" + num(lo) + ", " + num(hi) +
                  "], got " + num(v));
      return;
    }
    *out = v;
  }

  void boolean(const toml::table& t, const char* key, const std::string& path, bool* out) {
    const toml::node* n = t.get(key);
    if (n == nullptr || !ok()) return;
    if (!n->is_boolean()) {
      fail(n, "key \"" + join(path, key) + "\" must be true or false, got " + type_name(*n));
      return;
    }
    *out = n->as_boolean()->get();
  }

  void string(const toml::table& t, const char* key, const std::string& path, std::string* out) {
    const toml::node* n = t.get(key);
    if (n == nullptr || !ok()) return;
    if (!n->is_string()) {
      fail(n, "key \"" + join(path, key) + "\" must be a string, got " + type_name(*n));
      return;
    }
    *out = n->as_string()->get();
  }

  // A string that must be one of `names`; *out = its index.
  template <typename E>
  void choice(const toml::table& t, const char* key, const std::string& path,
              std::initializer_list<std::pair<const char*, E>> names, E* out) {
    const toml::node* n = t.get(key);
    if (n == nullptr || !ok()) return;
    std::string list;
    for (const auto& [name, value] : names) list += std::string(list.empty() ? "" : " | ") + name;
    if (!n->is_string()) {
      fail(n, "key \"" + join(path, key) + "\" must be one of " + list + ", got " + type_name(*n));
      return;
    }
    const std::string& s = n->as_string()->get();
    for (const auto& [name, value] : names) {
      if (s == name) {
        *out = value;
        return;
      }
    }
    fail(n, "key \"" + join(path, key) + "\" must be one of " + list + ", got \"" + s + "\"");
  }

  // [left, right]: an array of two integers, each in [lo, hi].
  void integer_pair(const toml::table& t, const char* key, const std::string& path, long long lo,
                    long long hi, std::array<int, 2>* out) {
    const toml::node* n = t.get(key);
    if (n == nullptr || !ok()) return;
    const std::string name = "key \"" + join(path, key) + "\" ";
    const auto* a = n->as_array();
    if (a == nullptr || a->size() != 2) {
      fail(n, name + "must be [left, right], two integers, got " +
                  (a ? std::to_string(a->size()) + " elements" : type_name(*n)));
      return;
    }
    std::array<int, 2> v{};
    for (std::size_t i = 0; i < 2; ++i) {
      const auto* e = a->get(i) ? a->get(i)->as_integer() : nullptr;
      if (e == nullptr || e->get() < lo || e->get() > hi) {
        fail(n, name + "element " + std::to_string(i) + " must be an integer in [" +
                    std::to_string(lo) + ", " + std::to_string(hi) + "]");
        return;
      }
      v[i] = static_cast<int>(e->get());
    }
    *out = v;
  }

  // A 3x3 rotation matrix: 3 arrays of 3 numbers, orthonormal with det +1.
  void rotation(const toml::table& t, const char* key, const std::string& path,
                std::array<std::array<double, 3>, 3>* out) {
    const toml::node* n = t.get(key);
    if (n == nullptr || !ok()) return;
    const std::string name = "key \"" + join(path, key) + "\" ";
    const auto* rows = n->as_array();
    if (rows == nullptr || rows->size() != 3) {
      fail(n, name + "must be a 3x3 matrix [[r00,r01,r02],[r10,r11,r12],[r20,r21,r22]], got " +
                  (rows ? std::to_string(rows->size()) + " rows" : type_name(*n)));
      return;
    }
    std::array<std::array<double, 3>, 3> m{};
    for (std::size_t r = 0; r < 3; ++r) {
      const auto* row = rows->get(r) ? rows->get(r)->as_array() : nullptr;
      if (row == nullptr || row->size() != 3) {
        fail(n, name + "row " + std::to_string(r) + " must be an array of 3 numbers");
        return;
      }
      for (std::size_t c = 0; c < 3; ++c) {
        const toml::node* e = row->get(c);
        if (e == nullptr || (!e->is_floating_point() && !e->is_integer())) {
          fail(n, name + "element [" + std::to_string(r) + "][" + std::to_string(c) +
                      "] must be a number");
          return;
        }
        m[r][c] = e->value<double>().value_or(kNaN);
        if (!std::isfinite(m[r][c])) {
          fail(n, name + "element [" + std::to_string(r) + "][" + std::to_string(c) +
                      "] must be finite");
          return;
        }
      }
    }
    Eigen::Matrix3d R;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c)
        R(r, c) = m[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)];
    }
    if ((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-6 || R.determinant() <= 0.0) {
      fail(n, name + "must be a rotation matrix (orthonormal, determinant +1)");
      return;
    }
    *out = m;
  }

  // A pose [x, y, z, qw, qx, qy, qz]: 7 finite numbers, the quaternion unit within
  // kBoardUnitQuaternionTolerance (then normalised).
  void pose(const toml::table& t, const char* key, const std::string& path,
            std::array<double, 7>* out) {
    const toml::node* n = t.get(key);
    if (n == nullptr || !ok()) return;
    const std::string name = "key \"" + join(path, key) + "\" ";
    const auto* a = n->as_array();
    if (a == nullptr || a->size() != 7) {
      fail(n, name + "must be [x, y, z, qw, qx, qy, qz] (metres, unit quaternion), got " +
                  (a ? std::to_string(a->size()) + " elements" : type_name(*n)));
      return;
    }
    std::array<double, 7> v{};
    for (std::size_t i = 0; i < 7; ++i) {
      const toml::node* e = a->get(i);
      v[i] = e != nullptr && (e->is_floating_point() || e->is_integer())
                 ? e->value<double>().value_or(kNaN)
                 : kNaN;
      if (!std::isfinite(v[i])) {
        fail(n, name + "element " + std::to_string(i) + " must be a finite number");
        return;
      }
    }
    const double norm = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
    if (std::abs(norm - 1.0) > kBoardUnitQuaternionTolerance) {
      fail(n, name + "quaternion (qw, qx, qy, qz) is not unit (norm " + num(norm) + ", tolerance " +
                  num(kBoardUnitQuaternionTolerance) + ")");
      return;
    }
    for (std::size_t i = 3; i < 7; ++i) v[i] /= norm;
    *out = v;
  }

 private:
  std::string origin_;
  std::string error_;
};

// [sim] object must be one of the simulator's presets: --check then refuses what the run would.
void check_sim_object(Reader& rd, const toml::table& t, const std::string& object) {
  if (!rd.ok() || t.get("object") == nullptr) return;
  std::string list;
  for (const char* name : kSimObjectNames) {
    if (object == name) return;
    list += std::string(list.empty() ? "" : " | ") + name;
  }
  rd.fail(t.get("object"),
          "key \"sim.object\" must be one of " + list + ", got \"" + object + "\"");
}

void read_sensor(Reader& rd, const toml::table& t, const std::string& path, SensorBoardConfig* s) {
  s->enabled = true;
  if (!rd.only_keys(t, path,
                    {"backend", "device", "width", "height", "fps", "buffer_count", "allow_mjpeg",
                     "rotation", "phase_us"})) {
    return;
  }
  if (t.get("backend") == nullptr) {
    rd.fail(&t, "missing required key \"" + path + ".backend\" (sim | replay | v4l2 | libcamera)");
    return;
  }
  rd.choice<CameraBackend>(t, "backend", path,
                           {{"sim", CameraBackend::kSim},
                            {"replay", CameraBackend::kReplay},
                            {"v4l2", CameraBackend::kV4l2},
                            {"libcamera", CameraBackend::kLibcamera}},
                           &s->backend);
  rd.string(t, "device", path, &s->device);
  // The pipeline is built for 320x240 (dsp::kWidth x kHeight); other sizes are rejected here
  // rather than by every frame.
  rd.integer(t, "width", path, 320, 320, &s->width);
  rd.integer(t, "height", path, 240, 240, &s->height);
  rd.integer(t, "fps", path, 1, 1000, &s->fps);
  rd.integer(t, "buffer_count", path, 2, 16, &s->buffer_count);
  rd.boolean(t, "allow_mjpeg", path, &s->allow_mjpeg);
  rd.rotation(t, "rotation", path, &s->rotation);
  rd.integer(t, "phase_us", path, 0, 1'000'000, &s->phase_us);
  if (!rd.ok()) return;
  if (t.get("phase_us") != nullptr && s->backend != CameraBackend::kReplay) {
    rd.fail(t.get("phase_us"), "key \"" + path + ".phase_us\" is for backend \"replay\" only");
    return;
  }
  const bool needs_device =
      s->backend == CameraBackend::kV4l2 || s->backend == CameraBackend::kReplay;
  if (needs_device && s->device.empty()) {
    rd.fail(t.get("backend"), "key \"" + path + ".device\" is required for backend \"" +
                                  to_string(s->backend) + "\"");
  }
}

void read_gpio_line(Reader& rd, const toml::table& parent, const char* key, GpioLine line,
                    GpioBoardConfig* g) {
  const std::string path = std::string("gpio.") + key;
  const toml::table* t = rd.table(parent, key, "gpio");
  if (t == nullptr) return;
  GpioLineConfig& l = g->lines.line(line);
  l.enabled = true;
  const bool input = !is_output(line);
  if (input) {
    if (!rd.only_keys(*t, path, {"offset", "name", "chip", "active_low", "bias", "debounce_ms"})) {
      return;
    }
  } else if (!rd.only_keys(*t, path, {"offset", "name", "chip", "active_low"})) {
    return;
  }
  rd.integer(*t, "offset", path, 0, 1023, &l.offset);
  rd.string(*t, "name", path, &l.name);
  rd.string(*t, "chip", path, &l.chip);
  rd.boolean(*t, "active_low", path, &l.active_low);
  if (input) {
    rd.choice<GpioBias>(*t, "bias", path,
                        {{"as-is", GpioBias::kAsIs},
                         {"disable", GpioBias::kDisable},
                         {"pull-up", GpioBias::kPullUp},
                         {"pull-down", GpioBias::kPullDown}},
                        &l.bias);
    rd.integer(*t, "debounce_ms", path, 0, 1000, &g->debounce_ms);
  }
  if (rd.ok() && l.offset < 0 && l.name.empty()) {
    rd.fail(t, "table \"" + path + "\" needs \"offset\" or \"name\"");
  }
}

bool parse_impl(std::string_view text, const std::string& origin, BoardConfig* out,
                std::string* error) {
  if (std::string bad = check_toml_characters(text, origin); !bad.empty()) {
    *error = std::move(bad);
    return false;
  }
  toml::parse_result parsed = toml::parse(text, origin);
  if (!parsed) {
    const auto& b = parsed.error().source().begin;
    *error = origin + ":" + std::to_string(b.line) + ":" + std::to_string(b.column) +
             ": TOML syntax error: " + std::string(parsed.error().description());
    return false;
  }
  const toml::table& root = parsed.table();
  Reader rd(origin);
  BoardConfig b;
  b.origin = origin;

  const toml::node* ver = root.get("version");
  if (ver == nullptr) {
    *error = origin + ": missing required key \"version\" (must be " +
             std::to_string(kBoardVersion) + ")";
    return false;
  }
  long long version = 0;
  rd.integer64(root, "version", "", kBoardVersion, kBoardVersion, &version);
  if (!rd.ok()) {
    *error = rd.error() + " (this daemon reads board schema version " +
             std::to_string(kBoardVersion) + ")";
    return false;
  }
  rd.only_keys(root, "",
               {"version", "name", "description", "sensors", "sim", "pipeline", "can", "gpio",
                "realtime", "record", "rig", "viewer"});
  rd.string(root, "name", "", &b.name);
  rd.string(root, "description", "", &b.description);

  if (const toml::table* sensors = rd.table(root, "sensors", "")) {
    rd.only_keys(*sensors, "sensors", {"left", "right"});
    if (const toml::table* t = rd.table(*sensors, "left", "sensors")) {
      read_sensor(rd, *t, "sensors.left", &b.sensors[0]);
    }
    if (const toml::table* t = rd.table(*sensors, "right", "sensors")) {
      read_sensor(rd, *t, "sensors.right", &b.sensors[1]);
      // The mirrored pad's default orientation (contract B) when the file gives none.
      if (rd.ok() && t->get("rotation") == nullptr) {
        b.sensors[1].rotation = {{{1, 0, 0}, {0, -1, 0}, {0, 0, -1}}};
      }
    }
  }
  if (rd.ok() && b.sensor_count() == 0) {
    *error = origin + ": no sensor: the board needs [sensors.left] and/or [sensors.right]";
    return false;
  }

  if (const toml::table* t = rd.table(root, "sim", "")) {
    rd.only_keys(*t, "sim",
                 {"object", "motion", "magnitude", "regime", "seed", "repeat", "realtime", "plan"});
    rd.string(*t, "object", "sim", &b.sim.object);
    check_sim_object(rd, *t, b.sim.object);
    rd.choice<std::string>(*t, "motion", "sim",
                           {{"rx", "rx"}, {"ry", "ry"}, {"rz", "rz"}, {"tx", "tx"}, {"ty", "ty"}},
                           &b.sim.motion);
    rd.real(*t, "magnitude", "sim", -360.0, 360.0, &b.sim.magnitude);
    rd.choice<std::string>(*t, "regime", "sim", {{"stick", "stick"}, {"slide", "slide"}},
                           &b.sim.regime);
    long long seed = static_cast<long long>(b.sim.seed);
    rd.integer64(*t, "seed", "sim", 0, INT64_MAX, &seed);
    b.sim.seed = static_cast<std::uint64_t>(seed);
    rd.boolean(*t, "repeat", "sim", &b.sim.repeat);
    rd.boolean(*t, "realtime", "sim", &b.sim.realtime);
    rd.string(*t, "plan", "sim", &b.sim.plan);
    if (rd.ok() && t->get("plan") != nullptr) {
      if (b.sim.plan.empty()) {
        rd.fail(t->get("plan"), "key \"sim.plan\" must name a plan CSV file, got \"\"");
      } else if (!std::filesystem::path(b.sim.plan).is_absolute()) {
        b.sim.plan = (std::filesystem::path(origin).parent_path() / b.sim.plan).string();
      }
    }
    // The plan's motions are timed by the controller's waits: they play in real time.
    if (rd.ok() && !b.sim.plan.empty() && !b.sim.realtime) {
      rd.fail(t->get("realtime"),
              "key \"sim.realtime\" must be true with sim.plan (the plan's "
              "motions play in real time, as the controller waits for them)");
    }
  }

  if (const toml::table* t = rd.table(root, "pipeline", "")) {
    const std::string p = "pipeline";
    rd.only_keys(*t, p,
                 {"finger_separation_m", "method", "velocity_proxy", "pair_tolerance_us",
                  "stale_ms", "lost_ms"});
    rd.real(*t, "finger_separation_m", p, kMinFingerSeparationM, kMaxFingerSeparationM,
            &b.pipeline.finger_separation_m);
    rd.choice<dsp::FusionMethod>(
        *t, "method", p,
        {{"joint", dsp::FusionMethod::kJoint}, {"paper", dsp::FusionMethod::kPaper}},
        &b.pipeline.method);
    rd.choice<protocol::VelocityMode>(*t, "velocity_proxy", p,
                                      {{"auto", protocol::VelocityMode::kAuto},
                                       {"velocity", protocol::VelocityMode::kVelocity},
                                       {"displacement", protocol::VelocityMode::kDisplacement}},
                                      &b.pipeline.velocity_proxy);
    rd.integer(*t, "pair_tolerance_us", p, 0, 50000, &b.pipeline.pair_tolerance_us);
    rd.integer(*t, "stale_ms", p, 1, 10000, &b.pipeline.stale_ms);
    rd.integer(*t, "lost_ms", p, 1, 60000, &b.pipeline.lost_ms);
    if (rd.ok() && b.pipeline.lost_ms < b.pipeline.stale_ms) {
      rd.fail(t->get("lost_ms"), "key \"pipeline.lost_ms\" (" + std::to_string(b.pipeline.lost_ms) +
                                     ") must be >= pipeline.stale_ms (" +
                                     std::to_string(b.pipeline.stale_ms) + ")");
    }
  }

  if (const toml::table* t = rd.table(root, "can", "")) {
    const std::string p = "can";
    rd.only_keys(*t, p,
                 {"backend", "interface", "log", "mode", "bitrate", "data_bitrate", "node_id",
                  "extended_ids", "tx_queue", "rate_divider"});
    rd.choice<CanBackend>(*t, "backend", p,
                          {{"socketcan", CanBackend::kSocketCan}, {"log", CanBackend::kLog}},
                          &b.can.backend);
    rd.string(*t, "interface", p, &b.can.interface);
    rd.string(*t, "log", p, &b.can.log);
    rd.choice<protocol::FrameMode>(
        *t, "mode", p,
        {{"classic", protocol::FrameMode::kClassic}, {"fd", protocol::FrameMode::kFd}},
        &b.can.mode);
    rd.integer(*t, "bitrate", p, 10000, 1000000, &b.can.bitrate);
    rd.integer(*t, "data_bitrate", p, 10000, 8000000, &b.can.data_bitrate);
    rd.integer(*t, "node_id", p, protocol::kMinNodeId, protocol::kMaxNodeId, &b.can.node_id);
    rd.boolean(*t, "extended_ids", p, &b.can.extended_ids);
    rd.integer(*t, "tx_queue", p, 8, 4096, &b.can.tx_queue);
    rd.integer(*t, "rate_divider", p, 1, 120, &b.can.rate_divider);
    if (rd.ok() && b.can.backend == CanBackend::kSocketCan && b.can.interface.empty()) {
      rd.fail(t, "key \"can.interface\" must not be empty with backend \"socketcan\"");
    }
  }

  if (const toml::table* t = rd.table(root, "gpio", "")) {
    rd.only_keys(
        *t, "gpio",
        {"backend", "chip", "status_led", "tare_button", "sensor_trigger", "gripper_closed"});
    rd.choice<GpioBackendKind>(
        *t, "backend", "gpio",
        {{"null", GpioBackendKind::kNull}, {"libgpiod", GpioBackendKind::kLibgpiod}},
        &b.gpio.backend);
    rd.string(*t, "chip", "gpio", &b.gpio.lines.chip);
    read_gpio_line(rd, *t, "status_led", GpioLine::kStatusLed, &b.gpio);
    read_gpio_line(rd, *t, "tare_button", GpioLine::kTareButton, &b.gpio);
    read_gpio_line(rd, *t, "sensor_trigger", GpioLine::kSensorTrigger, &b.gpio);
    read_gpio_line(rd, *t, "gripper_closed", GpioLine::kGripperClosed, &b.gpio);
  }

  if (const toml::table* t = rd.table(root, "realtime", "")) {
    rd.only_keys(*t, "realtime", {"dsp_cpu", "dsp_priority", "pad_cpus"});
    rd.integer(*t, "dsp_cpu", "realtime", -1, 1023, &b.realtime.dsp_cpu);
    rd.integer(*t, "dsp_priority", "realtime", 0, 99, &b.realtime.dsp_priority);
    rd.integer_pair(*t, "pad_cpus", "realtime", -1, 1023, &b.realtime.pad_cpus);
  }

  if (const toml::table* t = rd.table(root, "record", "")) {
    rd.only_keys(*t, "record", {"dir"});
    rd.string(*t, "dir", "record", &b.record.dir);
    // The daemon's working directory is no place to depend on; the directory itself is checked
    // when tacse3d starts (it may be a mount that is not there while the file is edited).
    if (rd.ok() && !std::filesystem::path(b.record.dir).is_absolute()) {
      rd.fail(t->get("dir"),
              "key \"record.dir\" must be an absolute path, got \"" + b.record.dir + "\"");
    }
  }

  if (const toml::table* t = rd.table(root, "rig", "")) {
    rd.only_keys(*t, "rig", {"tcp_to_grasp"});
    b.rig.has_tcp_to_grasp = t->get("tcp_to_grasp") != nullptr;
    rd.pose(*t, "tcp_to_grasp", "rig", &b.rig.tcp_to_grasp);
  }

  if (const toml::table* t = rd.table(root, "viewer", "")) {
    rd.only_keys(*t, "viewer", {"listen", "controls"});
    rd.string(*t, "listen", "viewer", &b.viewer.listen);
    rd.boolean(*t, "controls", "viewer", &b.viewer.controls);
    ListenAddress a;
    std::string e;
    // controls alone is fine: --http gives the address.
    if (rd.ok() && t->get("listen") != nullptr && !parse_listen_address(b.viewer.listen, &a, &e)) {
      rd.fail(t->get("listen"), "key \"viewer.listen\": " + e);
    }
  }

  if (!rd.ok()) {
    *error = rd.error();
    return false;
  }
  *out = std::move(b);
  return true;
}

}  // namespace

bool parse_board(std::string_view text, const std::string& origin, BoardConfig* out,
                 std::string* error) noexcept {
  try {
    return parse_impl(text, origin, out, error);
  } catch (const std::exception& e) {  // std::bad_alloc from the strings: still a message
    *error = origin + ": " + e.what();
    return false;
  }
}

bool load_board(const std::filesystem::path& file, BoardConfig* out, std::string* error) noexcept {
  try {
    std::string text;
    const fileio::ReadResult r = fileio::read_regular_file(file, kMaxBoardBytes, &text);
    const std::string name = file.string();
    switch (r.error) {
      case fileio::ReadError::kNone:
        return parse_board(text, name, out, error);
      case fileio::ReadError::kNotFound:
        *error = name + ": board file not found";
        break;
      case fileio::ReadError::kNotRegular:
        *error = name + ": is " + r.kind + ", expected a board file (a regular file)";
        break;
      case fileio::ReadError::kTooLarge:
        *error = name + ": file is larger than " + fileio::size_text(kMaxBoardBytes) +
                 "; not a board file";
        break;
      default:
        *error = name + ": cannot read the board file" + fileio::os_error(r.os_errno);
        break;
    }
    return false;
  } catch (const std::exception& e) {
    *error = file.string() + ": " + e.what();
    return false;
  }
}

std::filesystem::path resolve_board(const std::string& name_or_path,
                                    const std::filesystem::path& exe_dir,
                                    const std::filesystem::path& source_boards_dir,
                                    std::string* error) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const bool looks_like_path =
      name_or_path.find('/') != std::string::npos ||
      (name_or_path.size() > 5 && name_or_path.compare(name_or_path.size() - 5, 5, ".toml") == 0);
  if (looks_like_path || fs::is_regular_file(name_or_path, ec)) {
    // Anything at the path goes to load_board, which says what it is if not a board file.
    if (fs::exists(fs::symlink_status(name_or_path, ec))) return fs::path(name_or_path);
    *error = name_or_path + ": board file not found";
    return {};
  }
  std::vector<fs::path> dirs;
  if (const char* env = std::getenv("TACSE3_BOARD_DIR"); env != nullptr && *env != '\0') {
    dirs.emplace_back(env);
  }
  dirs.emplace_back("/etc/tacse3/boards");
  if (!exe_dir.empty()) dirs.push_back(exe_dir / ".." / "share" / "tacse3" / "boards");
  if (!source_boards_dir.empty()) dirs.push_back(source_boards_dir);
  std::string searched;
  for (const auto& d : dirs) {
    const fs::path p = (d / name_or_path / "board.toml").lexically_normal();
    if (fs::is_regular_file(p, ec)) return p;
    searched += (searched.empty() ? "" : ", ") + p.string();
  }
  *error = "board \"" + name_or_path + "\" not found (searched " + searched + ")";
  return {};
}

dsp::FusionConfig fusion_config(const BoardConfig& board) noexcept {
  dsp::FusionConfig f;
  f.method = board.pipeline.method;
  for (std::size_t s = 0; s < 2; ++s) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        f.extrinsics[s].R_GS(r, c) =
            board.sensors[s].rotation[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)];
      }
    }
  }
  return f;
}

std::string describe(const BoardConfig& b) {
  std::ostringstream s;
  s << "board \"" << b.name << "\" (" << b.origin << "): " << b.description << "\n";
  const char* side[2] = {"left", "right"};
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& c = b.sensors[i];
    if (!c.enabled) {
      s << "  sensor " << side[i] << ": none\n";
      continue;
    }
    s << "  sensor " << side[i] << ": " << to_string(c.backend)
      << (c.device.empty() ? "" : " " + c.device) << ", " << c.width << "x" << c.height << " @ "
      << c.fps << " fps, " << c.buffer_count << " buffers\n";
  }
  if (b.uses_backend(CameraBackend::kSim) && !b.sim.plan.empty()) {
    s << "  sim: " << b.sim.object << ", seed " << b.sim.seed << ", plan " << b.sim.plan
      << " (one motion per recording)\n";
  } else if (b.uses_backend(CameraBackend::kSim)) {
    s << "  sim: " << b.sim.object << ", motion " << b.sim.motion << " " << b.sim.magnitude << ", "
      << b.sim.regime << ", seed " << b.sim.seed << (b.sim.repeat ? ", repeat" : "")
      << (b.sim.realtime ? ", real time" : ", as fast as possible") << "\n";
  }
  s << "  pipeline: " << (b.pipeline.method == dsp::FusionMethod::kJoint ? "joint" : "paper")
    << " fusion, proxy " << protocol::to_string(b.pipeline.velocity_proxy)
    << ", W = " << b.pipeline.finger_separation_m << " m, pair tolerance "
    << b.pipeline.pair_tolerance_us << " us, stale " << b.pipeline.stale_ms << " ms, lost "
    << b.pipeline.lost_ms << " ms\n";
  s << "  can: "
    << (b.can.backend == CanBackend::kLog ? "log " + b.can.log : "socketcan " + b.can.interface)
    << ", " << (b.can.mode == protocol::FrameMode::kFd ? "fd" : "classic") << " " << b.can.bitrate
    << " bit/s, node " << b.can.node_id << (b.can.extended_ids ? ", 29-bit ids" : ", 11-bit ids")
    << ", tx queue " << b.can.tx_queue << ", rate divider " << b.can.rate_divider << "\n";
  s << "  gpio: "
    << (b.gpio.backend == GpioBackendKind::kNull ? "null" : "libgpiod " + b.gpio.lines.chip);
  for (std::size_t i = 0; i < kGpioLineCount; ++i) {
    const auto& l = b.gpio.lines.lines[i];
    if (!l.enabled) continue;
    s << ", " << to_string(static_cast<GpioLine>(i)) << "="
      << (l.name.empty() ? std::to_string(l.offset) : l.name)
      << (l.active_low ? " (active low)" : "");
  }
  s << "\n  realtime: dsp cpu " << b.realtime.dsp_cpu << ", SCHED_FIFO priority "
    << b.realtime.dsp_priority << "; pad cpus " << b.realtime.pad_cpus[0] << ", "
    << b.realtime.pad_cpus[1] << "\n";
  s << "  record: " << (b.record.dir.empty() ? "none (START_RECORDING refused)" : b.record.dir)
    << "\n";
  s << "  viewer: "
    << (b.viewer.listen.empty() ? std::string("off")
                                : std::string("http on ").append(b.viewer.listen))
    << (b.viewer.controls ? ", controls on" : "") << "\n";
  return s.str();
}

}  // namespace tacse3::config
