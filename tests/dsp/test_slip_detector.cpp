// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: VelocityProxy::kAuto: planar rigid content, stick/slip decisions, deficit payback.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <vector>

#include "tacse3/dsp/calibration.hpp"
#include "tacse3/dsp/motion.hpp"
#include "tacse3/dsp/slip_payback.hpp"
#include "tacse3/dsp_ref/motion_ref.hpp"

namespace tacse3::dsp {
namespace {

constexpr double kDt = 1.0 / 120.0;
constexpr double kPitchM = 0.6e-3;  // flow-grid spacing on the pad (8 sensor px of 0.075 mm)
constexpr double kDeg = std::numbers::pi / 180.0;

// A disc of grid cells (radius 6 cells by default) around the grid centre, 0.5 mm deep, as a
// ContactSet and as the reference's ContactSetRef (same points).
struct Disc {
  std::unique_ptr<ContactSet> cs = std::make_unique<ContactSet>();
  dsp_ref::ContactSetRef ref;
  explicit Disc(double radius_cells = 6.0, double depth_m = 0.5e-3) {
    const auto n = static_cast<std::size_t>(kGridCount);
    ref.mask.assign(n, 0);
    ref.fz_filtered.assign(n, 0.0);
    ref.q.assign(n, Eigen::Vector3d::Zero());
    for (int gy = 0; gy < kGridHeight; ++gy) {
      for (int gx = 0; gx < kGridWidth; ++gx) {
        const double x = (gx - kGridWidth / 2 + 0.5) * kPitchM;
        const double y = (gy - kGridHeight / 2 + 0.5) * kPitchM;
        if (std::hypot(x, y) > radius_cells * kPitchM) continue;
        const auto i = static_cast<std::size_t>(gy * kGridWidth + gx);
        const auto xn = static_cast<std::int32_t>(std::lround(x * 1e9));
        const auto yn = static_cast<std::int32_t>(std::lround(y * 1e9));
        cs->mask.v[i] = 1;
        cs->x_nm.v[i] = xn;
        cs->y_nm.v[i] = yn;
        const auto zn = static_cast<std::int32_t>(std::lround(depth_m * 1e9));
        cs->z_nm.v[i] = zn;
        ++cs->count;
        ref.mask[i] = 1;
        ref.q[i] = Eigen::Vector3d(xn * 1e-9, yn * 1e-9, zn * 1e-9);
        ++ref.count;
      }
    }
    cs->contact = cs->count > 0;
  }
  // Shear (shear units) of a rotation by theta about the pad normal plus a shift (m), read as a
  // contact displacement with c_displacement.
  void shear(double theta, double tx, double c_disp, VectorField& out, std::vector<double>& sx,
             std::vector<double>& sy) const {
    out.x.fill(0);
    out.y.fill(0);
    sx.assign(static_cast<std::size_t>(kGridCount), 0.0);
    sy.assign(static_cast<std::size_t>(kGridCount), 0.0);
    for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
      if (cs->mask.v[i] == 0) continue;
      const double x = cs->x_nm.v[i] * 1e-9, y = cs->y_nm.v[i] * 1e-9;
      const double ux = (-theta * y + tx) / c_disp, uy = theta * x / c_disp;
      out.x.v[i] = static_cast<std::int32_t>(std::lround(ux * 65536.0));
      out.y.v[i] = static_cast<std::int32_t>(std::lround(uy * 65536.0));
      sx[i] = out.x.v[i] / 65536.0;
      sy[i] = out.y.v[i] / 65536.0;
    }
  }
};

// Minimum-jerk position and its rate on [0, 1].
double min_jerk(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
}
double min_jerk_rate(double s) {
  if (s <= 0.0 || s >= 1.0) return 0.0;
  return 30.0 * s * s * (1.0 - s) * (1.0 - s);
}

// The gel's drag time (shear displacement per unit sliding speed) of the simulator, 50 ms:
// c_velocity = c_displacement / drag.
constexpr double kDragS = 0.05;
Calibration base_cal() {
  Calibration c;
  c.c_velocity = c.c_displacement / kDragS;
  return c;
}
Calibration auto_cal() {
  Calibration c = base_cal();
  c.velocity_proxy = VelocityProxy::kAuto;
  return c;
}

TEST(SlipDetector, ValidateAcceptsAutoAndRejectsBadThresholds) {
  Calibration c = auto_cal();
  EXPECT_EQ(validate(c), Status::kOk);
  c.slip_relax_rate_on = 0.0;
  EXPECT_EQ(validate(c), Status::kBadCalibration);
  c = auto_cal();
  c.slip_on_frames = 0;
  EXPECT_EQ(validate(c), Status::kBadCalibration);
  c = auto_cal();
  c.slip_exit_fraction = 1.5;
  EXPECT_EQ(validate(c), Status::kBadCalibration);
  c = auto_cal();
  c.stick_rest_speed_m_s = std::nan("");
  EXPECT_EQ(validate(c), Status::kBadCalibration);
  c = auto_cal();
  c.slip_catchup_frames = 0;
  EXPECT_EQ(validate(c), Status::kBadCalibration);
  c = auto_cal();
  c.slip_smoothing_s = -0.01;
  EXPECT_EQ(validate(c), Status::kBadCalibration);
  c = auto_cal();
  c.velocity_proxy = static_cast<VelocityProxy>(3);
  EXPECT_EQ(validate(c), Status::kBadCalibration);
}

TEST(SlipDetector, PlanarContentOfARigidShearIsItsRotationAndShift) {
  const Disc disc;
  const Calibration cal;
  VectorField sh;
  std::vector<double> sx, sy;
  const double theta = 2.0 * kDeg, tx = 40e-6;
  disc.shear(theta, tx, cal.c_displacement, sh, sx, sy);
  ContactMoments m;
  double inertia = 0.0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    if (disc.cs->mask.v[i] == 0) continue;
    const std::int64_t x = disc.cs->x_nm.v[i], y = disc.cs->y_nm.v[i];
    ++m.n;
    m.sx += x;
    m.sy += y;
    m.sxx += x * x;
    m.syy += y * y;
    m.svx += sh.x.v[i];
    m.svy += sh.y.v[i];
    m.sx_vy += x * sh.y.v[i];
    m.sy_vx += y * sh.x.v[i];
    inertia += (x * 1e-9) * (x * 1e-9) + (y * 1e-9) * (y * 1e-9);
  }
  const Eigen::Vector3d X = planar_content(m, cal.c_displacement / 65536.0);
  const double lever = std::sqrt(inertia / static_cast<double>(m.n));
  // Q16 rounding of the shear: 1/65536 shear unit = 2.3 nm.
  EXPECT_NEAR(X(0), lever * theta, 1e-8);
  EXPECT_NEAR(X(1), tx, 1e-8);
  EXPECT_NEAR(X(2), 0.0, 1e-8);
  EXPECT_EQ(planar_content(ContactMoments{}, 1.0), Eigen::Vector3d::Zero());
}

