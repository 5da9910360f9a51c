// SPDX-License-Identifier: Apache-2.0
// Tests of the sensor profiles and their alternative models: validity, determinism, the random
// profile's ranges, the half-space decay law, the Coulomb cap, tanh saturation, the radial
// bulge's symmetry and volume balance, and the MJPEG camera.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "tacse3/sim/profile.hpp"
#include "tacse3/sim/simulator.hpp"
#include "tacse3/sim/spread.hpp"

namespace tacse3::sim {
namespace {

constexpr const char* kNamed[] = {"reference", "soft-thick", "stiff-thin", "coulomb-rim",
                                  "halfspace-mjpeg"};

std::int64_t ns(double t) {
  return std::llround(t * 1e9);
}

SensorProfile profile(const std::string& name, std::uint64_t seed = 1) {
  SensorProfile p;
  std::string error;
  EXPECT_TRUE(make_profile(name, seed, &p, &error)) << error;
  return p;
}

SimConfig config_for(const SensorProfile& p, MotionAxis axis, double magnitude, Regime regime,
                     bool images) {
  SimConfig c;
  c.scenario.axis = axis;
  c.scenario.magnitude = magnitude;
  c.scenario.regime = regime;
  c.images = images;
  apply_profile(p, &c);
  return c;
}

std::unique_ptr<Simulator> make(const SimConfig& c) {
  std::string error;
  auto sim = Simulator::create(c, &error);
  EXPECT_TRUE(sim) << error;
  return sim;
}

void run_to(Simulator& sim, Sensor s, double t) {
  const double dt = 1.0 / sim.scenario().spec().fps;
  for (double x = 0.0; x < t - 1e-12; x += dt) ASSERT_EQ(sim.step(s, ns(x)), SimStatus::kOk);
  ASSERT_EQ(sim.step(s, ns(t)), SimStatus::kOk);
}

TEST(SimProfiles, EveryProfileValidatesAndBuilds) {
  std::vector<std::string> names(std::begin(kNamed), std::end(kNamed));
  names.push_back("random");
  for (const auto& name : names) {
    const SensorProfile p = profile(name, 7);
    EXPECT_EQ(p.name, name);
    EXPECT_EQ(validate(p), "") << name;
    const SimConfig c = config_for(p, MotionAxis::kRx, 30.0, Regime::kAuto, false);
    EXPECT_EQ(validate(c), "") << name;
    auto sim = make(c);
    ASSERT_TRUE(sim) << name;
    run_to(*sim, Sensor::kLeft, sim->scenario().motion_end_s());
    EXPECT_TRUE(sim->labels(Sensor::kLeft).in_contact) << name;
  }
}

TEST(SimProfiles, UnknownNameIsRejectedWithTheChoices) {
  SensorProfile p;
  std::string error;
  EXPECT_FALSE(make_profile("squishy", 1, &p, &error));
  EXPECT_NE(error.find("squishy"), std::string::npos);
  EXPECT_NE(error.find("halfspace-mjpeg"), std::string::npos);
}

TEST(SimProfiles, ProfilesDifferInEveryModelChoice) {
  std::set<BulgeModel> bulge;
  std::set<SlideLaw> slide;
  std::set<SpreadKernel> spread;
  for (const char* name : kNamed) {
    const SensorProfile p = profile(name);
    bulge.insert(p.gel.bulge_model);
    slide.insert(p.gel.slide_law);
    spread.insert(p.gel.spread_kernel);
  }
  EXPECT_EQ(bulge.size(), 2u);
  EXPECT_EQ(slide.size(), 3u);
  EXPECT_EQ(spread.size(), 2u);
}

// The reference profile is the simulator's default physics: applying it changes nothing, so
// the frames are bit-identical.
TEST(SimProfiles, ReferenceIsTheDefaultPhysics) {
  SimConfig plain;
  plain.scenario.axis = MotionAxis::kRz;
  plain.scenario.magnitude = 3.0;
  SimConfig profiled = plain;
  apply_profile(profile("reference"), &profiled);
  EXPECT_EQ(profiled.scenario.motion_s, plain.scenario.motion_s);
  EXPECT_EQ(profiled.scenario.indentation_mm, plain.scenario.indentation_mm);
  EXPECT_EQ(profiled.scenario.object.size_mm, plain.scenario.object.size_mm);
  EXPECT_EQ(profiled.rig.pixel_pitch_mm, plain.rig.pixel_pitch_mm);
  auto a = make(plain);
  auto b = make(profiled);
  ASSERT_TRUE(a && b);
  std::vector<std::uint8_t> fa(a->frame_bytes(3)), fb(b->frame_bytes(3));
  const Scenario& scn = a->scenario();
  for (int i = 0; i < scn.frame_count(); i += 10) {
    ASSERT_EQ(a->render(Sensor::kLeft, scn.frame_time_ns(i), fa, 3), SimStatus::kOk);
    ASSERT_EQ(b->render(Sensor::kLeft, scn.frame_time_ns(i), fb, 3), SimStatus::kOk);
    ASSERT_EQ(fa, fb) << "frame " << i;
  }
}

TEST(SimProfiles, RandomProfileIsDeterministicBySeed) {
  EXPECT_EQ(profile_values(profile("random", 42)), profile_values(profile("random", 42)));
  EXPECT_NE(profile_values(profile("random", 42)), profile_values(profile("random", 43)));
  // The named profiles ignore the seed.
  EXPECT_EQ(profile_values(profile("soft-thick", 1)), profile_values(profile("soft-thick", 2)));
}

// "random:N" is one sensor: random's draw for N, whatever the recording's seed.
TEST(SimProfiles, ANumberedRandomSensorKeepsItsPhysicsOverSeeds) {
  const SensorProfile a = profile("random:7", 1);
  const SensorProfile b = profile("random:7", 99);
  EXPECT_EQ(a.name, "random:7");
  EXPECT_EQ(profile_values(a), profile_values(b));
  EXPECT_EQ(profile_values(a), profile_values(profile("random", 7)));
  EXPECT_NE(profile_values(a), profile_values(profile("random:8", 1)));
  SensorProfile p;
  std::string error;
  for (const char* bad : {"random:", "random:x", "random:1x", "random:-1", "random:+1", "random: 1",
                          "random:99999999999999999999"}) {
    EXPECT_FALSE(make_profile(bad, 1, &p, &error)) << bad;
    EXPECT_NE(error.find("random:N"), std::string::npos) << error;
  }
}

TEST(SimProfiles, RandomProfileStaysInItsRanges) {
  std::set<BulgeModel> bulge;
  std::set<SlideLaw> slide;
  std::set<SpreadKernel> spread;
  std::set<bool> grey;
  for (std::uint64_t seed = 0; seed < 2000; ++seed) {
    const SensorProfile p = profile("random", seed);
    ASSERT_EQ(validate(p), "") << seed;
    const GelSpec& g = p.gel;
    bulge.insert(g.bulge_model);
    slide.insert(g.slide_law);
    spread.insert(g.spread_kernel);
    grey.insert(p.pattern.grey_dots);
    EXPECT_GE(g.bulge_gain_mm, 1.4);
    EXPECT_LE(g.bulge_gain_mm, 3.8);
    EXPECT_GE(g.bulge_sigma_mm, 0.5);
    EXPECT_LE(g.bulge_sigma_mm, 2.0);
    EXPECT_GE(g.bulge_surface_factor, 0.5);
    EXPECT_LE(g.bulge_surface_factor, 1.0);
    EXPECT_GE(g.gel_thickness_mm, 1.75);
    EXPECT_LE(g.gel_thickness_mm, 4.0);
    EXPECT_GE(g.drag_time_s, 0.005);
    EXPECT_LE(g.drag_time_s, 0.05);
    EXPECT_GE(g.lag_time_s, 0.001);
    EXPECT_LE(g.lag_time_s, 0.05);
    EXPECT_GE(g.shear_compliance, 0.5);
    EXPECT_LE(g.shear_compliance, 3.0);
    EXPECT_LE(g.friction_variation, 0.5);
    EXPECT_GE(g.spread_length_mm, 1.0);
    EXPECT_LE(g.spread_length_mm, 4.0);
    const ShadingSpec& s = p.camera.shading;
    EXPECT_NEAR(s.light_dir.norm(), 1.0, 1e-12);
    EXPECT_GE(s.slope_gain, 0.3);
    EXPECT_LE(s.slope_gain, 1.0);
    const PatternSpec& d = p.pattern;
    const double r_mean = 0.5 * (d.dot_radius_min_mm + d.dot_radius_max_mm);
    EXPECT_GE(r_mean, 0.08 - 1e-12);
    EXPECT_LE(r_mean, 0.2 + 1e-12);
    const double area =
        std::numbers::pi *
        (d.dot_radius_min_mm * d.dot_radius_min_mm + d.dot_radius_min_mm * d.dot_radius_max_mm +
         d.dot_radius_max_mm * d.dot_radius_max_mm) /
        3.0;
    const double density = d.dot_fill * area / (d.dot_spacing_mm * d.dot_spacing_mm);
    EXPECT_GE(density, 0.3 - 1e-9);
    EXPECT_LE(density, 0.7 + 1e-9);
    EXPECT_GE(p.camera.read_noise_dn, 0.5);
    EXPECT_LE(p.camera.read_noise_dn, 4.0);
    EXPECT_LE(p.camera.flicker, 0.04);
    EXPECT_GE(p.camera.vignetting_corner, 0.5);
    EXPECT_LE(p.camera.vignetting_corner, 0.9);
    EXPECT_GE(p.camera.mjpeg_quality, 70);
    EXPECT_LE(p.camera.mjpeg_quality, 95);
    EXPECT_GE(p.pixel_pitch_mm, 0.06);
    EXPECT_LE(p.pixel_pitch_mm, 0.12);
    EXPECT_GE(p.indentation_mm, 0.5);
    EXPECT_LE(p.indentation_mm, 1.5);
    EXPECT_GE(p.object_size_mm, 15.0);
    EXPECT_LE(p.object_size_mm, 30.0);
    EXPECT_GE(p.seconds_per_30deg, 0.5);
    EXPECT_LE(p.seconds_per_30deg, 3.0);
  }
  // Every modelling choice is drawn.
  EXPECT_EQ(bulge.size(), 2u);
  EXPECT_EQ(slide.size(), 3u);
  EXPECT_EQ(spread.size(), 2u);
  EXPECT_EQ(grey.size(), 2u);
}

// Peak in-plane bulge |U_n| of a 20 mm sphere pressed 1 mm into the pad.
double bulge_amplitude_mm(const GelSpec& gel) {
  SimConfig c;
  c.gel = gel;
  c.images = false;
  auto sim = make(c);
  if (!sim) return -1.0;
  EXPECT_EQ(sim->step(Sensor::kLeft, ns(sim->scenario().grasp_end_s())), SimStatus::kOk);
  const PadFields& f = sim->fields(Sensor::kLeft);
  double peak = 0.0;
  for (std::size_t k = 0; k < f.normal_x.size(); ++k) {
    peak = std::max(peak, std::hypot(f.normal_x[k], f.normal_y[k]));
  }
  return peak;
}

// The bulge amplitude a DM-Tac-class gel shows, 0.2-1.0 mm for that sphere (docs/sim-profiles.md):
// the named profiles and the random profile's extremes of both bulge models stay in it.
TEST(SimProfiles, BulgeAmplitudeStaysInItsRange) {
  for (const char* name : kNamed) {
    const double a = bulge_amplitude_mm(profile(name).gel);
    EXPECT_GE(a, 0.2 - 0.005) << name;
    EXPECT_LE(a, 1.0) << name;
  }
  GelSpec g;
  g.bulge_gain_mm = 1.4;  // smallest gain, widest smoothing
  g.bulge_sigma_mm = 2.0;
  EXPECT_NEAR(bulge_amplitude_mm(g), 0.2, 0.01);
  g.bulge_gain_mm = 3.8;  // largest gain, narrowest smoothing
  g.bulge_sigma_mm = 0.5;
  EXPECT_NEAR(bulge_amplitude_mm(g), 1.0, 0.01);
  g.bulge_model = BulgeModel::kRadialVolume;
  g.bulge_surface_factor = 0.5;  // weakest flow, thickest gel
  g.gel_thickness_mm = 4.0;
  EXPECT_NEAR(bulge_amplitude_mm(g), 0.2, 0.02);
  g.bulge_surface_factor = 1.0;  // strongest flow, thinnest gel
  g.gel_thickness_mm = 1.75;
  EXPECT_NEAR(bulge_amplitude_mm(g), 1.0, 0.02);
}

TEST(SimProfiles, SpeedSetsTheMotionDuration) {
  SensorProfile p = profile("reference");
  p.seconds_per_30deg = 2.0;
  EXPECT_DOUBLE_EQ(config_for(p, MotionAxis::kRx, 15.0, Regime::kAuto, false).scenario.motion_s,
                   1.0);
  EXPECT_DOUBLE_EQ(config_for(p, MotionAxis::kTx, -10.0, Regime::kAuto, false).scenario.motion_s,
                   2.0);
}

// The printed area fraction: the share of the undeformed pattern that differs from the bare
// gel matches the profile's density (dots overlap a little and have soft edges).
TEST(SimProfiles, PatternDensityAndGreyDots) {
  for (const char* name : {"stiff-thin", "soft-thick"}) {
    const SensorProfile p = profile(name);
    // Sampled finely (10 um pixels) so the dots' blurred edges hardly count.
    Pattern pat;
    PatternSpec spec = p.pattern;
    spec.edge_px = 0.3;
    spec.supersample = 1;
    pat.build(spec, 0.01, 640, 480, 5);
    const double mean_area = std::numbers::pi *
                             (p.pattern.dot_radius_min_mm * p.pattern.dot_radius_min_mm +
                              p.pattern.dot_radius_min_mm * p.pattern.dot_radius_max_mm +
                              p.pattern.dot_radius_max_mm * p.pattern.dot_radius_max_mm) /
                             3.0;
    const double density =
        p.pattern.dot_fill * mean_area / (p.pattern.dot_spacing_mm * p.pattern.dot_spacing_mm);
    int inked = 0, total = 0;
    for (double y = 0.0; y < 480.0; y += 1.0) {
      for (double x = 0.0; x < 640.0; x += 1.0) {
        const Eigen::Vector3d c = pat.eval(x, y);
        ++total;
        if ((c - Eigen::Vector3d::Constant(p.pattern.background)).norm() > 0.01) ++inked;
        if (p.pattern.grey_dots) {
          ASSERT_NEAR(c.x(), c.y(), 1e-6);
          ASSERT_NEAR(c.y(), c.z(), 1e-6);
        }
      }
    }
    // Overlapping dots lower it by up to about density^2 / 2.
    EXPECT_NEAR(static_cast<double>(inked) / total, density, 0.5 * density * density + 0.02)
        << name;
  }
}

// A uniform disc patch: outside it the half-space spread is U (2/pi) asin(a / (a + delta))
// exp(-delta / L) of the distance delta to the rim, with a 1/r far field.
TEST(SimProfiles, HalfSpaceSpreadFollowsTheRigidPunchLaw) {
  const double L = 3.0;
  EXPECT_DOUBLE_EQ(HalfSpaceSpread::decay(4.0, 0.0, L), 1.0);
  // Far field without the thickness screening: decay * r -> 2 a / pi.
  const double a = 4.0;
  for (double r : {40.0, 80.0, 160.0}) {
    EXPECT_NEAR(HalfSpaceSpread::decay(a, r - a, 1e12) * r, 2.0 * a / std::numbers::pi, 0.01 * a);
  }
  const int gw = 80, gh = 60;
  const double cell = 0.4;
  HalfSpaceSpread spread;
  spread.build(gw, gh, cell, L);
  std::vector<std::uint8_t> contact(static_cast<std::size_t>(gw * gh), 0);
  std::vector<double> ux(contact.size(), 0.0), uy(contact.size(), 0.0);
  const double cx = 40.0, cy = 30.0, radius_cells = 10.0;
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      const auto k = static_cast<std::size_t>(j * gw + i);
      if (std::hypot(i - cx, j - cy) <= radius_cells) {
        contact[k] = 1;
        ux[k] = 0.7;
        uy[k] = -0.2;
      } else {
        ux[k] = 99.0;  // overwritten
      }
    }
  }
  spread.apply(contact.data(), ux.data(), uy.data());
  int area = 0;
  for (auto c : contact) area += c;
  const double a_mm = std::sqrt(area / std::numbers::pi) * cell;
  double worst = 0.0;
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      const auto k = static_cast<std::size_t>(j * gw + i);
      if (contact[k]) {
        ASSERT_EQ(ux[k], 0.7);  // the patch is kept
        continue;
      }
      EXPECT_NEAR(uy[k] * 0.7, -0.2 * ux[k], 1e-12);  // the uniform patch's direction
      const double delta = (std::hypot(i - cx, j - cy) - radius_cells) * cell;
      const double expect = 0.7 * HalfSpaceSpread::decay(a_mm, delta, L);
      if (delta + cell < spread.window_mm()) worst = std::max(worst, std::abs(ux[k] - expect));
      if (delta > spread.window_mm() + cell) {
        ASSERT_EQ(ux[k], 0.0);
      }
    }
  }
  // One cell of discretisation in the distance to the rim: |dU/ddelta| <= U (2/pi/a + 1/L) cell.
  EXPECT_LT(worst, 0.7 * (2.0 / std::numbers::pi / a_mm + 1.0 / L) * cell);
}

