// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: a calibration plan (tacse3-calibrate --plan --format csv, docs/calibrate-a-rig.md)
// as the scenarios the simulated rig plays, one per recording.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "tacse3/sim/scenario.hpp"

namespace tacse3::sim {

// One line of the plan.
struct PlanMotion {
  MotionAxis axis = MotionAxis::kRz;
  double magnitude = 0.0;  // degrees (rotations) or millimetres (translations), signed
  Regime regime = Regime::kStick;
  double duration_s = 1.0;   // the motion itself
  double pads_open_s = 0.5;  // pads open before the grasp
  double hold_s = 1.0;       // still after the motion
};

// Parses the plan's CSV text. Columns are found by name in the header (axis, magnitude, unit,
// regime, duration_s, pads_open_s, hold_s; others, such as determines, are ignored); fields may
// be quoted as RFC 4180 says. At least one line. False with *error naming `name`, the line and
// the field on bad input (a unit that does not match the axis, a magnitude or time the
// simulator cannot play).
bool parse_plan(std::string_view text, const std::string& name, std::vector<PlanMotion>* out,
                std::string* error);

// The scenario that plays `m` from rest: `base` (object, grasp timing, fps) with the line's
// axis, magnitude, regime and times; no loop, no release.
ScenarioSpec plan_scenario(const PlanMotion& m, const ScenarioSpec& base);

}  // namespace tacse3::sim