// One sensor's twist [ω; t] as chosen, and as the velocity proxy read it.
Vector6d chosen_twist(const SensorMotion& m) {
  Vector6d xi;
  xi << m.omega, m.translation;
  return xi;
}
Vector6d velocity_twist(const SensorMotion& m) {
  Vector6d xi;
  xi << m.velocity_omega, m.velocity_translation;
  return xi;
}
Vector6d chosen_twist(const dsp_ref::SensorMotionRef& m) {
  Vector6d xi;
  xi << m.omega, m.translation;
  return xi;
}
Vector6d velocity_twist(const dsp_ref::SensorMotionRef& m) {
  Vector6d xi;
  xi << m.velocity_omega, m.velocity_translation;
  return xi;
}
// One frame of the fixed payback for a single sensor, as dsp::DualPipeline feeds it.
Vector6d pay(SlipPayback& p, const SensorMotion& m) {
  SlipPayback::Frame f;
  f.chosen = chosen_twist(m);
  f.velocity = velocity_twist(m);
  f.differs = m.velocity_differs;
  f.contact = m.contact;
  f.onset = m.slip_onset;
  f.confirmed = m.contact && m.stick_confirmed;
  return p.update(f, kDt);
}
Vector6d pay(dsp_ref::SlipPaybackRef& p, const dsp_ref::SensorMotionRef& m) {
  return p.update(chosen_twist(m), velocity_twist(m), m.velocity_differs, m.contact, m.slip_onset,
                  m.contact && m.stick_confirmed, false, kDt);
}

// Runs one auto and one fixed-mode estimator (and the reference's auto) over a shear history;
// the auto ones through the slip payback. disc_at(k) (may be null) gives frame k's contact.
struct Trace {
  std::vector<Eigen::Vector3d> omega_auto, omega_fixed, omega_ref;
  std::vector<bool> slipping, slipping_ref;
  int onsets = 0;
};

Trace run(const std::vector<double>& theta, VelocityProxy fixed_mode,
          const Disc* (*disc_at)(std::size_t) = nullptr) {
  const Disc default_disc;
  const Calibration cal_auto = auto_cal();
  Calibration cal_fixed = base_cal();
  cal_fixed.velocity_proxy = fixed_mode;
  auto a = std::make_unique<MotionEstimator>();
  auto f = std::make_unique<MotionEstimator>();
  EXPECT_EQ(a->configure(cal_auto), Status::kOk);
  EXPECT_EQ(f->configure(cal_fixed), Status::kOk);
  dsp_ref::MotionRef ref(cal_auto);
  SlipPayback payback;
  payback.configure(cal_auto.slip_catchup_frames);
  dsp_ref::SlipPaybackRef payback_ref(cal_auto.slip_catchup_frames);
  Trace t;
  auto sh = std::make_unique<VectorField>();
  std::vector<double> sx, sy;
  for (std::size_t k = 0; k < theta.size(); ++k) {
    const Disc& disc = disc_at != nullptr ? *disc_at(k) : default_disc;
    const double th = theta[k];
    disc.shear(th, 0.0, cal_auto.c_displacement, *sh, sx, sy);
    SensorMotion ma, mf;
    EXPECT_EQ(a->update(*disc.cs, *sh, kDt, ma), Status::kOk);
    EXPECT_EQ(f->update(*disc.cs, *sh, kDt, mf), Status::kOk);
    const dsp_ref::SensorMotionRef mr = ref.update(disc.ref, sx, sy, kDt);
    t.omega_auto.push_back(pay(payback, ma).head<3>());
    t.omega_fixed.push_back(mf.omega);
    t.omega_ref.push_back(pay(payback_ref, mr).head<3>());
    t.slipping.push_back(ma.slipping);
    t.slipping_ref.push_back(mr.slipping);
    t.onsets += ma.slip_onset ? 1 : 0;
  }
  return t;
}