// Coulomb rim in a stuck torsion: no cell's shear exceeds mu(x) kappa d, the shallow rim holds
// at that cap (partial slip) while the deep centre follows the object exactly.
TEST(SimProfiles, CoulombRimCapsTheStuckShearAndSlipsAtTheRim) {
  for (double variation : {0.0, 0.4}) {
    SensorProfile p = profile("coulomb-rim");
    p.gel.friction_variation = variation;
    p.seconds_per_30deg = 0.0;
    const SimConfig c = config_for(p, MotionAxis::kRz, 4.0, Regime::kStick, false);
    auto sim = make(c);
    ASSERT_TRUE(sim);
    run_to(*sim, Sensor::kLeft, sim->scenario().motion_end_s());
    const PadFields& f = sim->fields(Sensor::kLeft);
    const double mu = sim->shape().spec().friction, kappa = p.gel.shear_compliance;
    const double angle = 4.0 * std::numbers::pi / 180.0;
    int capped = 0, free_centre = 0;
    for (int j = 0; j < f.gh; ++j) {
      for (int i = 0; i < f.gw; ++i) {
        const std::size_t k = f.index(i, j);
        if (!f.contact[k]) continue;
        const double u = std::hypot(f.tangential_x[k], f.tangential_y[k]);
        const double cap = mu * kappa * f.depth_mm[k];
        ASSERT_LE(u, cap * (1.0 + variation) + 1e-12);
        const double r =
            std::hypot(f.u_mm[static_cast<std::size_t>(i)], f.v_mm[static_cast<std::size_t>(j)]);
        const double rigid = 2.0 * r * std::sin(0.5 * angle);  // chord of the torsion
        if (rigid > cap * (1.0 + variation) + 1e-9) {
          ++capped;
          if (variation == 0.0) {
            EXPECT_NEAR(u, cap, 1e-9);
          }
        } else if (rigid < cap * (1.0 - variation) - 1e-9) {
          ++free_centre;
          EXPECT_NEAR(u, rigid, 1e-3 * r + 1e-9);
        }
      }
    }
    EXPECT_GT(capped, 0);
    EXPECT_GT(free_centre, 0);
    EXPECT_GT(sim->labels(Sensor::kLeft).slip_fraction, 0.0);
  }
}

