// SPDX-License-Identifier: Apache-2.0
// Tests of the simulator's contact mechanics: patch, bulge, stick kinematics, slide drag law.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include "tacse3/sim/simulator.hpp"

namespace tacse3::sim {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr Sensor kBoth[] = {Sensor::kLeft, Sensor::kRight};

SimConfig sphere_config(MotionAxis axis, double magnitude, Regime regime) {
  SimConfig c;
  c.scenario.object.shape = ShapeKind::kSphere;
  c.scenario.object.size_mm = 20.0;
  c.scenario.indentation_mm = 1.0;
  c.scenario.axis = axis;
  c.scenario.magnitude = magnitude;
  c.scenario.regime = regime;
  c.images = false;  // fields only
  return c;
}

std::unique_ptr<Simulator> make(const SimConfig& c) {
  std::string error;
  auto sim = Simulator::create(c, &error);
  EXPECT_TRUE(sim) << error;
  return sim;
}

std::int64_t ns(double t) {
  return std::llround(t * 1e9);
}

// Steps both pads at the frame rate from `from` to t (inclusive of t).
void run_to(Simulator& sim, double t, double from = 0.0) {
  const double dt = 1.0 / sim.scenario().spec().fps;
  for (double s = from; s < t - 1e-12; s += dt) {
    for (Sensor p : kBoth) ASSERT_EQ(sim.step(p, ns(s)), SimStatus::kOk);
  }
  for (Sensor p : kBoth) ASSERT_EQ(sim.step(p, ns(t)), SimStatus::kOk);
}

TEST(SimPhysics, SpherePatchMatchesHertzianGeometry) {
  auto sim = make(sphere_config(MotionAxis::kRz, 30.0, Regime::kAuto));
  ASSERT_TRUE(sim);
  const double R = 20.0, d = 1.0;
  EXPECT_NEAR(sim->finger_separation_mm(), 2.0 * (R - d), 1e-5);
  for (Sensor p : kBoth) {
    ASSERT_EQ(sim->step(p, ns(sim->scenario().grasp_end_s())), SimStatus::kOk);
    const PadLabels& l = sim->labels(p);
    const PadFields& f = sim->fields(p);
    EXPECT_TRUE(l.in_contact);
    EXPECT_NEAR(l.peak_depth_mm, d, 3e-3);  // the peak lies between cell centres
    EXPECT_NEAR(f.pad_surface_mm, R - d, 5e-6);
    // Contact area of a sphere pressed d into a plane: pi (2 R d - d^2).
    EXPECT_NEAR(l.area_mm2, std::numbers::pi * (2 * R * d - d * d), 0.04 * l.area_mm2);
    EXPECT_NEAR(l.centroid_mm.norm(), 0.0, 0.05);
    // Depth at every cell equals the sphere's cap height.
    double worst = 0.0;
    for (int j = 0; j < f.gh; ++j) {
      for (int i = 0; i < f.gw; ++i) {
        const double u = f.u_mm[static_cast<std::size_t>(i)],
                     v = f.v_mm[static_cast<std::size_t>(j)];
        const double expect =
            std::max(0.0, std::sqrt(std::max(0.0, R * R - u * u - v * v)) - (R - d));
        worst = std::max(worst, std::abs(f.depth_mm[f.index(i, j)] - expect));
      }
    }
    EXPECT_LT(worst, 1e-5);
  }
}

TEST(SimPhysics, NormalBulgePushesThePatternOutward) {
  auto sim = make(sphere_config(MotionAxis::kRz, 30.0, Regime::kAuto));
  ASSERT_TRUE(sim);
  ASSERT_EQ(sim->step(Sensor::kLeft, ns(sim->scenario().grasp_end_s())), SimStatus::kOk);
  const PadFields& f = sim->fields(Sensor::kLeft);
  int outward = 0, total = 0;
  double max_mag = 0.0;
  for (std::size_t k = 0; k < f.normal_x.size(); ++k) {
    const double u = f.u_mm[k % static_cast<std::size_t>(f.gw)];
    const double v = f.v_mm[k / static_cast<std::size_t>(f.gw)];
    const double r = std::hypot(u, v);
    if (r < 2.0 || r > 9.0) continue;
    const double radial = (f.normal_x[k] * u + f.normal_y[k] * v) / r;
    const double tangential = (-f.normal_x[k] * v + f.normal_y[k] * u) / r;
    ++total;
    outward += radial > 0.0 ? 1 : 0;
    EXPECT_LT(std::abs(tangential), 1e-3 + 0.02 * std::abs(radial));
    max_mag = std::max(max_mag, std::hypot(f.normal_x[k], f.normal_y[k]));
  }
  EXPECT_EQ(outward, total);
  EXPECT_GT(max_mag, 0.1);  // a visible bulge: > 1 px at P = 0.1 mm
  EXPECT_LT(max_mag, 0.5);
}

// Stick: inside the patch the gel displacement is exactly the object's surface kinematics.
void expect_stick_kinematics(MotionAxis axis, double magnitude) {
  auto sim = make(sphere_config(axis, magnitude, Regime::kStick));
  ASSERT_TRUE(sim);
  ASSERT_FALSE(sim->scenario().sliding());
  const double R = 20.0;
  for (double frac : {0.5, 1.0}) {
    const double t = sim->scenario().motion_start_s() + frac * sim->scenario().motion_duration_s();
    const Pose pose = sim->scenario().pose(t);
    for (Sensor p : kBoth) {
      ASSERT_EQ(sim->step(p, ns(t)), SimStatus::kOk);
      const PadFields& f = sim->fields(p);
      const Eigen::Matrix3d rpad = pad_rotation(p);
      int cells = 0;
      double worst = 0.0;
      for (int j = 0; j < f.gh; ++j) {
        for (int i = 0; i < f.gw; ++i) {
          const std::size_t k = f.index(i, j);
          if (!f.contact[k]) continue;
          ++cells;
          // The sphere's surface point over this cell, in the pad frame, then in G.
          const double u = f.u_mm[static_cast<std::size_t>(i)],
                       v = f.v_mm[static_cast<std::size_t>(j)];
          const Eigen::Vector2d o = sim->scenario().object().offset_mm;
          const Eigen::Vector3d off = Eigen::Vector3d(o.x(), o.y(), 0.0) + pose.p;  // sphere centre
          const double du = u - (rpad * off).x(), dv = v - (rpad * off).y();
          const Eigen::Vector3d c_pad(u, v,
                                      (rpad * off).z() + std::sqrt(R * R - du * du - dv * dv));
          const Eigen::Vector3d c_g = rpad.transpose() * c_pad;
          // It came from where the motion's inverse puts it.
          const Eigen::Vector3d from = pose.q.conjugate() * (c_g - pose.p);
          const Eigen::Vector3d disp = rpad * (c_g - from);
          worst = std::max(worst,
                           std::hypot(f.tangential_x[k] - disp.x(), f.tangential_y[k] - disp.y()));
        }
      }
      EXPECT_GT(cells, 500);
      EXPECT_LT(worst, 2e-5) << to_string(axis) << " " << to_string(p) << " frac " << frac;
    }
  }
}

TEST(SimPhysics, StickRotationFollowsSurfaceKinematicsExactly) {
  expect_stick_kinematics(MotionAxis::kRx, 2.0);
  expect_stick_kinematics(MotionAxis::kRy, -3.0);
  expect_stick_kinematics(MotionAxis::kRz, 4.0);
}

TEST(SimPhysics, StickTranslationFollowsSurfaceKinematicsExactly) {
  expect_stick_kinematics(MotionAxis::kTx, 0.6);
  expect_stick_kinematics(MotionAxis::kTy, -0.4);
}

// Stick bonds the gel to the object: the material now at c sits where the object carried it
// since the motion started, bulge and all (docs/simulator.md §6). For a torsion of a centred
// sphere the bulge is radial and does not change, so the material now at c came from R⁻¹c and
// was displaced there by U_n(R⁻¹c) = R⁻¹U_n(c): U(c) = c − R⁻¹c + R⁻¹U_n(c). The plain sum
// U_t + U_n leaves the bulge vector unturned (off by θ|U_n|, 15 µm here), which would make the
// image's patch turn faster than the object. In a translation the
// bulge moves with the object: U(c) = t + U_n(c), the plain sum (sampling the moved bulge where
// the material came from would shift it twice, by t·∇U_n: 41 µm here).
TEST(SimPhysics, AStuckObjectCarriesTheBulgedGelWithIt) {
  struct Case {
    MotionAxis axis;
    double magnitude;
    bool join;
  };
  // The in-plane rotation about x carries the patch's gel ≈ θ·R along y over a bulge that stays
  // (a sphere turning about its centre): U(c) = U_t(c) + U_n(c − U_t(c)), sampled here
  // bilinearly between cells. `join`: the pad is first stepped at the end of the motion, as the
  // live camera joins a scenario at the present; it bonds the bulge it finds (for this torsion
  // the same).
  for (const Case& m : {Case{MotionAxis::kRz, 4.0, false}, Case{MotionAxis::kTx, 0.6, false},
                        Case{MotionAxis::kRx, 4.0, false}, Case{MotionAxis::kRz, 4.0, true}}) {
    auto sim = make(sphere_config(m.axis, m.magnitude, Regime::kStick));
    ASSERT_TRUE(sim);
    const double t = sim->scenario().motion_start_s() + sim->scenario().motion_duration_s();
    if (m.join) {
      for (Sensor p : kBoth) ASSERT_EQ(sim->step(p, ns(t)), SimStatus::kOk);
    } else {
      run_to(*sim, t);
    }
    const Pose pose = sim->scenario().pose(t);
    for (Sensor p : kBoth) {
      const PadFields& f = sim->fields(p);
      const Eigen::Matrix3d rpad = pad_rotation(p);
      // The in-plane rotation the pad sees (the right pad is mirrored: −θ), and the shift.
      const Eigen::Matrix2d r_inv =
          (rpad * pose.q.conjugate().toRotationMatrix() * rpad.transpose()).topLeftCorner<2, 2>();
      const Eigen::Vector2d shift = (rpad * pose.p).head<2>();
      int cells = 0;
      double worst = 0.0, plain_sum_off = 0.0, twice_shifted_off = 0.0;
      for (int j = 0; j < f.gh; ++j) {
        for (int i = 0; i < f.gw; ++i) {
          const std::size_t k = f.index(i, j);
          if (!f.contact[k]) continue;
          const Eigen::Vector2d c(f.u_mm[static_cast<std::size_t>(i)],
                                  f.v_mm[static_cast<std::size_t>(j)]);
          const Eigen::Vector2d un(f.normal_x[k], f.normal_y[k]);
          const Eigen::Vector2d ut(f.tangential_x[k], f.tangential_y[k]);
          Eigen::Vector2d expected = shift + un;
          if (m.axis == MotionAxis::kRz) expected = c - r_inv * c + r_inv * un;
          if (m.axis == MotionAxis::kRx) {
            const double fi = i - ut.x() / f.cell_mm, fj = j - ut.y() / f.cell_mm;
            const int i0 = static_cast<int>(std::floor(fi)), j0 = static_cast<int>(std::floor(fj));
            if (i0 < 0 || j0 < 0 || i0 + 1 >= f.gw || j0 + 1 >= f.gh) continue;
            const double wx = fi - i0, wy = fj - j0;
            Eigen::Vector2d from = Eigen::Vector2d::Zero();
            for (int b = 0; b < 2; ++b) {
              for (int a = 0; a < 2; ++a) {
                const std::size_t q = f.index(i0 + a, j0 + b);
                from += (a ? wx : 1.0 - wx) * (b ? wy : 1.0 - wy) *
                        Eigen::Vector2d(f.normal_x[q], f.normal_y[q]);
              }
            }
            expected = ut + from;
          }
          const Eigen::Vector2d total(f.total_x[k], f.total_y[k]);
          ++cells;
          worst = std::max(worst, (total - expected).norm());
          plain_sum_off = std::max(plain_sum_off, (ut + un - expected).norm());
          // The current bulge sampled where the material came from, c − t (t along x here),
          // linearly between the two cells around it.
          const double back = shift.x() / f.cell_mm;
          const int b0 = static_cast<int>(std::floor(back));
          if (m.axis == MotionAxis::kTx && i - b0 - 1 >= 0 && i - b0 < f.gw) {
            const double w = back - b0;
            const std::size_t k0 = f.index(i - b0, j), k1 = f.index(i - b0 - 1, j);
            const Eigen::Vector2d moved((1.0 - w) * f.normal_x[k0] + w * f.normal_x[k1],
                                        (1.0 - w) * f.normal_y[k0] + w * f.normal_y[k1]);
            twice_shifted_off = std::max(twice_shifted_off, (shift + moved - expected).norm());
          }
        }
      }
      EXPECT_GT(cells, 500);
      std::printf(
          "%s%s %s: %d cells, off by %.1f um (plain sum %.1f um, bulge shifted twice %.1f um)\n",
          to_string(m.axis), m.join ? " joined" : "", to_string(p), cells, worst * 1e3,
          plain_sum_off * 1e3, twice_shifted_off * 1e3);
      EXPECT_LT(worst, 3e-3) << to_string(m.axis) << " " << to_string(p);  // mm: bilinear sampling
      if (m.axis != MotionAxis::kTx) {
        EXPECT_GT(plain_sum_off, 10e-3) << "the bulge must be large enough to tell them apart";
      } else {
        EXPECT_GT(twice_shifted_off, 10e-3) << "the bulge must be large enough to tell them apart";
      }
    }
  }
}

// The pads open after a stuck hold: the bonded bulge relaxes with the load, so the rendered
// field changes smoothly until the contact is gone (no jump when its last cell lets go).
TEST(SimPhysics, AReleasedStuckContactLetsItsBondedGelGoSmoothly) {
  SimConfig cfg = sphere_config(MotionAxis::kRx, 4.0, Regime::kStick);
  cfg.scenario.release_s = 0.3;
  auto sim = make(cfg);
  ASSERT_TRUE(sim);
  const double dt = 1.0 / sim->scenario().spec().fps;
  const double t0 = sim->scenario().motion_end_s();
  run_to(*sim, t0);
  std::vector<double> last_x = sim->fields(Sensor::kLeft).bond_x;
  std::vector<double> last_y = sim->fields(Sensor::kLeft).bond_y;
  double worst_step = 0.0, worst_at_loss = 0.0;
  bool had_contact = true;
  for (double t = t0 + dt; t < sim->scenario().duration_s(); t += dt) {
    ASSERT_EQ(sim->step(Sensor::kLeft, ns(t)), SimStatus::kOk);
    const PadFields& f = sim->fields(Sensor::kLeft);
    double step = 0.0;
    bool contact = false;
    for (std::size_t k = 0; k < f.total_x.size(); ++k) {
      step = std::max(step, std::hypot(f.bond_x[k] - last_x[k], f.bond_y[k] - last_y[k]));
      contact = contact || f.contact[k] != 0;
    }
    worst_step = std::max(worst_step, step);
    if (had_contact && !contact) worst_at_loss = step;
    had_contact = contact;
    last_x = f.bond_x;
    last_y = f.bond_y;
  }
  std::printf("release: the bond's largest per-frame change %.1f um, at contact loss %.1f um\n",
              worst_step * 1e3, worst_at_loss * 1e3);
  EXPECT_FALSE(had_contact);
  // A bond that held the full grasp bulge to the end would jump by about that bulge at the
  // contact's loss, far beyond both bounds.
  EXPECT_LT(worst_at_loss, 10e-3);
  EXPECT_LT(worst_step, 60e-3);
}

TEST(SimPhysics, RightPadIsMirroredImageYIsMinusGy) {
  // Translation along G y: the left image sees +y, the right image -y; along G x both see +x.
  for (auto [axis, sx, sy] :
       {std::tuple{MotionAxis::kTy, 0.0, 1.0}, std::tuple{MotionAxis::kTx, 1.0, 0.0}}) {
    auto sim = make(sphere_config(axis, 0.5, Regime::kStick));
    ASSERT_TRUE(sim);
    const double t = sim->scenario().motion_end_s();
    for (Sensor p : kBoth) {
      ASSERT_EQ(sim->step(p, ns(t)), SimStatus::kOk);
      const PadFields& f = sim->fields(p);
      const std::size_t centre = f.index(f.gw / 2, f.gh / 2);
      const double mirror = p == Sensor::kRight ? -1.0 : 1.0;
      EXPECT_NEAR(f.tangential_x[centre], 0.5 * sx, 1e-5);
      EXPECT_NEAR(f.tangential_y[centre], 0.5 * sy * mirror, 1e-5);
    }
  }
  // Rotation about G z: the two images show opposite senses of rotation (curl).
  auto sim = make(sphere_config(MotionAxis::kRz, 3.0, Regime::kStick));
  ASSERT_TRUE(sim);
  double curl[2] = {0.0, 0.0};
  for (Sensor p : kBoth) {
    ASSERT_EQ(sim->step(p, ns(sim->scenario().motion_end_s())), SimStatus::kOk);
    const PadFields& f = sim->fields(p);
    const int ci = f.gw / 2, cj = f.gh / 2;
    curl[index_of(p)] =
        (f.tangential_y[f.index(ci + 5, cj)] - f.tangential_y[f.index(ci - 5, cj)]) -
        (f.tangential_x[f.index(ci, cj + 5)] - f.tangential_x[f.index(ci, cj - 5)]);
  }
  EXPECT_GT(curl[0], 0.0);
  EXPECT_NEAR(curl[1], -curl[0], 1e-6);
  // Contact patches of a translation along G y move in opposite image directions.
  auto ty = make(sphere_config(MotionAxis::kTy, 8.0, Regime::kSlide));
  ASSERT_TRUE(ty);
  for (Sensor p : kBoth) {
    const double mirror = p == Sensor::kRight ? -1.0 : 1.0;
    ASSERT_EQ(ty->step(p, ns(ty->scenario().motion_start_s())), SimStatus::kOk);
    EXPECT_NEAR(ty->labels(p).centroid_mm.y(), -4.0 * mirror, 0.1);
    ASSERT_EQ(ty->step(p, ns(ty->scenario().motion_end_s())), SimStatus::kOk);
    EXPECT_NEAR(ty->labels(p).centroid_mm.y(), 4.0 * mirror, 0.1);
  }
}

TEST(SimPhysics, SlideFollowsTheViscousDragLawWithLag) {
  SimConfig c = sphere_config(MotionAxis::kRz, 30.0, Regime::kSlide);
  c.scenario.object.friction = 5.0;  // far from the friction cap: pure drag law
  auto sim = make(c);
  ASSERT_TRUE(sim);
  const Scenario& scn = sim->scenario();
  const double t_end = scn.motion_start_s() + 0.6 * scn.motion_duration_s();
  run_to(*sim, t_end);
  // Reference: tau dU/dt = c v(t) - U for the cell at radius r, v = omega(t) r, integrated finely.
  const double tau = c.gel.lag_time_s, drag = c.gel.drag_time_s;
  const PadFields& f = sim->fields(Sensor::kLeft);
  const int i = f.gw / 2 + 7, j = f.gh / 2;
  const std::size_t k = f.index(i, j);
  ASSERT_TRUE(f.contact[k]);
  const double cu = f.u_mm[static_cast<std::size_t>(i)], cv = f.v_mm[static_cast<std::size_t>(j)];
  // The sliding velocity is omega x (u, v) = omega (-v, u): U = s(t) (-v, u) with
  // tau ds/dt = c omega(t) - s.
  double s = 0.0;
  const double h = 1e-5;
  for (double t = scn.motion_start_s(); t < t_end; t += h) {
    s += h * (drag * scn.twist(t + 0.5 * h).w.z() - s) / tau;
  }
  const double u = s * cu;
  EXPECT_GT(u, 0.05);
  EXPECT_NEAR(f.tangential_y[k], u, 0.01 * u);
  EXPECT_NEAR(f.tangential_x[k], -s * cv, 0.01 * u);
  // Lag: the displacement trails the steady state c v(t).
  const double steady = drag * scn.twist(t_end).w.z() * cu;
  EXPECT_GT(std::abs(steady - f.tangential_y[k]), 0.01 * u);
  // Elastic spreading: outside the patch the field decays smoothly to zero.
  const int edge_i = f.gw / 2 + 16;  // u ~ 6.6 mm, just outside the 6.2 mm patch
  ASSERT_FALSE(f.contact[f.index(edge_i, j)]);
  const double near =
      std::hypot(f.tangential_x[f.index(edge_i, j)], f.tangential_y[f.index(edge_i, j)]);
  const double far =
      std::hypot(f.tangential_x[f.index(f.gw - 1, j)], f.tangential_y[f.index(f.gw - 1, j)]);
  EXPECT_GT(near, 0.02);
  EXPECT_LT(far, 0.05 * near);
  // The right pad sees the same physics, mirrored: opposite image y at the mirrored cell.
  const PadFields& fr = sim->fields(Sensor::kRight);
  EXPECT_NEAR(fr.tangential_y[k], -u, 0.01 * u);
  EXPECT_NEAR(fr.tangential_x[k], s * cv, 0.01 * u);
  EXPECT_TRUE(sim->labels(Sensor::kLeft).slipping);
}

TEST(SimPhysics, SlideSaturatesAtTheFrictionLimitAndRelaxesAfterwards) {
  SimConfig c = sphere_config(MotionAxis::kRx, 60.0, Regime::kSlide);
  c.scenario.object.friction = 0.2;
  auto sim = make(c);
  ASSERT_TRUE(sim);
  const Scenario& scn = sim->scenario();
  run_to(*sim, scn.motion_start_s() + 0.5 * scn.motion_duration_s());
  const double cap_per_mm = 0.2 * c.gel.shear_compliance;
  for (Sensor p : kBoth) {
    const PadFields& f = sim->fields(p);
    int cells = 0, at_cap = 0;
    for (std::size_t k = 0; k < f.contact.size(); ++k) {
      if (!f.contact[k]) continue;
      ++cells;
      const double cap = cap_per_mm * f.depth_mm[k];
      const double mag = std::hypot(f.tangential_x[k], f.tangential_y[k]);
      EXPECT_LE(mag, cap * (1.0 + 1e-5) + 1e-7);
      if (mag > cap * (1.0 - 1e-4)) ++at_cap;
      // Direction: the sliding direction, -v for rx on both images (see docs/simulator.md).
      if (f.depth_mm[k] > 0.2) {
        EXPECT_LT(f.tangential_y[k], 0.0);
      }
    }
    EXPECT_GT(at_cap, 0.95 * cells);
  }
  // After the motion the drag vanishes and the shear relaxes with the lag time.
  run_to(*sim, scn.motion_end_s() + 10.0 * c.gel.lag_time_s,
         scn.motion_start_s() + 0.5 * scn.motion_duration_s() + 1.0 / scn.spec().fps);
  for (Sensor p : kBoth) {
    const PadFields& f = sim->fields(p);
    double worst = 0.0;
    for (std::size_t k = 0; k < f.contact.size(); ++k) {
      worst = std::max(worst, std::hypot(f.tangential_x[k], f.tangential_y[k]));
    }
    EXPECT_LT(worst, 1e-3);
    EXPECT_FALSE(sim->labels(p).slipping);
  }
}

TEST(SimPhysics, PatchMovesOverThePadWhenTheObjectTranslates) {
  auto sim = make(sphere_config(MotionAxis::kTx, 10.0, Regime::kSlide));
  ASSERT_TRUE(sim);
  const Scenario& scn = sim->scenario();
  for (double frac : {0.0, 0.25, 0.5, 1.0}) {
    const double t = scn.motion_start_s() + frac * scn.motion_duration_s();
    const double expect = -5.0 + 10.0 * scn.progress(t);
    for (Sensor p : kBoth) {
      ASSERT_EQ(sim->step(p, ns(t)), SimStatus::kOk);
      EXPECT_NEAR(sim->labels(p).centroid_mm.x(), expect, 0.05) << frac;
    }
  }
}

TEST(SimPhysics, EveryObjectPresetTouchesBothPads) {
  for (const char* name : {"sphere", "large-sphere", "ellipsoid", "irregular", "cylinder",
                           "plastic-cube", "wooden-cube", "textured-cube", "screwdriver"}) {
    SimConfig c;
    c.images = false;
    ASSERT_TRUE(object_preset(name, &c.scenario.object)) << name;
    c.scenario.axis = MotionAxis::kRz;
    auto sim = make(c);
    ASSERT_TRUE(sim) << name;
    EXPECT_GT(sim->finger_separation_mm(), 10.0) << name;
    for (Sensor p : kBoth) {
      ASSERT_EQ(sim->step(p, ns(sim->scenario().grasp_end_s())), SimStatus::kOk);
      EXPECT_TRUE(sim->labels(p).in_contact) << name;
      EXPECT_NEAR(sim->labels(p).peak_depth_mm, 1.0, 0.05) << name;
      EXPECT_GT(sim->labels(p).area_mm2, 20.0) << name;
    }
  }
  // A flat face: the cube's patch is a rounded square of uniform depth.
  SimConfig c;
  c.images = false;
  object_preset("plastic-cube", &c.scenario.object);
  auto cube = make(c);
  ASSERT_TRUE(cube);
  ASSERT_EQ(cube->step(Sensor::kLeft, ns(cube->scenario().grasp_end_s())), SimStatus::kOk);
  const PadFields& f = cube->fields(Sensor::kLeft);
  EXPECT_NEAR(f.depth_mm[f.index(f.gw / 2 + 10, f.gh / 2 + 10)], 1.0,
              1e-5);  // (4, 4) mm: on the face
  // Flat 16 mm face plus the 2 mm edge rounding down to 1 mm: 19.46 mm square, rounded corners.
  EXPECT_NEAR(cube->labels(Sensor::kLeft).area_mm2, 376.0, 15.0);
}

TEST(SimPhysics, FingerSeparationFitsTheObject) {
  SimConfig c = sphere_config(MotionAxis::kRz, 30.0, Regime::kAuto);
  std::string error;
  ASSERT_TRUE(fit_object_to_separation(&c, 30.0, &error)) << error;
  EXPECT_NEAR(c.scenario.object.size_mm, 16.0, 1e-3);
  EXPECT_NEAR(nominal_finger_separation(c, &error), 30.0, 1e-3);
}

TEST(SimPhysics, TimeMustNotGoBackwardsUntilReset) {
  auto sim = make(sphere_config(MotionAxis::kRz, 30.0, Regime::kAuto));
  ASSERT_TRUE(sim);
  EXPECT_EQ(sim->step(Sensor::kLeft, ns(1.0)), SimStatus::kOk);
  EXPECT_EQ(sim->step(Sensor::kLeft, ns(0.5)), SimStatus::kTimeBackwards);
  sim->reset(Sensor::kLeft);
  EXPECT_EQ(sim->step(Sensor::kLeft, ns(0.5)), SimStatus::kOk);
  std::string error;
  SimConfig bad = sphere_config(MotionAxis::kRz, 30.0, Regime::kAuto);
  bad.scenario.object.offset_mm = {40.0, 0.0};
  EXPECT_EQ(Simulator::create(bad, &error), nullptr);
  EXPECT_NE(error.find("does not reach"), std::string::npos) << error;
}

}  // namespace
}  // namespace tacse3::sim