// First frame the auto estimator used the velocity proxy (size of the trace if none).
std::size_t first_slipping(const Trace& t) {
  for (std::size_t k = 0; k < t.slipping.size(); ++k) {
    if (t.slipping[k]) return k;
  }
  return t.slipping.size();
}

// The slide shear history: rest 24 frames, a 30° minimum-jerk rotation over 1 s read through the
// gel's drag (shear ∝ sliding speed, lag ignored), rest 60 frames.
std::vector<double> slide_theta() {
  std::vector<double> theta;
  for (int k = 0; k < 24; ++k) theta.push_back(0.0);
  for (int k = 0; k <= 120; ++k) theta.push_back(kDragS * 30.0 * kDeg * min_jerk_rate(k / 120.0));
  for (int k = 0; k < 60; ++k) theta.push_back(0.0);
  return theta;
}

double integrate_z(const std::vector<Eigen::Vector3d>& w) {
  double s = 0.0;
  for (const auto& v : w) s += v.z() * kDt;
  return s;
}

TEST(SlipDetector, StickRampAndHoldStaysStuckAndEqualsTheDisplacementProxy) {
  // A 4° stick rotation over 0.5 s, then a 1 s hold: the shear is the accumulated displacement.
  std::vector<double> theta;
  for (int k = 0; k < 24; ++k) theta.push_back(0.0);
  for (int k = 0; k <= 60; ++k) theta.push_back(4.0 * kDeg * min_jerk(k / 60.0));
  for (int k = 0; k < 120; ++k) theta.push_back(4.0 * kDeg);
  const Trace t = run(theta, VelocityProxy::kDisplacement);
  EXPECT_EQ(t.onsets, 0);
  for (std::size_t k = 0; k < theta.size(); ++k) {
    ASSERT_FALSE(t.slipping[k]) << "frame " << k;
    ASSERT_FALSE(t.slipping_ref[k]) << "frame " << k;
    // Same proxy, same moments: bit-identical.
    ASSERT_EQ(t.omega_auto[k], t.omega_fixed[k]) << "frame " << k;
  }
  EXPECT_NEAR(integrate_z(t.omega_auto), 4.0 * kDeg, 0.02 * kDeg);
  EXPECT_NEAR(integrate_z(t.omega_ref), 4.0 * kDeg, 0.02 * kDeg);
}

// A stuck contact whose Ω loses its rim for a while (on small or deeply pressed objects the rim
// cells flicker out of Ω, and during the grasp Ω can collapse for a few frames). The rigid
// content X over Ω then drops by a third although no cell's shear changed; read as a relaxation
// it would start a slip, whose payback adds the velocity proxy's reading of the held shear, many
// times the motion. The detector reads dX from the increments over Ω_t ∩ Ω_{t−1}.
TEST(SlipDetector, AStuckContactLosingItsRimStaysStuck) {
  std::vector<double> theta;
  for (int k = 0; k < 24; ++k) theta.push_back(0.0);
  for (int k = 0; k <= 60; ++k) theta.push_back(4.0 * kDeg * min_jerk(k / 60.0));
  for (int k = 0; k < 120; ++k) theta.push_back(4.0 * kDeg);
  const Trace t = run(theta, VelocityProxy::kDisplacement, [](std::size_t k) -> const Disc* {
    static const Disc wide(6.0), narrow(4.0);
    return k >= 24 + 60 + 20 && k < 24 + 60 + 40 ? &narrow : &wide;
  });
  EXPECT_EQ(t.onsets, 0);
  for (std::size_t k = 0; k < theta.size(); ++k) {
    ASSERT_FALSE(t.slipping[k]) << "frame " << k;
    ASSERT_FALSE(t.slipping_ref[k]) << "frame " << k;
  }
  EXPECT_NEAR(integrate_z(t.omega_auto), 4.0 * kDeg, 0.02 * kDeg);
  EXPECT_NEAR(integrate_z(t.omega_ref), 4.0 * kDeg, 0.02 * kDeg);
}