// tanh slide law: with a short lag the shear is at its target Umax tanh(c|v| / Umax) along v;
// it never exceeds Umax.
TEST(SimProfiles, TanhSlideSaturatesAtTheFrictionLimit) {
  for (double kappa : {3.0, 0.2}) {
    SensorProfile p = profile("soft-thick");
    p.gel.lag_time_s = 0.001;
    p.gel.shear_compliance = kappa;
    p.gel.friction_variation = 0.0;
    p.seconds_per_30deg = 0.0;
    const SimConfig c = config_for(p, MotionAxis::kTx, 6.0, Regime::kSlide, false);
    auto sim = make(c);
    ASSERT_TRUE(sim);
    const Scenario& scn = sim->scenario();
    // Peak speed: the middle of the minimum-jerk motion.
    run_to(*sim, Sensor::kLeft, 0.5 * (scn.motion_start_s() + scn.motion_end_s()));
    const PadFields& f = sim->fields(Sensor::kLeft);
    const double mu = sim->shape().spec().friction;
    int checked = 0;
    for (std::size_t k = 0; k < f.depth_mm.size(); ++k) {
      if (!f.contact[k] || f.depth_mm[k] < 0.3) continue;
      const double umax = mu * kappa * f.depth_mm[k];
      const double v = std::hypot(f.slide_vx[k], f.slide_vy[k]);
      const double u = std::hypot(f.tangential_x[k], f.tangential_y[k]);
      // The previous frame's shear, from a deeper cell, has relaxed to exp(-dt / tau) ~ 3e-4.
      ASSERT_LE(u, umax * (1.0 + 1e-3));
      EXPECT_NEAR(u, umax * std::tanh(p.gel.drag_time_s * v / umax), 0.01 * umax);
      EXPECT_NEAR(f.tangential_x[k] * f.slide_vy[k] - f.tangential_y[k] * f.slide_vx[k], 0.0,
                  1e-3 * u * v + 1e-12);
      ++checked;
    }
    EXPECT_GT(checked, 20);
  }
}

