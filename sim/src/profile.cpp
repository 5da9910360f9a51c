// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: the named sensor profiles, the random profile's ranges, and applying a profile.
#include "tacse3/sim/profile.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <system_error>

#include "tacse3/sim/rng.hpp"
#include "tacse3/sim/simulator.hpp"

namespace tacse3::sim {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDotFill = 0.92;  // share of the jittered grid's cells that carry a dot

// Dot radii uniform in [r_min, r_max], a dot in kDotFill of the cells: the spacing that gives
// the expected printed area fraction `density` (overlaps ignored).
PatternSpec dots(double r_min_mm, double r_max_mm, double density, bool grey, double pitch_mm) {
  PatternSpec p;
  p.dot_radius_min_mm = r_min_mm;
  p.dot_radius_max_mm = r_max_mm;
  p.dot_fill = kDotFill;
  const double mean_area =
      kPi * (r_min_mm * r_min_mm + r_min_mm * r_max_mm + r_max_mm * r_max_mm) / 3.0;
  p.dot_spacing_mm = std::sqrt(kDotFill * mean_area / density);
  p.grey_dots = grey;
  // The texture must reach as far as the gel is displaced: 4.8 mm, as the reference's 48 px.
  p.margin_px = static_cast<int>(std::ceil(4.8 / pitch_mm));
  return p;
}

ShadingSpec leds(double angle_deg, double slope_gain, double press_gain_per_mm) {
  ShadingSpec s;
  const double a = angle_deg * kPi / 180.0;
  s.light_dir = {std::cos(a), std::sin(a)};
  s.slope_gain = slope_gain;
  s.press_gain_per_mm = press_gain_per_mm;
  return s;
}

void camera(SensorProfile* p, double read_noise_dn, double flicker, double vignetting_corner,
            int mjpeg_quality) {
  p->camera.read_noise_dn = read_noise_dn;
  p->camera.flicker = flicker;
  p->camera.vignetting_corner = vignetting_corner;
  p->camera.mjpeg_quality = mjpeg_quality;
}

void rig(SensorProfile* p, double pitch_mm, double indentation_mm, double size_mm,
         double seconds_per_30deg) {
  p->pixel_pitch_mm = pitch_mm;
  p->indentation_mm = indentation_mm;
  p->object_size_mm = size_mm;
  p->seconds_per_30deg = seconds_per_30deg;
}

// Soft silicone (Shore 00-20 class), 4 mm thick: the pressed volume flows out radially, the
// shear saturates smoothly.
SensorProfile soft_thick() {
  SensorProfile p;
  p.name = "soft-thick";
  GelSpec& g = p.gel;
  g.bulge_model = BulgeModel::kRadialVolume;
  g.bulge_surface_factor = 1.0;
  g.gel_thickness_mm = 4.0;
  g.bulge_sigma_mm = 2.0;
  g.slide_law = SlideLaw::kTanh;
  g.drag_time_s = 0.03;
  g.lag_time_s = 0.04;
  g.shear_compliance = 2.5;
  g.spread_length_mm = 4.0;
  g.friction_variation = 0.1;
  p.camera.shading = leds(127.0, 0.8, 0.06);
  p.pattern = dots(0.16, 0.24, 0.6, false, 0.08);
  camera(&p, 1.5, 0.02, 0.65, 85);
  rig(&p, 0.08, 1.5, 25.0, 2.0);
  return p;
}

// Firm elastomer (Shore A 20 class), 1.2 mm thick: a small, tight bulge and spread, fast shear,
// fine grey dots, a clean camera sending raw frames.
SensorProfile stiff_thin() {
  SensorProfile p;
  p.name = "stiff-thin";
  GelSpec& g = p.gel;
  g.bulge_gain_mm = 0.8;
  g.bulge_sigma_mm = 0.6;
  g.drag_time_s = 0.008;
  g.lag_time_s = 0.01;
  g.shear_compliance = 0.6;
  g.spread_length_mm = 1.0;
  p.camera.shading = leds(0.0, 0.4, 0.02);
  p.pattern = dots(0.06, 0.10, 0.35, true, 0.06);
  camera(&p, 0.6, 0.01, 0.85, 0);
  rig(&p, 0.06, 0.5, 15.0, 0.5);
  return p;
}

// A patchy coating: friction varies by 40 % over the pad and even a stuck grasp slips at the
// rim, where the indentation (and with it the friction-limited shear) goes to zero.
SensorProfile coulomb_rim() {
  SensorProfile p;
  p.name = "coulomb-rim";
  GelSpec& g = p.gel;
  g.bulge_gain_mm = 1.8;
  g.bulge_sigma_mm = 1.2;
  g.slide_law = SlideLaw::kCoulombRim;
  g.drag_time_s = 0.02;
  g.lag_time_s = 0.03;
  g.shear_compliance = 1.0;
  g.friction_variation = 0.4;
  g.spread_length_mm = 2.5;
  p.camera.shading = leds(90.0, 0.6, 0.04);
  p.pattern = dots(0.10, 0.16, 0.5, false, 0.1);
  camera(&p, 2.0, 0.03, 0.7, 90);
  rig(&p, 0.1, 1.0, 20.0, 1.0);
  return p;
}

// A gel thick against the patch seen by a cheap UVC camera: the shear spreads as on an elastic
// half-space (1/r tail), strong MJPEG compression, noise, flicker and vignetting.
SensorProfile halfspace_mjpeg() {
  SensorProfile p;
  p.name = "halfspace-mjpeg";
  GelSpec& g = p.gel;
  g.bulge_model = BulgeModel::kRadialVolume;
  g.bulge_surface_factor = 0.7;
  g.gel_thickness_mm = 3.0;
  g.bulge_sigma_mm = 1.0;
  g.slide_law = SlideLaw::kTanh;
  g.drag_time_s = 0.05;
  g.lag_time_s = 0.02;
  g.shear_compliance = 2.0;
  g.friction_variation = 0.2;
  g.spread_kernel = SpreadKernel::kHalfSpace;
  g.spread_length_mm = 3.0;
  p.camera.shading = leds(225.0, 1.0, 0.08);
  p.pattern = dots(0.12, 0.20, 0.45, true, 0.12);
  camera(&p, 3.5, 0.04, 0.5, 70);
  rig(&p, 0.12, 1.2, 30.0, 3.0);
  return p;
}

// Every value drawn from its range (docs/sim-profiles.md, "The random profile").
SensorProfile random_profile(std::uint64_t seed) {
  SensorProfile p;
  p.name = "random";
  Rng rng(hash_combine(seed, 0x9F0F11E));
  GelSpec& g = p.gel;
  g.bulge_model = rng.uniform() < 0.5 ? BulgeModel::kSmoothedGradient : BulgeModel::kRadialVolume;
  g.bulge_gain_mm = rng.uniform(1.4, 3.8);
  g.bulge_sigma_mm = rng.uniform(0.5, 2.0);
  g.bulge_surface_factor = rng.uniform(0.5, 1.0);
  g.gel_thickness_mm = rng.uniform(1.75, 4.0);
  g.slide_law = static_cast<SlideLaw>(static_cast<int>(rng.uniform() * 3.0));
  g.drag_time_s = rng.uniform(0.005, 0.05);
  g.lag_time_s = rng.uniform(0.001, 0.05);
  g.shear_compliance = rng.uniform(0.5, 3.0);
  g.friction_variation = rng.uniform(0.0, 0.5);
  g.spread_kernel = rng.uniform() < 0.5 ? SpreadKernel::kThinLayer : SpreadKernel::kHalfSpace;
  g.spread_length_mm = rng.uniform(1.0, 4.0);
  p.camera.shading = leds(rng.uniform(0.0, 360.0), rng.uniform(0.3, 1.0), rng.uniform(0.02, 0.08));
  const double pitch = rng.uniform(0.06, 0.12);
  const double r_mean = rng.uniform(0.08, 0.2);
  const double density = rng.uniform(0.3, 0.7);
  p.pattern = dots(0.75 * r_mean, 1.25 * r_mean, density, rng.uniform() < 0.5, pitch);
  const double noise = rng.uniform(0.5, 4.0);
  const double flicker = rng.uniform(0.0, 0.04);
  const double vignetting = rng.uniform(0.5, 0.9);
  const int quality = 70 + static_cast<int>(rng.uniform() * 26.0);  // 70 .. 95
  camera(&p, noise, flicker, vignetting, quality);
  const double indentation = rng.uniform(0.5, 1.5);
  const double size = rng.uniform(15.0, 30.0);
  const double speed = rng.uniform(0.5, 3.0);
  rig(&p, pitch, indentation, size, speed);
  return p;
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

// "random:N" with N a decimal number below 2^64: *sensor = N.
bool parse_random_sensor(std::string_view name, std::uint64_t* sensor) {
  constexpr std::string_view kPrefix = "random:";
  if (name.substr(0, kPrefix.size()) != kPrefix || name.size() == kPrefix.size()) return false;
  const std::string_view digits = name.substr(kPrefix.size());
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), *sensor);
  return ec == std::errc{} && end == digits.data() + digits.size();
}

}  // namespace