// When a contact at rest counts as stuck, which drops the velocity proxy's pending reading. An
// unloaded contact (|X| ≤ slip_min_shift_m, no tangential load to speak of; sliding, if at all,
// slower than any slide the detector could call) is stuck after slip_on_frames frames at rest. A
// loaded one at rest may be sliding steadily at the friction limit, so it needs stick_confirm_s.
// The reference decides on the same frames.
TEST(SlipDetector, AnUnloadedContactAtRestIsConfirmedStuckAfterOnsetFrames) {
  const Calibration cal = auto_cal();
  ASSERT_GT(cal.slip_on_frames, 1);
  const Disc disc;
  for (const double shift_m : {0.0, 0.5 * cal.slip_min_shift_m, 3.0 * cal.slip_min_shift_m}) {
    auto est = std::make_unique<MotionEstimator>();
    ASSERT_EQ(est->configure(cal), Status::kOk);
    dsp_ref::MotionRef ref(cal);
    auto sh = std::make_unique<VectorField>();
    std::vector<double> sx, sy;
    disc.shear(0.0, shift_m, cal.c_displacement, *sh, sx, sy);
    int first = -1, first_ref = -1;
    const int frames = static_cast<int>(std::lround(1.5 * cal.stick_confirm_s / kDt));
    for (int k = 0; k < frames; ++k) {
      SensorMotion m;
      ASSERT_EQ(est->update(*disc.cs, *sh, kDt, m), Status::kOk);
      const dsp_ref::SensorMotionRef mr = ref.update(disc.ref, sx, sy, kDt);
      ASSERT_FALSE(m.slipping);
      if (first < 0 && m.stick_confirmed) first = k;
      if (first_ref < 0 && mr.stick_confirmed) first_ref = k;
    }
    // The first frame has no previous shear, so its change reads zero: at rest from frame 0.
    if (shift_m <= cal.slip_min_shift_m) {
      EXPECT_EQ(first, cal.slip_on_frames - 1) << "shift " << shift_m;
    } else {
      // Σ Δt reaches stick_confirm_s on frame 119 or, by the sum's rounding, the next one.
      const int at = static_cast<int>(std::lround(cal.stick_confirm_s / kDt)) - 1;
      EXPECT_GE(first, at) << "shift " << shift_m;
      EXPECT_LE(first, at + 1) << "shift " << shift_m;
    }
    EXPECT_EQ(first_ref, first) << "shift " << shift_m;
  }
}

TEST(SlipDetector, SlideIsDetectedWhenTheShearRelaxesAndThePoseCatchesUp) {
  // A slide: the shear follows the sliding speed (gel lag ignored), rising and falling with a
  // minimum-jerk speed profile of a 30° rotation over 1 s, then 0.5 s at rest. The velocity
  // proxy with c_velocity = c_displacement / drag reads it exactly.
  const Calibration cal = auto_cal();
  const std::vector<double> theta = slide_theta();
  const Trace t = run(theta, VelocityProxy::kVelocity);
  EXPECT_EQ(t.onsets, 1);
  // Detected in the second half of the slide (the shear relaxes as the slide slows) ...
  const std::size_t first = first_slipping(t);
  EXPECT_GT(first, 24u + 60u);
  EXPECT_LT(first, 24u + 120u);
  // ... and back to stick once the shear has relaxed at rest.
  EXPECT_FALSE(t.slipping.back());
  // The payback makes the integrated rotation the velocity proxy's (30°), not the displacement
  // proxy's (0°), without a pose jump: no frame turns faster than the slide's peak rate plus
  // the payback spread over slip_catchup_frames.
  const double v_total = integrate_z(t.omega_fixed);
  EXPECT_NEAR(v_total, 30.0 * kDeg, 0.3 * kDeg);
  EXPECT_NEAR(integrate_z(t.omega_auto), v_total, 0.01 * v_total);
  EXPECT_NEAR(integrate_z(t.omega_ref), v_total, 0.01 * v_total);
  double peak_fixed = 0.0, peak_auto = 0.0;
  for (std::size_t k = 0; k < theta.size(); ++k) {
    peak_fixed = std::max(peak_fixed, std::abs(t.omega_fixed[k].z()));
    peak_auto = std::max(peak_auto, std::abs(t.omega_auto[k].z()));
  }
  const double payback_rate = v_total / (cal.slip_catchup_frames * kDt);
  EXPECT_LT(peak_auto, peak_fixed + payback_rate);
  // Fixed point and the double reference take the same decisions and agree per frame.
  for (std::size_t k = 0; k < theta.size(); ++k) {
    ASSERT_EQ(t.slipping[k], t.slipping_ref[k]) << "frame " << k;
    ASSERT_NEAR(t.omega_auto[k].z(), t.omega_ref[k].z(), 1e-3 + 1e-3 * std::abs(t.omega_ref[k].z()))
        << "frame " << k;
  }
}

// The deficit is kept in the fused twist, not per grid cell: when Ω shrinks while a slide is
// still read as a stick (on the simulator's fast slides the mask collapses towards the patch
// centre), the payback still equals what the velocity proxy read, frame by frame.
TEST(SlipDetector, PaybackMatchesTheVelocityProxyWhenTheContactShrinksMidSlide) {
  const std::vector<double> theta = slide_theta();
  const Trace t = run(theta, VelocityProxy::kVelocity, [](std::size_t k) -> const Disc* {
    static const Disc wide(6.0), narrow(3.0);
    return k >= 24 + 10 && k < 24 + 50 ? &narrow : &wide;
  });
  EXPECT_EQ(t.onsets, 1);
  const std::size_t first = first_slipping(t);
  EXPECT_GT(first, 24u + 50u);  // the whole narrow phase was read as a stick
  const double v_total = integrate_z(t.omega_fixed);
  EXPECT_NEAR(v_total, 30.0 * kDeg, 0.3 * kDeg);
  EXPECT_NEAR(integrate_z(t.omega_auto), v_total, 0.01 * v_total);
  EXPECT_NEAR(integrate_z(t.omega_ref), v_total, 0.01 * v_total);
}

