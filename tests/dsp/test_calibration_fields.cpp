// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: the calibration schema table (calibration_fields.hpp) is well formed, and
// dsp::validate honours each of its bounds exactly as the table states them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "tacse3/dsp/calibration_fields.hpp"

namespace tacse3::dsp {
namespace {

using Kind = CalibrationField::Kind;

TEST(CalibrationFields, KeysAndMembersAreUniqueAndFindable) {
  std::set<std::string> keys;
  for (std::size_t i = 0; i < kCalibrationFields.size(); ++i) {
    const CalibrationField& f = kCalibrationFields[i];
    EXPECT_TRUE(keys.insert(f.key).second) << f.key;
    EXPECT_EQ(find_calibration_field(f.key), &f) << f.key;
    EXPECT_GT(std::string(f.doc).size(), 10u) << f.key;
    EXPECT_EQ(f.real != nullptr, f.kind == Kind::kReal) << f.key;
    EXPECT_EQ(f.integer != nullptr, f.kind == Kind::kInt) << f.key;
    EXPECT_EQ(f.vec != nullptr, f.kind == Kind::kVec3) << f.key;
    for (std::size_t j = 0; j < i; ++j) {
      const CalibrationField& g = kCalibrationFields[j];
      if (f.real != nullptr) {
        EXPECT_NE(f.real, g.real) << f.key << " / " << g.key;
      }
      if (f.integer != nullptr) {
        EXPECT_NE(f.integer, g.integer) << f.key << " / " << g.key;
      }
      if (f.vec != nullptr) {
        EXPECT_NE(f.vec, g.vec) << f.key << " / " << g.key;
      }
    }
  }
  EXPECT_EQ(find_calibration_field("no_such_key"), nullptr);
  EXPECT_EQ(find_calibration_field("pixel_pitch"), nullptr);  // a prefix is not a key
}

TEST(CalibrationFields, RulesNameRealFields) {
  for (const auto& r : kCalibrationRules) {
    for (const char* k : {r.key, r.other}) {
      const CalibrationField* f = find_calibration_field(k);
      ASSERT_NE(f, nullptr) << k;
      EXPECT_EQ(f->kind, Kind::kReal) << k;
    }
    EXPECT_TRUE(r.holds(Calibration{})) << r.key;
  }
}

// Sets a real or integer field, or every element of a vector field, to v.
void set_value(const CalibrationField& f, Calibration& c, double v) {
  if (f.kind == Kind::kReal) c.*(f.real) = v;
  if (f.kind == Kind::kInt) c.*(f.integer) = static_cast<int>(v);
  if (f.kind == Kind::kVec3) c.*(f.vec) = {v, v, v};
}

// A calibration in which no rule ties the field's value to another (the rules' partners are
// moved out of the way), so only the field's own range decides.
Calibration free_of_rules() {
  Calibration c;
  c.contact_tau_on = 1e4;                 // contact_tau_off may take its whole range
  c.release_load_rate = kReleaseRuleOff;  // slip_smoothing_s may take its whole range
  return c;
}

TEST(CalibrationFields, ValidateHonoursEachBoundAsStated) {
  for (const CalibrationField& f : kCalibrationFields) {
    if (f.kind == Kind::kProxy) continue;
    for (const bool low : {true, false}) {
      const double bound = low ? f.lo : f.hi;
      const bool open = low ? f.lo_open : f.hi_open;
      Calibration c = free_of_rules();
      set_value(f, c, bound);
      if (&f == find_calibration_field("contact_tau_on") && low) c.contact_tau_off = 0.0;
      if (&f == find_calibration_field("release_load_rate")) c.slip_smoothing_s = 0.0;
      EXPECT_EQ(validate(c) == Status::kOk, !open) << f.key << (low ? " at lo" : " at hi");
      // Just outside the bound (one integer step, or a relative nudge for reals).
      const double step = f.kind == Kind::kInt ? 1.0 : std::max(std::abs(bound) * 1e-9, 1e-300);
      set_value(f, c, low ? bound - step : bound + step);
      EXPECT_EQ(validate(c), Status::kBadCalibration) << f.key << (low ? " below lo" : " above hi");
      set_value(f, c, std::nan(""));
      if (f.kind != Kind::kInt) {
        EXPECT_EQ(validate(c), Status::kBadCalibration) << f.key << " NaN";
      }
    }
  }
}

}  // namespace
}  // namespace tacse3::dsp
