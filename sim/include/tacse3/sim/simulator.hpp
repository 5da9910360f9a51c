// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: the two-pad tactile simulator facade used by tacse3-sim and the live `sim` backend.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "tacse3/sim/camera.hpp"
#include "tacse3/sim/object.hpp"
#include "tacse3/sim/pad.hpp"
#include "tacse3/sim/pattern.hpp"
#include "tacse3/sim/scenario.hpp"
#include "tacse3/sim/types.hpp"

namespace tacse3::sim {

struct SimConfig {
  ScenarioSpec scenario;
  RigSpec rig;
  GelSpec gel;
  PatternSpec pattern;
  CameraSpec camera;
  std::uint64_t seed = 1;  // patterns, noise, flicker, bumpy shape: all derive from it
  std::array<bool, kSensorCount> sensors{true, true};  // which pads to render
  // false: physics and truth only (no pattern textures; render() returns kBadBuffer). Saves the
  // texture memory and build time when only fields, labels or truth are needed.
  bool images = true;
};

// Empty string if usable, else a message naming the field.
std::string validate(const SimConfig& config);

// Renders two mirrored DM-Tac-like sensors with exact ground truth.
//
// create() validates the configuration and allocates every buffer (patterns, textures, grids,
// noise tables); step()/render() never allocate, never throw and never touch the disk. Each
// sensor keeps its own physical state (the slide regime integrates a lag), so per sensor the
// times must be non-decreasing; reset(sensor) starts that sensor over. Calls for different
// sensors may run concurrently on different threads; calls for one sensor may not.
class Simulator {
 public:
  static std::unique_ptr<Simulator> create(const SimConfig& config, std::string* error);

  // Advances sensor s's physics to t_ns (nanoseconds since the first frame) without rendering.
  SimStatus step(Sensor s, std::int64_t t_ns) noexcept;
  // step() plus the image: width x height x channels bytes (3 = RGB888, 1 = GREY) into out.
  SimStatus render(Sensor s, std::int64_t t_ns, std::span<std::uint8_t> out, int channels) noexcept;
  void reset(Sensor s) noexcept;

  // Exact object pose in G relative to the first frame (millimetres; truth.csv uses metres).
  Pose truth(std::int64_t t_ns) const noexcept { return scenario_.pose(seconds(t_ns)); }
  Twist truth_twist(std::int64_t t_ns) const noexcept { return scenario_.twist(seconds(t_ns)); }

  const SimConfig& config() const noexcept { return config_; }
  const Scenario& scenario() const noexcept { return scenario_; }
  const Shape& shape() const noexcept { return shape_; }
  bool has_sensor(Sensor s) const noexcept { return config_.sensors[idx(s)]; }
  // Per-sensor state after the last step()/render() of that sensor.
  const PadFields& fields(Sensor s) const noexcept { return pads_[idx(s)].fields(); }
  const PadLabels& labels(Sensor s) const noexcept { return pads_[idx(s)].labels(); }
  const Pattern& pattern(Sensor s) const noexcept { return patterns_[idx(s)]; }
  // Distance between the undeformed pad surfaces at the end of the grasp (recording.json's
  // rig.finger_separation_mm).
  double finger_separation_mm() const noexcept { return finger_separation_mm_; }
  std::size_t frame_bytes(int channels) const noexcept {
    return static_cast<std::size_t>(config_.rig.width) *
           static_cast<std::size_t>(config_.rig.height) * static_cast<std::size_t>(channels);
  }

  static double seconds(std::int64_t t_ns) noexcept { return static_cast<double>(t_ns) * 1e-9; }

 private:
  explicit Simulator(const SimConfig& config);
  static std::size_t idx(Sensor s) noexcept { return static_cast<std::size_t>(s); }

  SimConfig config_;
  Scenario scenario_;
  Shape shape_;
  std::array<PadPhysics, kSensorCount> pads_;
  std::array<Pattern, kSensorCount> patterns_;
  std::array<Camera, kSensorCount> cameras_;
  double finger_separation_mm_ = 0.0;
};

// Nominal finger separation of a configuration (both pads at the end of the grasp), or a
// negative value with *error set if the object does not reach a pad.
double nominal_finger_separation(const SimConfig& config, std::string* error);

// Rescales config->scenario.object.size_mm so that nominal_finger_separation() equals
// separation_mm (to 1 um). False with *error set if that is impossible.
bool fit_object_to_separation(SimConfig* config, double separation_mm, std::string* error);

}  // namespace tacse3::sim