TEST(SlipDetector, ContactLossRestartsSticking) {
  const Disc disc;
  auto me = std::make_unique<MotionEstimator>();
  ASSERT_EQ(me->configure(auto_cal()), Status::kOk);
  auto sh = std::make_unique<VectorField>();
  std::vector<double> sx, sy;
  bool slipped = false;
  for (int k = 0; k <= 120; ++k) {
    disc.shear(kDragS * 30.0 * kDeg * min_jerk_rate(k / 120.0), 0.0, auto_cal().c_displacement, *sh,
               sx, sy);
    SensorMotion m;
    ASSERT_EQ(me->update(*disc.cs, *sh, kDt, m), Status::kOk);
    slipped = slipped || m.slipping;
  }
  EXPECT_TRUE(slipped);
  auto empty = std::make_unique<ContactSet>();
  SensorMotion m;
  ASSERT_EQ(me->update(*empty, *sh, kDt, m), Status::kOk);
  EXPECT_FALSE(m.contact);
  ASSERT_EQ(me->update(*disc.cs, *sh, kDt, m), Status::kOk);
  EXPECT_FALSE(m.slipping);
}

// A stuck contact let go. A 2° stick rotation is held for 0.3 s, then the pads open over 0.3 s
// (minimum jerk): the depth d falls to 0, the patch radius with √d (a sphere), and the gel under
// what is left springs back with the load, shear ∝ d. The object does not move. The shear's
// rigid content then relaxes (ρ ≈ 1.5 ρ_d) while the load Σ z ∝ d² falls faster (ρ_L = 2 ρ_d):
//  - no slip onset (only relaxation beyond the load's fall counts), so the velocity proxy's
//    reading of the held shear (the deficit, ≈ 12° here) is never paid;
//  - the frames whose load falls faster than release_load_rate drop the displacement proxy's
//    reading of the spring-back, so the pose stays near 2° (kDisplacement with the rule off
//    reads most of the way back to 0°; kAuto with it off also calls a slip and overshoots);
//  - the same in kDisplacement, never in kVelocity (no chosen reading of increments);
//  - the reference decides every frame the same and integrates the same rotation.
TEST(SlipDetector, AReleasedStuckContactIsNeitherASlipNorAMotionBack) {
  constexpr int kRest = 12, kRamp = 36, kHold = 36, kRelease = 36, kAfter = 12;
  const double theta_end = 2.0 * kDeg;
  std::vector<std::unique_ptr<Disc>> discs;
  std::vector<double> theta;
  for (int k = 0; k < kRest + kRamp + kHold; ++k) {
    discs.push_back(std::make_unique<Disc>());
    theta.push_back(k < kRest ? 0.0 : theta_end * min_jerk((k - kRest) / double(kRamp)));
  }
  double min_rate_while_releasing = 1e9;
  for (int k = 1; k <= kRelease + kAfter; ++k) {
    const double depth = 1.0 - min_jerk(k / double(kRelease));  // relative to 0.5 mm
    discs.push_back(std::make_unique<Disc>(6.0 * std::sqrt(depth), 0.5e-3 * depth));
    theta.push_back(theta_end * depth);
  }
  ASSERT_FALSE(discs.back()->cs->contact);
  struct Run {
    double rotation = 0.0, rotation_ref = 0.0;
    int onsets = 0, releasing = 0, mismatches = 0;
  };
  auto replay = [&](VelocityProxy mode, double release_load_rate) {
    Calibration cal = auto_cal();
    cal.velocity_proxy = mode;
    cal.release_load_rate = release_load_rate;
    auto est = std::make_unique<MotionEstimator>();
    EXPECT_EQ(est->configure(cal), Status::kOk);
    dsp_ref::MotionRef ref(cal);
    SlipPayback payback;
    payback.configure(cal.slip_catchup_frames);
    dsp_ref::SlipPaybackRef payback_ref(cal.slip_catchup_frames);
    auto sh = std::make_unique<VectorField>();
    std::vector<double> sx, sy;
    Run r;
    for (std::size_t k = 0; k < theta.size(); ++k) {
      discs[k]->shear(theta[k], 0.0, cal.c_displacement, *sh, sx, sy);
      SensorMotion m;
      EXPECT_EQ(est->update(*discs[k]->cs, *sh, kDt, m), Status::kOk);
      const dsp_ref::SensorMotionRef mr = ref.update(discs[k]->ref, sx, sy, kDt);
      r.rotation += pay(payback, m).z() * kDt;
      r.rotation_ref += pay(payback_ref, mr).z() * kDt;
      r.onsets += m.slip_onset ? 1 : 0;
      r.onsets += mr.slip_onset ? 1 : 0;
      r.releasing += m.releasing ? 1 : 0;
      if (m.releasing) {
        min_rate_while_releasing = std::min(min_rate_while_releasing, m.load_drop_rate);
        EXPECT_FALSE(m.proxy_valid) << "frame " << k;
        EXPECT_FALSE(m.translation_valid) << "frame " << k;
      }
      r.mismatches += (m.releasing != mr.releasing || m.slipping != mr.slipping) ? 1 : 0;
    }
    return r;
  };
  const double rate = Calibration{}.release_load_rate;
  const Run on = replay(VelocityProxy::kAuto, rate);
  const Run off = replay(VelocityProxy::kAuto, kReleaseRuleOff);
  const Run disp = replay(VelocityProxy::kDisplacement, rate);
  const Run disp_off = replay(VelocityProxy::kDisplacement, kReleaseRuleOff);
  const Run vel = replay(VelocityProxy::kVelocity, rate);
  EXPECT_EQ(on.onsets, 0);
  EXPECT_GT(on.releasing, 10);
  EXPECT_GT(min_rate_while_releasing, rate);
  EXPECT_EQ(off.releasing, 0);
  EXPECT_EQ(vel.releasing, 0);
  EXPECT_EQ(on.mismatches + disp.mismatches + vel.mismatches + off.mismatches, 0);
  // With the rule the pose keeps most of the 2°. Without it the release is called a slip and
  // the payback adds the velocity proxy's reading of the held shear, and the displacement proxy
  // reads the spring-back most of the way back to 0°.
  EXPECT_GT(off.onsets, 0);
  EXPECT_NEAR(on.rotation, theta_end, 0.3 * kDeg);
  EXPECT_NEAR(on.rotation_ref, on.rotation, 0.01 * kDeg);
  EXPECT_NEAR(disp.rotation, on.rotation, 0.01 * kDeg);
  EXPECT_GT(std::abs(off.rotation - theta_end), 1.0 * kDeg);
  EXPECT_LT(disp_off.rotation, theta_end - 1.0 * kDeg);
}

