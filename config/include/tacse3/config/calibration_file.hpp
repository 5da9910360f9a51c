// SPDX-License-Identifier: Apache-2.0
// tacse3 config: the versioned TOML calibration file (docs/calibration.md): read, validate, write.
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "tacse3/dsp/calibration.hpp"
#include "tacse3/dsp/fusion.hpp"

namespace tacse3::config {

inline constexpr const char* kCalibrationFormat = "tacse3-calibration";
inline constexpr int kCalibrationVersion = 1;
// Largest calibration file read: a full file is a few KiB, so anything larger is not one.
inline constexpr std::size_t kMaxCalibrationBytes = std::size_t{1} << 20;

// Success, or a message that names the file and the key at fault. Nothing in this library
// throws (the daemon reloads the file on SIGHUP and must keep running on a bad file). The
// convention of protocol::Status: `!s` is true on a failure, and there is no conversion to bool
// (`if (s)` does not compile), so a check reads the same on both.
class Status {
 public:
  Status() = default;
  static Status error(std::string message) {
    Status s;
    s.message_ = message.empty() ? std::string("unknown error") : std::move(message);
    return s;
  }
  bool ok() const noexcept { return message_.empty(); }
  bool operator!() const noexcept { return !ok(); }
  const std::string& message() const noexcept { return message_; }

 private:
  std::string message_;
};

// Sensor slots of the file, in the order of dsp::DualPipeline (left = sensor 1).
inline constexpr std::size_t kLeft = 0;
inline constexpr std::size_t kRight = 1;

// Per-axis scales used by the paper's fusion (ξ = ½(ξ₁ + S ξ₂)) instead of the sensor tables'
// scales: with that fusion ω_x, ω_y come out lever-scaled (≈ W / 2z̄ too large), so they need
// their own per-axis scales, while the joint fusion is in rad/s and keeps scales near 1.
struct PaperScales {
  std::array<double, 3> rotation_scale{1.0, 1.0, 1.0};
  std::array<double, 3> translation_scale{1.0, 1.0, 1.0};
};

// Free-form provenance ([meta] table); informational only, never used by the pipeline.
struct CalibrationMeta {
  std::string generator;
  std::string created;
  std::string note;
  std::vector<std::string> recordings;
};

// Everything a calibration file holds.
struct CalibrationSet {
  // Complete per-sensor calibration (left, right) as used with the joint fusion.
  std::array<dsp::Calibration, 2> sensor{};
  // Scales that replace sensor[i].rotation_scale / translation_scale with the paper fusion.
  std::array<PaperScales, 2> paper{};
  CalibrationMeta meta;
  // The file sets at least one sensor key ([sensor], [left] or [right]): a calibration fitted to
  // some pads. False for the built-in defaults and a file holding only the header.
  bool fitted = false;

  // The per-sensor calibrations for a fusion method (paper: with the [paper] scales).
  std::array<dsp::Calibration, 2> for_method(dsp::FusionMethod method) const;
};

// Parses and validates TOML text. `origin` names the source in messages (a file path). On error
// *out is left unchanged. Missing keys take the documented defaults (dsp::Calibration{});
// unknown keys, wrong types and out-of-range values are errors naming the key.
Status parse_calibration(std::string_view text, const std::string& origin,
                         CalibrationSet* out) noexcept;

// Reads and parses a file (see parse_calibration); errors name the file. Only a regular file of
// at most kMaxCalibrationBytes is read: a FIFO or a device at the path is an error at once,
// never a wait (the daemon reloads on SIGHUP and must stay responsive).
Status load_calibration(const std::filesystem::path& file, CalibrationSet* out) noexcept;

// Serialises a set (validated first) as TOML text; every key is written. False + *error on an
// invalid set.
bool format_calibration(const CalibrationSet& set, std::string* text, std::string* error) noexcept;

// Checks that save_calibration can write `file`: its directory exists and is writable, and
// `file` is absent or a regular file. Tools call it before a long fit.
Status check_calibration_output(const std::filesystem::path& file) noexcept;

// Validates and writes atomically (a new file beside `file`, then rename), so a daemon never
// reads half a file. Only a regular file or a new path is replaced; a symlink, FIFO, device or
// directory at `file` is an error and stays as it is (check_calibration_output).
Status save_calibration(const std::filesystem::path& file, const CalibrationSet& set) noexcept;

// Field-by-field validation with messages naming the key ("left.contact_tau_off"); also runs
// dsp::validate on each sensor's calibration for both fusion methods.
Status validate(const CalibrationSet& set, const std::string& origin) noexcept;

// Text of the velocity proxy enum as written in the file ("velocity", "displacement").
const char* proxy_name(dsp::VelocityProxy p) noexcept;
bool parse_proxy_name(std::string_view name, dsp::VelocityProxy* out) noexcept;

// The calibration fitted on the simulator's pads (tools/replay/data/sim-calibration.toml), which
// a simulated board and a simulator recording use when no --calibration is given. Looked up as
// <exe_dir>/../share/tacse3/sim-calibration.toml (the installed copy), then `source_file` (the
// source tree's, for programs run from the build tree). Empty when neither is a regular file.
std::filesystem::path find_sim_calibration(const std::filesystem::path& exe_dir,
                                           const std::filesystem::path& source_file);

// The folder of the running program (/proc/self/exe), or an empty path.
std::filesystem::path executable_dir();

// Names of every key accepted in a sensor table, in file order (for docs and tests).
std::vector<std::string> sensor_keys();

}  // namespace tacse3::config
