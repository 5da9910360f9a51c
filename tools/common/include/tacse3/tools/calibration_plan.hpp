// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the motions to record for a calibration (tacse3-calibrate --plan), derived from
// the coverage rules the fit applies (kCoverageRules), so the two cannot drift apart.
#pragma once

#include <string>
#include <vector>

#include "tacse3/tools/calibration_check.hpp"

namespace tacse3::tools {

// Every recording of the plan: the pads open this long before they close on the object (the
// f^z noise is measured on these frames), and a hold this long after the motion.
inline constexpr double kPlanPadsOpenS = 0.5;
inline constexpr double kPlanHoldS = 1.0;

// One line of the plan: a rule's motion and every rule it satisfies.
struct PlanLine {
  const CoverageRule* rule = nullptr;  // the rule whose plan motion this is
  std::string unit;                    // deg | mm
  std::string why;                     // the calibration values it determines
};
std::vector<PlanLine> calibration_plan();

// The plan as text for the user, or as CSV with a header line (docs/calibrate-a-rig.md):
// axis,magnitude,unit,regime,duration_s,pads_open_s,hold_s,determines
std::string format_plan(bool csv);

}  // namespace tacse3::tools