// The onset's release gate on its own: a release whose shear relaxes faster than its load (here a
// held 4° whose shear falls with d⁵ against Σ z ∝ d², so ρ − ρ_L stays above slip_relax_rate_on
// for a dozen frames) starts no slip while ρ_L > release_load_rate. With the rate set just under
// the smoothing's ceiling (1/slip_smoothing_s), where the gate hardly acts, the same release is
// called a slip. The decision-locked reference follows `releasing` in kDisplacement too.
TEST(SlipDetector, NoSlipOnsetWhileTheLoadFallsFasterThanTheReleaseRate) {
  constexpr int kHold = 60, kRelease = 36;
  std::vector<std::unique_ptr<Disc>> discs;
  std::vector<double> theta;
  for (int k = 0; k < kHold; ++k) {
    discs.push_back(std::make_unique<Disc>());
    theta.push_back(4.0 * kDeg);
  }
  for (int k = 1; k <= kRelease; ++k) {
    const double depth = 1.0 - min_jerk(k / double(kRelease));
    discs.push_back(std::make_unique<Disc>(6.0 * std::sqrt(depth), 0.5e-3 * depth));
    theta.push_back(4.0 * kDeg * std::pow(depth, 5.0));
  }
  auto onsets = [&](double release_load_rate) {
    Calibration cal = auto_cal();
    cal.release_load_rate = release_load_rate;
    EXPECT_EQ(validate(cal), Status::kOk);
    auto est = std::make_unique<MotionEstimator>();
    EXPECT_EQ(est->configure(cal), Status::kOk);
    dsp_ref::MotionRef ref(cal);
    auto sh = std::make_unique<VectorField>();
    std::vector<double> sx, sy;
    int n = 0, n_ref = 0;
    for (std::size_t k = 0; k < theta.size(); ++k) {
      discs[k]->shear(theta[k], 0.0, cal.c_displacement, *sh, sx, sy);
      SensorMotion m;
      EXPECT_EQ(est->update(*discs[k]->cs, *sh, kDt, m), Status::kOk);
      n += m.slip_onset ? 1 : 0;
      n_ref += ref.update(discs[k]->ref, sx, sy, kDt).slip_onset ? 1 : 0;
    }
    EXPECT_EQ(n, n_ref) << "rate " << release_load_rate;
    return n;
  };
  EXPECT_EQ(onsets(Calibration{}.release_load_rate), 0);
  EXPECT_GT(onsets(0.99 / auto_cal().slip_smoothing_s), 0);

  // A followed `releasing` decision applies in kDisplacement as in kAuto.
  Calibration cal = base_cal();
  cal.velocity_proxy = VelocityProxy::kDisplacement;
  dsp_ref::MotionRef ref(cal);
  const Disc disc;
  VectorField sh;
  std::vector<double> sx, sy;
  disc.shear(2.0 * kDeg, 0.0, cal.c_displacement, sh, sx, sy);
  (void)ref.update(disc.ref, sx, sy, kDt);
  const dsp_ref::SlipDecision follow{false, false, false, true};
  const dsp_ref::SensorMotionRef mr = ref.update(disc.ref, sx, sy, kDt, &follow);
  EXPECT_TRUE(mr.releasing);
  EXPECT_FALSE(mr.proxy_valid);
  EXPECT_FALSE(mr.translation_valid);
  EXPECT_EQ(mr.omega, Eigen::Vector3d::Zero());
}