const char* profile_names() noexcept {
  return "reference, soft-thick, stiff-thin, coulomb-rim, halfspace-mjpeg, random";
}

bool make_profile(std::string_view name, std::uint64_t seed, SensorProfile* out,
                  std::string* error) {
  if (name == "reference") {
    *out = SensorProfile{};
  } else if (name == "soft-thick") {
    *out = soft_thick();
  } else if (name == "stiff-thin") {
    *out = stiff_thin();
  } else if (name == "coulomb-rim") {
    *out = coulomb_rim();
  } else if (name == "halfspace-mjpeg") {
    *out = halfspace_mjpeg();
  } else if (name == "random") {
    *out = random_profile(seed);
  } else if (std::uint64_t sensor = 0; parse_random_sensor(name, &sensor)) {
    // One sensor: the physics drawn by its own number, whatever the recording's seed.
    *out = random_profile(sensor);
    out->name = std::string(name);
  } else {
    if (error)
      *error = "unknown profile \"" + std::string(name) + "\" (one of: " + profile_names() +
               ", or random:N for one sensor of the random profile)";
    return false;
  }
  return true;
}

std::string validate(const SensorProfile& p) {
  if (std::string e = validate(p.gel); !e.empty()) return e;
  if (std::string e = validate(p.pattern); !e.empty()) return e;
  if (std::string e = validate(p.camera); !e.empty()) return e;
  if (!std::isfinite(p.pixel_pitch_mm) || p.pixel_pitch_mm < 0.005 || p.pixel_pitch_mm > 2.0) {
    return "profile pixel_pitch_mm must be in [0.005, 2]";
  }
  if (!std::isfinite(p.indentation_mm) || p.indentation_mm <= 0.0 || p.indentation_mm > 20.0) {
    return "profile indentation_mm must be in (0, 20]";
  }
  if (!std::isfinite(p.object_size_mm) || p.object_size_mm < 0.0 || p.object_size_mm > 500.0) {
    return "profile object_size_mm must be 0 (preset) or in (0, 500]";
  }
  if (!std::isfinite(p.seconds_per_30deg) || p.seconds_per_30deg < 0.0 ||
      p.seconds_per_30deg > 60.0) {
    return "profile seconds_per_30deg must be 0 (automatic) or in (0, 60]";
  }
  return {};
}