// Radial-volume bulge of a centred sphere: every cell's bulge points straight away from the
// patch centre, equal at equal radii, and outside the patch it carries the whole pressed volume:
// 2 pi r h |U| / eta = V exp(-(r - r_patch) / sigma).
TEST(SimProfiles, RadialBulgeIsRadialOutwardAndConservesVolume) {
  SensorProfile p = profile("soft-thick");
  p.object_size_mm = 20.0;
  const SimConfig c = config_for(p, MotionAxis::kRz, 3.0, Regime::kStick, false);
  auto sim = make(c);
  ASSERT_TRUE(sim);
  run_to(*sim, Sensor::kLeft, sim->scenario().grasp_end_s());
  const PadFields& f = sim->fields(Sensor::kLeft);
  double volume = 0.0, r_patch = 0.0;
  for (int j = 0; j < f.gh; ++j) {
    for (int i = 0; i < f.gw; ++i) {
      const double d = f.depth_mm[f.index(i, j)];
      volume += d * f.cell_mm * f.cell_mm;
      if (d > 0.0) {
        r_patch = std::max(r_patch, std::hypot(f.u_mm[static_cast<std::size_t>(i)],
                                               f.v_mm[static_cast<std::size_t>(j)]));
      }
    }
  }
  ASSERT_GT(volume, 0.0);
  const double h = p.gel.gel_thickness_mm, eta = p.gel.bulge_surface_factor;
  int outside = 0;
  for (int j = 0; j < f.gh; ++j) {
    for (int i = 0; i < f.gw; ++i) {
      const std::size_t k = f.index(i, j);
      const double u = f.u_mm[static_cast<std::size_t>(i)], v = f.v_mm[static_cast<std::size_t>(j)];
      const double r = std::hypot(u, v);
      const double nx = f.normal_x[k], ny = f.normal_y[k];
      const double mag = std::hypot(nx, ny);
      if (r < 0.5) continue;
      EXPECT_NEAR(nx * v - ny * u, 0.0, 1e-3 * mag * r + 1e-12);  // radial
      EXPECT_GT(nx * u + ny * v, 0.0);                            // outward
      // Mirror symmetry of the centred sphere: (u, v) and (-u, -v) carry opposite vectors.
      const std::size_t m = f.index(f.gw - 1 - i, f.gh - 1 - j);
      EXPECT_NEAR(f.normal_x[m], -nx, 1e-6 * (mag + 1.0));
      if (r > r_patch + 1.0) {
        const double expect = volume * std::exp(-(r - r_patch) / p.gel.bulge_sigma_mm);
        EXPECT_NEAR(2.0 * std::numbers::pi * r * h * mag / eta, expect, 0.02 * expect + 1e-9);
        ++outside;
      }
    }
  }
  EXPECT_GT(outside, 100);
}