// The displacement proxy's patch anchor is set again where a slide ended (docs/dsp/motion.md):
// the patch is where the slide left it, and the friction-held shear left in the gel is no
// reason to keep the patch of before the slide. Here the grasp is a small disc (anchored, no
// load), which grows into a large one once a 10 mm slide loads it (the anchor stays on the
// small one), and the slide ends with a held shift of 100 µm, 5 times slip_min_shift_m. After
// the slide the increments are read over the large disc. The double reference decides the same,
// and the decision-locked reference follows the anchor it is given, also when that differs.
TEST(SlipDetector, ASlideEndsWithThePatchItLeftAnchored) {
  const Calibration cal = auto_cal();
  const Disc small(3.0), large(6.0);
  constexpr int kRest = 12, kSlide = 120, kAfter = 48;
  const double held_m = 100e-6;
  struct Frame {
    const Disc* disc;
    double tx;
  };
  std::vector<Frame> frames;
  for (int k = 0; k < kRest; ++k) frames.push_back({&small, 0.0});
  bool loaded = false;
  for (int k = 0; k <= kSlide; ++k) {
    const double s = static_cast<double>(k) / kSlide;
    // Shear ∝ sliding speed (drag) plus the held shift building up over the slide.
    const double tx = kDragS * 10e-3 * min_jerk_rate(s) + held_m * min_jerk(s);
    loaded = loaded || tx > 2.0 * cal.slip_min_shift_m;
    frames.push_back({loaded ? &large : &small, tx});
  }
  for (int k = 0; k < kAfter; ++k) frames.push_back({&large, held_m});

  auto me = std::make_unique<MotionEstimator>();
  ASSERT_EQ(me->configure(cal), Status::kOk);
  dsp_ref::MotionRef free_ref(cal), locked(cal), other(cal);
  auto sh = std::make_unique<VectorField>();
  std::vector<double> sx, sy;
  std::vector<SensorMotion> fixed;
  std::vector<dsp_ref::SlipDecision> decisions;
  int onsets = 0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    frames[k].disc->shear(0.0, frames[k].tx, cal.c_displacement, *sh, sx, sy);
    SensorMotion m;
    ASSERT_EQ(me->update(*frames[k].disc->cs, *sh, kDt, m), Status::kOk);
    onsets += m.slip_onset ? 1 : 0;
    const dsp_ref::SensorMotionRef r = free_ref.update(frames[k].disc->ref, sx, sy, kDt);
    ASSERT_EQ(r.slipping, m.slipping) << "frame " << k;
    ASSERT_EQ(r.anchor_set, m.anchor_set) << "frame " << k;
    // While slipping the velocity proxy reads the drag over Ω ∩ anchor (the small disc), as
    // long as Ω holds it (docs/dsp/motion.md, drag region).
    ASSERT_EQ(r.velocity_anchored, m.velocity_anchored) << "frame " << k;
    ASSERT_EQ(static_cast<int>(r.samples.size()), m.moments.n) << "frame " << k;
    if (m.slipping) {
      EXPECT_TRUE(m.velocity_anchored) << "frame " << k;
      ASSERT_EQ(m.moments.n, small.cs->count) << "frame " << k;
    }
    fixed.push_back(m);
    decisions.push_back({m.slipping, m.stick_confirmed, m.slip_onset, m.releasing, true,
                         m.anchor_set, m.velocity_anchored});
  }
  ASSERT_EQ(onsets, 1);
  // The one anchor set on the large disc is at the slide's last frame.
  std::size_t first_large = 0, slide_end = 0;
  while (frames[first_large].disc != &large) ++first_large;
  int sets_on_large = 0;
  for (std::size_t k = first_large; k < frames.size(); ++k) {
    if (!fixed[k].anchor_set) continue;
    ++sets_on_large;
    slide_end = k;
  }
  ASSERT_EQ(sets_on_large, 1);
  ASSERT_LT(slide_end + 1, frames.size());
  EXPECT_TRUE(fixed[slide_end].slipping);
  EXPECT_FALSE(fixed[slide_end + 1].slipping);
  EXPECT_GT(fixed[slide_end].shear_shift_m, 2.0 * cal.slip_min_shift_m);
  // Before it, sticking on the large disc read the small one; after it, the large one.
  for (std::size_t k = first_large + 1; k < frames.size(); ++k) {
    if (fixed[k].slipping) continue;
    EXPECT_EQ(fixed[k].moments.n, k > slide_end ? large.cs->count : small.cs->count)
        << "frame " << k;
  }

  // Locked: the given anchors (the fixed path's), and then the same without the one at the
  // slide's end, which leaves the small disc anchored.
  std::vector<dsp_ref::SlipDecision> without = decisions;
  without[slide_end].anchor_set = false;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    frames[k].disc->shear(0.0, frames[k].tx, cal.c_displacement, *sh, sx, sy);
    const dsp_ref::SensorMotionRef l =
        locked.update(frames[k].disc->ref, sx, sy, kDt, &decisions[k]);
    const dsp_ref::SensorMotionRef o = other.update(frames[k].disc->ref, sx, sy, kDt, &without[k]);
    EXPECT_EQ(l.anchor_set, decisions[k].anchor_set) << "frame " << k;
    EXPECT_EQ(o.anchor_set, without[k].anchor_set) << "frame " << k;
    if (k > slide_end) {
      EXPECT_EQ(static_cast<int>(l.samples.size()), large.cs->count) << "frame " << k;
      EXPECT_EQ(static_cast<int>(o.samples.size()), small.cs->count) << "frame " << k;
    }
  }

  // A gap in the stream that swallows the slide's end (MotionEstimator::restart(), as the
  // pipeline calls it, at the frame the slide ended): the restarted detector never sees the end,
  // so restart() drops the pre-slide anchor while sliding and the frame after the gap anchors its
  // own Ω. The held stick after it reads the large disc, not the small one.
  const std::size_t gap = slide_end;
  auto gapped = std::make_unique<MotionEstimator>();
  ASSERT_EQ(gapped->configure(cal), Status::kOk);
  int read_large = 0, read_small = 0, sets_after_gap = 0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    if (k == gap) gapped->restart();
    frames[k].disc->shear(0.0, frames[k].tx, cal.c_displacement, *sh, sx, sy);
    SensorMotion m;
    ASSERT_EQ(gapped->update(*frames[k].disc->cs, *sh, kDt, m), Status::kOk);
    if (k == gap) {
      EXPECT_TRUE(m.anchor_set);
    } else if (k > gap) {
      sets_after_gap += m.anchor_set ? 1 : 0;
    }
    if (k > slide_end && !m.slipping) {
      read_large += m.moments.n == large.cs->count ? 1 : 0;
      read_small += m.moments.n == small.cs->count ? 1 : 0;
    }
  }
  std::printf(
      "after a gap at the slide's end: %d anchors set later, %d stick frames read the large disc, "
      "%d the small one\n",
      sets_after_gap, read_large, read_small);
  EXPECT_GT(read_large, 20);
  EXPECT_EQ(read_small, 0);
}

