// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the recording plan from the coverage rules.
#include "tacse3/tools/calibration_plan.hpp"

#include <cstdio>
#include <string_view>

namespace tacse3::tools {

std::vector<PlanLine> calibration_plan() {
  std::vector<PlanLine> lines;
  for (const auto& rule : kCoverageRules) {
    if (rule.plan.axis == nullptr) continue;
    PlanLine l;
    l.rule = &rule;
    l.unit = rule.plan.axis[0] == 'r' ? "deg" : "mm";
    l.why = rule.fields;
    // The regime rules this line satisfies (the pads-open rule is every line's, said once).
    for (const auto& other : kCoverageRules) {
      if (other.plan.axis != nullptr || other.plan.regime == nullptr) continue;
      if (std::string_view(other.plan.regime) == rule.plan.regime) {
        l.why += std::string("; ") + other.fields;
      }
    }
    lines.push_back(std::move(l));
  }
  return lines;
}

std::string format_plan(bool csv) {
  const std::vector<PlanLine> plan = calibration_plan();
  std::string o;
  char b[512];
  if (csv) {
    o = "axis,magnitude,unit,regime,duration_s,pads_open_s,hold_s,determines\n";
    for (const auto& l : plan) {
      std::snprintf(b, sizeof b, "%s,%g,%s,%s,%g,%g,%g,\"%s\"\n", l.rule->plan.axis,
                    l.rule->plan.magnitude, l.unit.c_str(), l.rule->plan.regime,
                    l.rule->plan.duration_s, kPlanPadsOpenS, kPlanHoldS, l.why.c_str());
      o += b;
    }
    return o;
  }
  std::snprintf(b, sizeof b,
                "Record one recording per line (docs/calibrate-a-rig.md).\nEach: the pads open "
                "for %g s (they determine %s), close on the object and settle; then the motion; "
                "then a hold of %g s.\n",
                kPlanPadsOpenS, coverage_rule(Motion::kPadsOpen).fields, kPlanHoldS);
  o = b;
  std::snprintf(b, sizeof b, "  %-4s %9s %-6s %8s\n", "axis", "magnitude", "regime", "duration");
  o += b;
  for (const auto& l : plan) {
    std::snprintf(b, sizeof b, "  %-4s %5g %-3s %-6s %6g s\n", l.rule->plan.axis,
                  l.rule->plan.magnitude, l.unit.c_str(), l.rule->plan.regime,
                  l.rule->plan.duration_s);
    o += b;
    o += "       why: it determines " + l.why + "\n";
  }
  o += "Stick: the contact follows the object (no slip); slide: the object slips on the pads.\n";
  return o;
}

}  // namespace tacse3::tools
