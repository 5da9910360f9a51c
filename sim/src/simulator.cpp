// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: simulator facade: configuration validation, allocation, per-sensor step and render.
#include "tacse3/sim/simulator.hpp"

#include <cmath>

#include "tacse3/sim/rng.hpp"

namespace tacse3::sim {

std::string validate(const SimConfig& c) {
  if (std::string e = validate(c.scenario); !e.empty()) return e;
  if (!std::isfinite(c.rig.pixel_pitch_mm) || c.rig.pixel_pitch_mm < 0.005 ||
      c.rig.pixel_pitch_mm > 2.0) {
    return "rig pixel_pitch_mm must be in [0.005, 2]";
  }
  if (c.rig.width < 4 * kCellPx || c.rig.height < 4 * kCellPx || c.rig.width > 4096 ||
      c.rig.height > 4096 || c.rig.width % kCellPx != 0 || c.rig.height % kCellPx != 0) {
    return "rig width and height must be multiples of 4 in [16, 4096]";
  }
  if (std::string e = validate(c.gel); !e.empty()) return e;
  if (std::string e = validate(c.pattern); !e.empty()) return e;
  if (std::string e = validate(c.camera); !e.empty()) return e;
  if (!c.sensors[0] && !c.sensors[1]) return "at least one sensor must be enabled";
  return {};
}

Simulator::Simulator(const SimConfig& config)
    : config_(config), scenario_(config.scenario), shape_(scenario_.object()) {}

double nominal_finger_separation(const SimConfig& config, std::string* error) {
  const Scenario scn(config.scenario);
  const Shape shape(scn.object());
  double sum = 0.0;
  for (int s = 0; s < kSensorCount; ++s) {
    PadPhysics pad;
    pad.build(static_cast<Sensor>(s), config.rig, config.gel, config.camera.shading,
              hash_combine(config.seed, 0xF7 + static_cast<std::uint64_t>(s)));
    pad.step(scn, shape, scn.grasp_end_s());
    if (!pad.labels().in_contact) {
      if (error) {
        *error = std::string("the object does not reach the ") + to_string(static_cast<Sensor>(s)) +
                 " pad (check its size, offset and the pad area)";
      }
      return -1.0;
    }
    sum += pad.fields().pad_surface_mm;
  }
  return sum;
}

std::unique_ptr<Simulator> Simulator::create(const SimConfig& config, std::string* error) {
  if (std::string e = validate(config); !e.empty()) {
    if (error) *error = e;
    return nullptr;
  }
  std::string sep_error;
  const double separation = nominal_finger_separation(config, &sep_error);
  if (separation <= 0.0) {
    if (error) *error = sep_error.empty() ? "the finger separation is not positive" : sep_error;
    return nullptr;
  }
  std::unique_ptr<Simulator> sim(new Simulator(config));
  sim->finger_separation_mm_ = separation;
  for (int s = 0; s < kSensorCount; ++s) {
    const auto sensor = static_cast<Sensor>(s);
    const auto k = static_cast<std::size_t>(s);
    sim->pads_[k].build(sensor, config.rig, config.gel, config.camera.shading,
                        hash_combine(config.seed, 0xF7 + static_cast<std::uint64_t>(s)));
    if (!config.sensors[k] || !config.images) continue;
    const std::uint64_t seed = hash_combine(config.seed, 0x5E45 + static_cast<std::uint64_t>(s));
    sim->patterns_[k].build(config.pattern, config.rig.pixel_pitch_mm, config.rig.width,
                            config.rig.height, seed);
    sim->cameras_[k].build(config.rig, config.camera, seed, sensor);
  }
  return sim;
}

SimStatus Simulator::step(Sensor s, std::int64_t t_ns) noexcept {
  return pads_[idx(s)].step(scenario_, shape_, seconds(t_ns));
}

SimStatus Simulator::render(Sensor s, std::int64_t t_ns, std::span<std::uint8_t> out,
                            int channels) noexcept {
  if ((channels != 1 && channels != 3) || out.size() < frame_bytes(channels) ||
      !config_.sensors[idx(s)] || !config_.images) {
    return SimStatus::kBadBuffer;
  }
  const SimStatus st = step(s, t_ns);
  if (st != SimStatus::kOk) return st;
  if (!cameras_[idx(s)].render(patterns_[idx(s)], pads_[idx(s)].fields(), t_ns, out.data(),
                               channels)) {
    return SimStatus::kCodecFailed;
  }
  return SimStatus::kOk;
}

void Simulator::reset(Sensor s) noexcept {
  pads_[idx(s)].reset();
}

bool fit_object_to_separation(SimConfig* config, double separation_mm, std::string* error) {
  if (!std::isfinite(separation_mm) || separation_mm <= 0.0) {
    if (error) *error = "finger separation must be positive";
    return false;
  }
  const double indent = config->scenario.indentation_mm;
  for (int it = 0; it < 8; ++it) {
    const double w = nominal_finger_separation(*config, error);
    if (w <= 0.0) return false;
    if (std::abs(w - separation_mm) < 1e-3) return true;
    double& size = config->scenario.object.size_mm;
    size *= (separation_mm + 2.0 * indent) / (w + 2.0 * indent);
    if (std::string e = validate(config->scenario.object); !e.empty()) {
      if (error) *error = "cannot reach that finger separation: " + e;
      return false;
    }
  }
  const double w = nominal_finger_separation(*config, error);
  if (w > 0.0 && std::abs(w - separation_mm) < 1e-2) return true;
  if (error) *error = "cannot fit the object to that finger separation";
  return false;
}

}  // namespace tacse3::sim