// The decision-locked reference (dsp_ref::SlipDecision, used only to report a second fixed−ref
// figure): following the fixed pipeline's decisions reproduces them frame by frame, also when
// the reference's own detector would decide differently (here: a delayed onset imposed on it).
TEST(SlipDetector, DecisionLockedReferenceFollowsTheGivenDecisions) {
  const Disc disc;
  const Calibration cal = auto_cal();
  const std::vector<double> theta = slide_theta();
  auto a = std::make_unique<MotionEstimator>();
  ASSERT_EQ(a->configure(cal), Status::kOk);
  dsp_ref::MotionRef free_ref(cal), locked(cal), delayed(cal);
  auto sh = std::make_unique<VectorField>();
  std::vector<double> sx, sy;
  std::vector<dsp_ref::SlipDecision> fixed_decisions;
  dsp_ref::SlipPaybackRef pay_free(cal.slip_catchup_frames), pay_locked(cal.slip_catchup_frames);
  int onset_frame = -1;
  for (std::size_t k = 0; k < theta.size(); ++k) {
    disc.shear(theta[k], 0.0, cal.c_displacement, *sh, sx, sy);
    SensorMotion ma;
    ASSERT_EQ(a->update(*disc.cs, *sh, kDt, ma), Status::kOk);
    const dsp_ref::SlipDecision d{ma.slipping, ma.stick_confirmed, ma.slip_onset};
    fixed_decisions.push_back(d);
    if (ma.slip_onset && onset_frame < 0) onset_frame = static_cast<int>(k);
    const dsp_ref::SensorMotionRef mf = free_ref.update(disc.ref, sx, sy, kDt);
    const dsp_ref::SensorMotionRef ml = locked.update(disc.ref, sx, sy, kDt, &d);
    // The free reference takes the same decisions here, so locking changes nothing.
    ASSERT_EQ(ml.slipping, ma.slipping) << "frame " << k;
    ASSERT_EQ(mf.slipping, ma.slipping) << "frame " << k;
    ASSERT_EQ(ml.slip_onset, ma.slip_onset) << "frame " << k;
    ASSERT_EQ(mf.slip_onset, ma.slip_onset) << "frame " << k;
    const double wf = pay(pay_free, mf).z(), wl = pay(pay_locked, ml).z();
    ASSERT_NEAR(wl, wf, 1e-12 + 1e-12 * std::abs(wf)) << "frame " << k;
  }
  ASSERT_GT(onset_frame, 0);
  // Impose an onset 5 frames late: the locked reference follows it (and the payback starts
  // from then on), so its integrated rotation still reaches the velocity proxy's.
  std::vector<dsp_ref::SlipDecision> late = fixed_decisions;
  late[static_cast<std::size_t>(onset_frame)].slip_onset = false;
  for (int k = onset_frame + 1; k <= onset_frame + 5; ++k) {
    late[static_cast<std::size_t>(k)].slipping = false;
  }
  late[static_cast<std::size_t>(onset_frame + 5)].slip_onset = true;
  dsp_ref::SlipPaybackRef pay_delayed(cal.slip_catchup_frames);
  double total = 0.0;
  for (std::size_t k = 0; k < theta.size(); ++k) {
    disc.shear(theta[k], 0.0, cal.c_displacement, *sh, sx, sy);
    const dsp_ref::SensorMotionRef m = delayed.update(disc.ref, sx, sy, kDt, &late[k]);
    ASSERT_EQ(m.slipping, late[k].slipping) << "frame " << k;
    ASSERT_EQ(m.slip_onset, late[k].slip_onset) << "frame " << k;
    total += pay(pay_delayed, m).z() * kDt;
  }
  EXPECT_NEAR(total, 30.0 * kDeg, 0.5 * kDeg);
}

}  // namespace
}  // namespace tacse3::dsp
