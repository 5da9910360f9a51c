// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: named sensor profiles (gel, pattern, camera and rig physics) and a random one.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "tacse3/sim/camera.hpp"
#include "tacse3/sim/pad.hpp"
#include "tacse3/sim/pattern.hpp"

namespace tacse3::sim {

struct SimConfig;

// One DM-Tac-class sensor's physics (docs/sim-profiles.md): the gel's models and parameters,
// the printed pattern, the camera, and the rig and grasp it is used with.
struct SensorProfile {
  std::string name = "reference";
  GelSpec gel;
  PatternSpec pattern;
  CameraSpec camera;             // with the LED shading and the MJPEG quality
  double pixel_pitch_mm = 0.1;   // rig
  double indentation_mm = 1.0;   // grasp
  double object_size_mm = 0.0;   // the object's size_mm; 0 keeps the object preset's
  double seconds_per_30deg = 0;  // motion speed (30 deg or 10 mm take this long); 0: automatic
};

// The profiles' names, comma-separated, for help texts ("reference, ..., random").
const char* profile_names() noexcept;

// Fills *out with the named profile. "random" draws every value from the documented ranges
// with `seed`; "random:N" draws them with N instead, so every recording of it is of one sensor;
// the named ones ignore the seed. False (with *error naming the choices) if unknown.
bool make_profile(std::string_view name, std::uint64_t seed, SensorProfile* out,
                  std::string* error);

// Empty if the profile is usable, else a message naming the field.
std::string validate(const SensorProfile& p);

// Puts the profile into config: gel, pattern, camera, pixel pitch, indentation, and (when set)
// the object size and the motion duration for config->scenario's axis and magnitude, so call it
// after those are set. Options a user gives explicitly are applied after it.
void apply_profile(const SensorProfile& p, SimConfig* config);

// The profile's values as (key, value) pairs, model choices as their names: for recordings'
// metadata and the documentation tables.
std::vector<std::pair<std::string, std::string>> profile_values(const SensorProfile& p);

}  // namespace tacse3::sim