void apply_profile(const SensorProfile& p, SimConfig* c) {
  c->gel = p.gel;
  c->pattern = p.pattern;
  c->camera = p.camera;
  c->rig.pixel_pitch_mm = p.pixel_pitch_mm;
  c->scenario.indentation_mm = p.indentation_mm;
  if (p.object_size_mm > 0.0) c->scenario.object.size_mm = p.object_size_mm;
  if (p.seconds_per_30deg > 0.0) {
    const double unit = is_rotation(c->scenario.axis) ? 30.0 : 10.0;
    c->scenario.motion_s =
        std::max(0.05, p.seconds_per_30deg * std::abs(c->scenario.magnitude) / unit);
  }
}

std::vector<std::pair<std::string, std::string>> profile_values(const SensorProfile& p) {
  const GelSpec& g = p.gel;
  const ShadingSpec& s = p.camera.shading;
  return {
      {"bulge_model", to_string(g.bulge_model)},
      {"bulge_gain_mm", number(g.bulge_gain_mm)},
      {"bulge_sigma_mm", number(g.bulge_sigma_mm)},
      {"bulge_surface_factor", number(g.bulge_surface_factor)},
      {"gel_thickness_mm", number(g.gel_thickness_mm)},
      {"slide_law", to_string(g.slide_law)},
      {"drag_time_s", number(g.drag_time_s)},
      {"lag_time_s", number(g.lag_time_s)},
      {"shear_compliance", number(g.shear_compliance)},
      {"friction_variation", number(g.friction_variation)},
      {"spread_kernel", to_string(g.spread_kernel)},
      {"spread_length_mm", number(g.spread_length_mm)},
      {"light_dir_deg", number(std::atan2(s.light_dir.y(), s.light_dir.x()) * 180.0 / kPi)},
      {"slope_gain", number(s.slope_gain)},
      {"press_gain_per_mm", number(s.press_gain_per_mm)},
      {"dot_radius_min_mm", number(p.pattern.dot_radius_min_mm)},
      {"dot_radius_max_mm", number(p.pattern.dot_radius_max_mm)},
      {"dot_spacing_mm", number(p.pattern.dot_spacing_mm)},
      {"dot_fill", number(p.pattern.dot_fill)},
      {"grey_dots", p.pattern.grey_dots ? "true" : "false"},
      {"read_noise_dn", number(p.camera.read_noise_dn)},
      {"flicker", number(p.camera.flicker)},
      {"vignetting_corner", number(p.camera.vignetting_corner)},
      {"mjpeg_quality", number(p.camera.mjpeg_quality)},
      {"pixel_pitch_mm", number(p.pixel_pitch_mm)},
      {"indentation_mm", number(p.indentation_mm)},
      {"object_size_mm", number(p.object_size_mm)},
      {"seconds_per_30deg", number(p.seconds_per_30deg)},
  };
}

}  // namespace tacse3::sim