// Peak signal-to-noise ratio of the luma (BT.601) of two frames, in dB.
double luma_psnr(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b,
                 int channels) {
  double se = 0.0;
  const std::size_t n = a.size() / static_cast<std::size_t>(channels);
  for (std::size_t k = 0; k < n; ++k) {
    double d = static_cast<double>(a[k]) - b[k];
    if (channels == 3) {
      const std::size_t q = 3 * k;
      d = 0.299 * (a[q] - b[q]) + 0.587 * (a[q + 1] - b[q + 1]) + 0.114 * (a[q + 2] - b[q + 2]);
    }
    se += d * d;
  }
  return 10.0 * std::log10(255.0 * 255.0 / (se / static_cast<double>(n)));
}

// The MJPEG camera delivers the rendered frame JPEG-compressed: changed, but its luma within
// the PSNR a JPEG of that quality keeps (> 30 dB), and closer at a higher quality. (The colour
// of dots a few pixels wide is lost to the 4:2:2 chroma subsampling, as on a UVC camera.)
TEST(SimProfiles, MjpegFramesStayCloseToTheRawOnes) {
  if (!mjpeg_available()) GTEST_SKIP() << "built without libturbojpeg";
  SensorProfile p = profile("reference");
  p.camera.noise = 1.0;
  double last = 0.0;
  for (int quality : {70, 85, 95}) {
    for (int channels : {3, 1}) {
      SimConfig raw = config_for(p, MotionAxis::kRz, 3.0, Regime::kStick, true);
      SimConfig jpeg = raw;
      jpeg.camera.mjpeg_quality = quality;
      auto a = make(raw);
      auto b = make(jpeg);
      ASSERT_TRUE(a && b);
      std::vector<std::uint8_t> fa(a->frame_bytes(channels)), fb(b->frame_bytes(channels));
      const std::int64_t t = ns(a->scenario().grasp_end_s());
      ASSERT_EQ(a->render(Sensor::kRight, t, fa, channels), SimStatus::kOk);
      ASSERT_EQ(b->render(Sensor::kRight, t, fb, channels), SimStatus::kOk);
      ASSERT_NE(fa, fb);
      const double q = luma_psnr(fa, fb, channels);
      EXPECT_GT(q, 30.0) << quality << " " << channels;
      if (channels == 3) {
        EXPECT_GT(q, last) << quality;
        last = q;
      }
    }
  }
}

TEST(SimProfiles, MjpegQualityIsValidated) {
  CameraSpec c;
  c.mjpeg_quality = 101;
  EXPECT_NE(validate(c).find("mjpeg_quality"), std::string::npos);
  c.mjpeg_quality = -1;
  EXPECT_NE(validate(c).find("mjpeg_quality"), std::string::npos);
}

// The random profile renders the same frames for the same seed.
TEST(SimProfiles, RandomProfileRendersDeterministically) {
  const SensorProfile p = profile("random", 11);
  const SimConfig c = config_for(p, MotionAxis::kRx, 5.0, Regime::kAuto, true);
  auto a = make(c);
  auto b = make(c);
  ASSERT_TRUE(a && b);
  std::vector<std::uint8_t> fa(a->frame_bytes(3)), fb(b->frame_bytes(3));
  const std::int64_t t = ns(a->scenario().grasp_end_s());
  ASSERT_EQ(a->render(Sensor::kLeft, t, fa, 3), SimStatus::kOk);
  ASSERT_EQ(b->render(Sensor::kLeft, t, fb, 3), SimStatus::kOk);
  EXPECT_EQ(fa, fb);
}

}  // namespace
}  // namespace tacse3::sim
