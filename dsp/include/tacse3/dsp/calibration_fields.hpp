// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: the calibration schema, said once. Every key of a calibration sensor table, with its
// member of dsp::Calibration, its range and a one-line meaning, plus the rules that tie two keys
// together. dsp::validate, the TOML reader and writer (config/) and the key table of
// docs/calibration.md (tacse3-calkeys) are all driven by this table.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "tacse3/dsp/calibration.hpp"
#include "tacse3/dsp/geometry.hpp"

namespace tacse3::dsp {

struct CalibrationField {
  enum class Kind : std::uint8_t { kReal, kInt, kVec3, kProxy };
  const char* key;  // the TOML key, in file order
  Kind kind;
  double lo, hi;  // the range; for kVec3 each element's
  bool lo_open;   // the bound itself is excluded
  bool hi_open;
  const char* unit;  // SI unit, or "1" for dimensionless
  const char* doc;   // one line: what it means
  double Calibration::*real = nullptr;
  int Calibration::*integer = nullptr;
  std::array<double, 3> Calibration::*vec = nullptr;
};

// The values the file names velocity_proxy with.
struct VelocityProxyName {
  VelocityProxy value;
  const char* name;
};
inline constexpr std::array<VelocityProxyName, 3> kVelocityProxyNames{{
    {VelocityProxy::kVelocity, "velocity"},
    {VelocityProxy::kDisplacement, "displacement"},
    {VelocityProxy::kAuto, "auto"},
}};

namespace detail {
consteval std::array<CalibrationField, 34> make_calibration_fields() {
  using F = CalibrationField;
  using C = Calibration;
  return {{
      {"pixel_pitch_m", F::Kind::kReal, 1e-6, 2e-4, false, false, "m",
       "sensor pixel to metres along x (paper Sec. IV-B, 1/kappa_x)", &C::pixel_pitch_m},
      {"pixel_aspect_y", F::Kind::kReal, 0.25, 4.0, false, false, "1", "pitch_y / pitch_x",
       &C::pixel_aspect_y},
      {"antialias_filter", F::Kind::kInt, 0, 1, false, false, "-",
       "working image: 0 the 2x2 box, 1 the 4x4 binomial (a pattern finer than 4 px per period)",
       nullptr, &C::antialias_filter},
      {"normal_gain_density", F::Kind::kReal, 0.0, 1e4, false, false, "1",
       "f^z per unit of the density proxy -G", &C::normal_gain_density},
      {"normal_gain_divergence", F::Kind::kReal, 0.0, 1e4, false, false, "1",
       "f^z per unit of div d (working px per working px)", &C::normal_gain_divergence},
      {"shear_gain_d", F::Kind::kReal, 0.0, 1e4, false, false, "1",
       "shear per unit of the curl-free NHHD part d (Eq. nhhd)", &C::shear_gain_d},
      {"shear_gain_r", F::Kind::kReal, 0.0, 1e4, false, false, "1",
       "shear per unit of the divergence-free part r", &C::shear_gain_r},
      {"shear_gain_k", F::Kind::kReal, 0.0, 1e4, false, false, "1",
       "shear per unit of the harmonic part k", &C::shear_gain_k},
      {"contact_tau_on", F::Kind::kReal, 0.0, 1e4, true, false, "1",
       "a new cell joins the contact mask when filtered f^z exceeds it", &C::contact_tau_on},
      {"contact_tau_off", F::Kind::kReal, 0.0, 1e4, false, false, "1",
       "a cell of the last mask stays while filtered f^z exceeds it (hysteresis)",
       &C::contact_tau_off},
      {"contact_min_area_cells", F::Kind::kInt, 1, kGridCount, false, false, "cells",
       "smaller 4-connected mask components are dropped", nullptr, &C::contact_min_area_cells},
      {"height_gain_m", F::Kind::kReal, 0.0, 1.0, false, false, "m",
       "contact height per f^z unit, z = min(gain * max(f^z, 0), max)", &C::height_gain_m},
      {"height_max_m", F::Kind::kReal, 0.0, 0.01, false, false, "m", "clamp of the contact height",
       &C::height_max_m},
      {"velocity_proxy", F::Kind::kProxy, 0, 0, false, false, "-",
       "how shear becomes motion: velocity, displacement or auto (stick/slip detector)"},
      {"c_velocity", F::Kind::kReal, 0.0, 100.0, true, false, "m/s",
       "contact speed per shear unit (velocity proxy, paper Sec. IV-C)", &C::c_velocity},
      {"c_displacement", F::Kind::kReal, 0.0, 1.0, true, false, "m",
       "contact displacement per shear unit (displacement proxy)", &C::c_displacement},
      {"slip_relax_rate_on", F::Kind::kReal, 0.0, 1e3, true, false, "1/s",
       "slip onset: the loaded shear relaxes faster than this", &C::slip_relax_rate_on},
      {"slip_on_frames", F::Kind::kInt, 1, 1000, false, false, "frames",
       "consecutive relaxing frames that make a slip onset", nullptr, &C::slip_on_frames},
      {"slip_min_shift_m", F::Kind::kReal, 0.0, 0.01, false, false, "m",
       "shear content below which a contact counts as unloaded", &C::slip_min_shift_m},
      {"slip_exit_fraction", F::Kind::kReal, 0.0, 1.0, false, false, "1",
       "slip end: shear content below this fraction of its peak, at rest", &C::slip_exit_fraction},
      {"stick_rest_speed_m_s", F::Kind::kReal, 0.0, 1.0, true, false, "m/s",
       "shear content changing slower than this is at rest", &C::stick_rest_speed_m_s},
      {"stick_confirm_s", F::Kind::kReal, 0.0, 10.0, false, false, "s",
       "a contact at rest this long is confirmed stuck (drops a pending payback)",
       &C::stick_confirm_s},
      {"slip_catchup_frames", F::Kind::kInt, 1, 1000, false, false, "frames",
       "frames over which a slip's missed motion is paid back", nullptr, &C::slip_catchup_frames},
      {"slip_smoothing_s", F::Kind::kReal, 0.0, 1.0, false, false, "s",
       "time constant of the detector's exponential smoothing", &C::slip_smoothing_s},
      {"release_load_rate", F::Kind::kReal, 0.0, 1e4, true, false, "1/s",
       "a contact losing load faster than this is being released; 1e4 = off",
       &C::release_load_rate},
      {"max_mask_change", F::Kind::kReal, 0.0, 1.0, false, false, "1",
       "1 - Jaccard above which translation reads material points; 1 = off", &C::max_mask_change},
      {"max_mask_area_ratio", F::Kind::kReal, 1.0, 1e4, false, false, "1",
       "area growth factor above which translation reads material points; 1e4 = off",
       &C::max_mask_area_ratio},
      {"rotation_scale", F::Kind::kVec3, 0.0, 100.0, false, false, "1",
       "per-axis scale of this sensor's rotation (its own frame)", nullptr, nullptr,
       &C::rotation_scale},
      {"translation_scale", F::Kind::kVec3, 0.0, 100.0, false, false, "1",
       "per-axis scale of this sensor's translation (its own frame)", nullptr, nullptr,
       &C::translation_scale},
      {"displacement_rotation_ratio", F::Kind::kVec3, 0.0, 100.0, false, false, "1",
       "factor on rotation_scale for frames read by the displacement proxy", nullptr, nullptr,
       &C::displacement_rotation_ratio},
      {"moving_average_length", F::Kind::kInt, 1, kMaxMovingAverage, false, false, "frames",
       "moving-average window (paper Sec. IV-D)", nullptr, &C::moving_average_length},
      {"solve_lambda_rel", F::Kind::kReal, 0.0, 1.0, false, false, "1",
       "3x3 solve regularisation relative to tr(A^T A)/3", &C::solve_lambda_rel},
      {"solve_lever_floor_m", F::Kind::kReal, 0.0, 1e-2, false, false, "m",
       "lever floor added to the regularisation, N * floor^2", &C::solve_lever_floor_m},
      {"solve_rcond_min", F::Kind::kReal, 0.0, 1.0, false, true, "1",
       "a solve with a smaller reciprocal condition number is invalid", &C::solve_rcond_min},
  }};
}
}  // namespace detail
inline constexpr std::array<CalibrationField, 34> kCalibrationFields =
    detail::make_calibration_fields();

// A rule over two keys: `key` <relation> `other`, shown as
// key "S.key" (value) <relation> "S.other" (value)<note>.
struct CalibrationRule {
  const char* key;
  const char* relation;
  const char* other;
  const char* note;
  bool (*holds)(const Calibration&);
};

inline constexpr std::array<CalibrationRule, 2> kCalibrationRules{{
    {"contact_tau_off", "must not exceed", "contact_tau_on", "",
     [](const Calibration& c) { return c.contact_tau_off <= c.contact_tau_on; }},
    // The smoothed load rate cannot exceed 1/slip_smoothing_s, so a larger rate would never act.
    {"release_load_rate", "must be below 1 /", "slip_smoothing_s",
     ", the largest rate the smoothed load can show, or 1e4 (off)",
     [](const Calibration& c) {
       return c.release_load_rate >= kReleaseRuleOff ||
              c.release_load_rate * c.slip_smoothing_s < 1.0;
     }},
}};

// Whether v lies in the field's range (NaN and infinities never do).
constexpr bool field_in_range(const CalibrationField& f, double v) noexcept {
  constexpr double kMax = std::numeric_limits<double>::max();
  if (!(v >= -kMax && v <= kMax)) return false;
  if (f.lo_open ? !(v > f.lo) : !(v >= f.lo)) return false;
  if (f.hi_open ? !(v < f.hi) : !(v <= f.hi)) return false;
  return true;
}

// Whether the field's value in c is valid (each element for kVec3; a named mode for kProxy).
constexpr bool field_valid(const CalibrationField& f, const Calibration& c) noexcept {
  switch (f.kind) {
    // The member checks cost nothing and keep a malformed entry (a kind without its member) from
    // dereferencing null; tests/dsp/test_calibration_fields.cpp checks every entry has its member.
    case CalibrationField::Kind::kReal:
      return f.real != nullptr && field_in_range(f, c.*(f.real));
    case CalibrationField::Kind::kInt:
      return f.integer != nullptr && field_in_range(f, static_cast<double>(c.*(f.integer)));
    case CalibrationField::Kind::kVec3:
      if (f.vec == nullptr) return false;
      for (const double v : c.*(f.vec)) {
        if (!field_in_range(f, v)) return false;
      }
      return true;
    case CalibrationField::Kind::kProxy:
      for (const auto& n : kVelocityProxyNames) {
        if (n.value == c.velocity_proxy) return true;
      }
      return false;
  }
  return false;
}

// The field with this key, or nullptr.
constexpr const CalibrationField* find_calibration_field(const char* key) noexcept {
  for (const auto& f : kCalibrationFields) {
    const char* a = f.key;
    const char* b = key;
    while (*a != '\0' && *a == *b) {
      ++a;
      ++b;
    }
    if (*a == *b) return &f;
  }
  return nullptr;
}

}  // namespace tacse3::dsp
