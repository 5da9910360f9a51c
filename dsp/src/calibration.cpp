// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: validation of the back-end calibration, driven by the schema table.
#include "tacse3/dsp/calibration.hpp"

#include "tacse3/dsp/calibration_fields.hpp"

namespace tacse3::dsp {

Status validate(const Calibration& c) noexcept {
  for (const auto& f : kCalibrationFields) {
    if (!field_valid(f, c)) return Status::kBadCalibration;
  }
  for (const auto& r : kCalibrationRules) {
    if (!r.holds(c)) return Status::kBadCalibration;
  }
  return Status::kOk;
}

}  // namespace tacse3::dsp
