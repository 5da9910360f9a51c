// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: dual-sensor fusion, paper method and joint method: the Sec. V-B cases (mirrored
// sensors: a translation cancels in the rotation, rotations about x/y/z add up with the right
// signs), single-sensor operation, bad inputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "tacse3/dsp/contact.hpp"
#include "tacse3/dsp/fusion.hpp"
#include "tacse3/dsp/motion.hpp"
#include "tacse3/dsp_ref/motion_ref.hpp"

namespace tacse3::dsp {
namespace {

constexpr double kDt = 1.0 / 120.0;
constexpr double kW = 30e-3;  // finger separation

// One pad's detector + motion estimator fed with the two frames of a synthetic scene.
SensorMotion run_pad(const Calibration& cal, const dsp_ref::SyntheticSensorFrames& f) {
  auto det = std::make_unique<ContactDetector>();
  auto me = std::make_unique<MotionEstimator>();
  auto cs = std::make_unique<ContactSet>();
  EXPECT_EQ(det->configure(cal), Status::kOk);
  EXPECT_EQ(me->configure(cal), Status::kOk);
  SensorMotion out;
  det->detect(f.fz, f.w_prev, f.valid, *cs);
  EXPECT_EQ(me->update(*cs, f.shear_prev, kDt, out), Status::kOk);
  det->detect(f.fz, f.w_now, f.valid, *cs);
  EXPECT_EQ(me->update(*cs, f.shear_now, kDt, out), Status::kOk);
  return out;
}

// Both pads of the default mirrored board touching the same object, contact patches opposite
// each other at (cx, cy) in G; object twist (ω, t) in G.
struct Dual {
  SensorMotion left, right;
  std::vector<dsp_ref::PointSample> points_G;
};
Dual observe(const Eigen::Vector3d& omega, const Eigen::Vector3d& t, double cx = 0.0,
             double cy = 0.0, const Calibration& cal = {}, double W = kW) {
  Dual d;
  const SensorExtrinsics e[2] = {left_pad_extrinsics(), right_pad_extrinsics()};
  for (int i = 0; i < 2; ++i) {
    dsp_ref::RigidContactScene sc;
    sc.R_GS = e[i].R_GS;
    sc.p_GS = e[i].p_GS(W);
    sc.contact_centre_G = Eigen::Vector3d(cx, cy, sc.p_GS.z());
    sc.omega_G = omega;
    sc.t_G = t;
    const auto f =
        std::make_unique<dsp_ref::SyntheticSensorFrames>(dsp_ref::render_rigid_contact(cal, sc));
    (i == 0 ? d.left : d.right) = run_pad(cal, *f);
    d.points_G.insert(d.points_G.end(), f->points_G.begin(), f->points_G.end());
  }
  return d;
}

FusedMotion fuse_with(FusionMethod method, const SensorMotion* a, const SensorMotion* b,
                      double W = kW) {
  FusionConfig cfg;
  cfg.method = method;
  FusedMotion out;
  EXPECT_EQ(fuse(a, b, cfg, W, out), Status::kOk);
  EXPECT_TRUE(out.xi.allFinite());
  return out;
}

const Eigen::Vector3d kZero = Eigen::Vector3d::Zero();

TEST(FusionPaper, PureTranslationCancelsInTheRotation) {
  for (const Eigen::Vector3d& t : {Eigen::Vector3d(5e-3, 0.0, 0.0), Eigen::Vector3d(0.0, 5e-3, 0.0),
                                   Eigen::Vector3d(3e-3, -4e-3, 0.0)}) {
    const Dual d = observe(kZero, t);
    // Single sensor: the translation is read as a large rotation (the paper's ambiguity) ...
    ASSERT_GT(d.left.omega.head<2>().norm(), 1.0);
    ASSERT_GT(d.right.omega.head<2>().norm(), 1.0);
    const FusedMotion f = fuse_with(FusionMethod::kPaper, &d.left, &d.right);
    EXPECT_FALSE(f.single_sensor);
    EXPECT_EQ(f.rotation_sensors, kSensor1 | kSensor2);
    // ... the mirrored pair cancels it: ω1 = −S ω2 to the last bit of the fixed-point input.
    EXPECT_LT(f.xi.head<3>().norm(), 1e-4 * d.left.omega.norm()) << t.transpose();
    // ½(t1 + S t2) is the object translation in G.
    EXPECT_LT((f.xi.tail<3>() - t).norm(), 3e-7);
    EXPECT_TRUE(f.translation_valid);
  }
}

TEST(FusionPaper, OffCentreTranslationCancelsInOmegaXyOnly) {
  // Off-centre contact: a single pad also reads a uniform shear as some ω_z. The mirror images
  // of that leak have opposite ω_z, exactly like the images of a true z rotation, so S does not
  // cancel it: documented limitation of the paper method (the joint method removes it).
  const Eigen::Vector3d t(5e-3, 2e-3, 0.0);
  const Dual d = observe(kZero, t, 4e-3, 3e-3);
  const FusedMotion f = fuse_with(FusionMethod::kPaper, &d.left, &d.right);
  EXPECT_LT(f.xi.head<2>().norm(), 1e-4 * d.left.omega.norm());
  EXPECT_GT(std::abs(d.left.omega.z()), 0.01);
  EXPECT_NEAR(f.xi(2), d.left.omega.z(), 1e-4 * std::abs(d.left.omega.z()));
  const FusedMotion j = fuse_with(FusionMethod::kJoint, &d.left, &d.right);
  EXPECT_LT(j.xi.head<3>().norm(), 1e-4);
  EXPECT_LT((j.xi.tail<3>() - t).norm(), 3e-7);
}

TEST(FusionPaper, RotationsAboutXYZAddUpWithTheRightSigns) {
  const FusionConfig cfg;
  for (int axis = 0; axis < 3; ++axis) {
    for (double sgn : {1.0, -1.0}) {
      Eigen::Vector3d w = kZero;
      w(axis) = sgn * 0.5;  // rad/s about G's axis through G's origin
      const Dual d = observe(w, kZero);
      // Both sensors see the rotation with the same sign once S is applied ...
      const double w1 = d.left.omega(axis);
      const double w2s = cfg.sign[static_cast<std::size_t>(axis)] * d.right.omega(axis);
      EXPECT_GT(w1 * sgn, 0.0) << axis;
      EXPECT_GT(w2s * sgn, 0.0) << axis;
      EXPECT_NEAR(w1, w2s, 1e-4 * std::abs(w1)) << axis;
      const FusedMotion f = fuse_with(FusionMethod::kPaper, &d.left, &d.right);
      // ... so they add up: the fused value is their mean, with the true sign.
      EXPECT_NEAR(f.xi(axis), 0.5 * (w1 + w2s), 1e-12);
      EXPECT_GT(f.xi(axis) * sgn, 0.0);
      for (int other = 0; other < 3; ++other) {
        if (other != axis) {
          EXPECT_LT(std::abs(f.xi(other)), 1e-4 * std::abs(f.xi(axis)));
        }
      }
      if (axis == 2) {
        // About the normal the own-frame fit is exact: no lever arm involved.
        EXPECT_NEAR(f.xi(2), w(2), 1e-4);
      } else {
        // About x/y each pad sees a uniform shear ω·W/2 and reads it through its tiny z lever:
        // the paper's per-axis calibrated scales exist to bring this back to rad/s.
        EXPECT_GT(std::abs(f.xi(axis)), 10.0 * std::abs(w(axis)));
      }
    }
  }
}

TEST(FusionPaper, PerAxisScalesCalibrateTheLeverArm) {
  // Calibrate rotation_scale on one rotation, then check it on another amplitude: the paper
  // method is linear, so one scale per axis recovers rad/s for this contact geometry.
  const Eigen::Vector3d w_cal(0.5, 0.0, 0.0);
  const Dual d = observe(w_cal, kZero);
  const FusedMotion f = fuse_with(FusionMethod::kPaper, &d.left, &d.right);
  Calibration cal;
  cal.rotation_scale[0] = w_cal.x() / f.xi(0);
  const Dual d2 = observe(Eigen::Vector3d(-0.2, 0.0, 0.0), kZero, 0.0, 0.0, cal);
  const FusedMotion f2 = fuse_with(FusionMethod::kPaper, &d2.left, &d2.right);
  EXPECT_NEAR(f2.xi(0), -0.2, 1e-4);
}

TEST(FusionJoint, TranslationCancelsAndRotationsAreInPhysicalUnits) {
  for (const Eigen::Vector3d& t :
       {Eigen::Vector3d(5e-3, 0.0, 0.0), Eigen::Vector3d(0.0, -5e-3, 0.0)}) {
    const Dual d = observe(kZero, t, 2e-3, -1e-3);
    const FusedMotion f = fuse_with(FusionMethod::kJoint, &d.left, &d.right);
    EXPECT_LT(f.xi.head<3>().norm(), 1e-4);
    EXPECT_LT((f.xi.tail<3>() - t).norm(), 3e-7);
    EXPECT_TRUE(f.valid);
    EXPECT_EQ(f.rank, 3);
  }
  for (int axis = 0; axis < 3; ++axis) {
    for (double sgn : {1.0, -1.0}) {
      Eigen::Vector3d w = kZero;
      w(axis) = sgn * 0.5;
      const Dual d = observe(w, kZero, 1e-3, 2e-3);
      const FusedMotion f = fuse_with(FusionMethod::kJoint, &d.left, &d.right);
      // The lever arm W/2 is in the extrinsics: ω comes out in rad/s, no calibration scale.
      EXPECT_LT((f.xi.head<3>() - w).norm(), 2e-4 * w.norm()) << axis;
      // Rotation about G's origin: the translation referred to the origin is zero.
      EXPECT_LT(f.xi.tail<3>().norm(), 3e-7) << axis;
      EXPECT_TRUE(f.valid);
    }
  }
}

TEST(FusionJoint, MatchesBruteForceStackedSolveOverBothPads) {
  const Eigen::Vector3d w(0.3, -0.2, 0.4), t(2e-3, 1e-3, 0.0);
  const Dual d = observe(w, t, -3e-3, 2e-3);
  const FusedMotion f = fuse_with(FusionMethod::kJoint, &d.left, &d.right);
  // Brute force: stack the rows of every contact point in G about their centroid.
  const auto centred = dsp_ref::shifted(d.points_G, dsp_ref::centroid(d.points_G));
  const dsp_ref::StackedSystem sys = dsp_ref::stack_shear_rows(centred);
  const Eigen::Matrix3d AtA = sys.A.transpose() * sys.A;
  const FusionConfig cfg;
  const double lambda =
      cfg.solve_lambda_rel * AtA.trace() / 3.0 +
      static_cast<double>(d.points_G.size()) * cfg.solve_lever_floor_m * cfg.solve_lever_floor_m;
  const Eigen::Vector3d w_ref = dsp_ref::solve_stacked(sys, lambda);
  EXPECT_LT((f.xi.head<3>() - w_ref).norm(), 1e-4 * w_ref.norm());
  EXPECT_LT((f.xi.head<3>() - w).norm(), 2e-4 * w.norm());
  EXPECT_LT((f.xi.tail<3>() - t).norm(), 3e-7);
}

TEST(FusionJoint, FingerSeparationIsTheLeverArm) {
  const Eigen::Vector3d w(0.4, -0.3, 0.0);
  for (double W : {10e-3, 30e-3, 80e-3}) {
    const Dual d = observe(w, kZero, 0.0, 0.0, Calibration{}, W);
    const FusedMotion f = fuse_with(FusionMethod::kJoint, &d.left, &d.right, W);
    EXPECT_LT((f.xi.head<3>() - w).norm(), 2e-4 * w.norm()) << W;
    // The wrong separation scales ω_x, ω_y by the ratio of lever arms.
    const FusedMotion g = fuse_with(FusionMethod::kJoint, &d.left, &d.right, 2.0 * W);
    EXPECT_GT((g.xi.head<2>() - w.head<2>()).norm(), 0.3 * w.norm()) << W;
  }
}

TEST(Fusion, SingleSensorWorksForBothMethodsAndIsFlagged) {
  const Eigen::Vector3d w(0.0, 0.0, 0.5), t(3e-3, -1e-3, 0.0);
  const Dual d = observe(w, t);
  const SensorMotion none;  // a pad without contact
  for (FusionMethod m : {FusionMethod::kPaper, FusionMethod::kJoint}) {
    for (int which = 0; which < 4; ++which) {
      const SensorMotion* a = which < 2 ? &d.left : (which == 2 ? nullptr : &none);
      const SensorMotion* b = which < 2 ? (which == 0 ? nullptr : &none) : &d.right;
      const FusedMotion f = fuse_with(m, a, b);
      EXPECT_TRUE(f.single_sensor);
      const std::uint8_t expect = which < 2 ? kSensor1 : kSensor2;
      EXPECT_EQ(f.rotation_sensors, expect);
      EXPECT_EQ(f.translation_sensors, expect);
      EXPECT_EQ(f.contact[0], which < 2);
      EXPECT_EQ(f.contact[1], which >= 2);
      // Rotation about the normal and the in-plane translation are observable by one pad.
      EXPECT_NEAR(f.xi(2), 0.5, 1e-3) << static_cast<int>(m) << " " << which;
      // Joint: t is referred to G's origin, W/2 = 15 mm away, with the single pad's ω (only ω_z
      // about the pad normal, whose quantisation noise enters t through the contact's offset).
      // The paper method reports the centroid velocity itself.
      const double tol = m == FusionMethod::kJoint ? 3e-6 : 3e-7;
      EXPECT_LT((f.xi.tail<3>() - t).norm(), tol) << static_cast<int>(m) << " " << which;
    }
  }
  // Paper method with sensor 1 alone is sensor 1's own twist rotated by R_GS1 (= I).
  const FusedMotion p1 = fuse_with(FusionMethod::kPaper, &d.left, nullptr);
  EXPECT_EQ(Eigen::Vector3d(p1.xi.head<3>()), d.left.omega);
  EXPECT_EQ(Eigen::Vector3d(p1.xi.tail<3>()), d.left.translation);
}

// One pad alone: the joint fusion reads only the rotation about that pad's normal. A rotation
// about an in-plane axis shears one flat pad like a translation; the noise-free scene here would
// still let the 3x3 solve recover it from the indentation's heights, but on real frames those
// sub-millimetre levers turn shear noise into rad/s (docs/dsp/solve-fusion-se3.md), so the two
// in-plane components are reported as exactly 0, rank 1, and the translation stays referred
// correctly.
TEST(FusionJoint, OnePadReadsOnlyTheRotationAboutItsNormal) {
  const Eigen::Vector3d w(0.4, -0.3, 0.5), t(3e-3, -1e-3, 0.0);
  const Dual d = observe(w, t);
  const Dual in_plane = observe(Eigen::Vector3d(0.4, -0.3, 0.0), kZero);
  for (int which = 0; which < 2; ++which) {
    const SensorMotion* pad = which == 0 ? &d.left : &d.right;
    const FusedMotion f = which == 0 ? fuse_with(FusionMethod::kJoint, pad, nullptr)
                                     : fuse_with(FusionMethod::kJoint, nullptr, pad);
    EXPECT_TRUE(f.single_sensor);
    EXPECT_TRUE(f.rotation_valid);
    EXPECT_EQ(f.rank, 1);
    EXPECT_EQ(f.xi(0), 0.0) << which;
    EXPECT_EQ(f.xi(1), 0.0) << which;
    EXPECT_NEAR(f.xi(2), 0.5, 1e-3) << which;
    // t = v(c) − ω × c with that ω, c the pad's contact point: the in-plane rotation the pad
    // cannot tell from a translation is read as one, t + (ω_true − ω) × c, with t_z = 0.
    Eigen::Vector3d expect_t = t + (w - f.xi.head<3>()).cross(f.reference_point);
    expect_t.z() = 0.0;
    EXPECT_LT((f.xi.tail<3>() - expect_t).norm(), 3e-6) << which;
    // Both pads: all three components.
    const FusedMotion both = fuse_with(FusionMethod::kJoint, &d.left, &d.right);
    EXPECT_LT((both.xi.head<3>() - w).norm(), 2e-4 * w.norm());
    // An in-plane rotation alone: nothing about the normal, nothing read in the plane.
    const SensorMotion* ip = which == 0 ? &in_plane.left : &in_plane.right;
    const FusedMotion g = which == 0 ? fuse_with(FusionMethod::kJoint, ip, nullptr)
                                     : fuse_with(FusionMethod::kJoint, nullptr, ip);
    EXPECT_EQ(g.xi(0), 0.0);
    EXPECT_EQ(g.xi(1), 0.0);
    EXPECT_LT(std::abs(g.xi(2)), 1e-3);
  }
}

TEST(Fusion, NoContactGivesZeroInvalid) {
  const SensorMotion none;
  for (FusionMethod m : {FusionMethod::kPaper, FusionMethod::kJoint}) {
    for (const SensorMotion* a : {static_cast<const SensorMotion*>(nullptr), &none}) {
      const FusedMotion f = fuse_with(m, a, a);
      EXPECT_EQ(f.xi, Vector6d::Zero());
      EXPECT_FALSE(f.valid);
      EXPECT_FALSE(f.rotation_valid);
      EXPECT_FALSE(f.translation_valid);
      EXPECT_FALSE(f.single_sensor);
      EXPECT_EQ(f.rotation_sensors | f.translation_sensors, 0);
      EXPECT_EQ(f.rcond, 0.0);
      EXPECT_EQ(f.quality.pads, 0);
    }
  }
}

TEST(Fusion, BadSeparationOrConfigIsRejected) {
  const Dual d = observe(Eigen::Vector3d(0.1, 0.0, 0.0), kZero);
  FusionConfig cfg;
  FusedMotion out;
  for (double W : {std::numeric_limits<double>::quiet_NaN(), -1e-3, 1.0,
                   std::numeric_limits<double>::infinity()}) {
    EXPECT_EQ(fuse(&d.left, &d.right, cfg, W, out), Status::kBadArgument);
    EXPECT_EQ(out.status, Status::kBadArgument);
    EXPECT_EQ(out.xi, Vector6d::Zero());
    EXPECT_FALSE(out.valid);
  }
  FusionConfig bad = cfg;
  bad.sign[2] = 0.5;
  EXPECT_EQ(validate(bad), Status::kBadArgument);
  EXPECT_EQ(fuse(&d.left, &d.right, bad, kW, out), Status::kBadArgument);
  bad = cfg;
  bad.extrinsics[1].R_GS(0, 0) = 2.0;  // not a rotation
  EXPECT_EQ(validate(bad), Status::kBadArgument);
  bad = cfg;
  bad.extrinsics[0].R_GS = Eigen::Vector3d(1.0, 1.0, -1.0).asDiagonal();  // reflection
  EXPECT_EQ(validate(bad), Status::kBadArgument);
  bad = cfg;
  bad.solve_lambda_rel = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(validate(bad), Status::kBadArgument);
  bad = cfg;
  bad.method = static_cast<FusionMethod>(9);
  EXPECT_EQ(validate(bad), Status::kBadArgument);
  EXPECT_EQ(validate(cfg), Status::kOk);
  // NaN smuggled into a sensor result never reaches the output.
  SensorMotion poisoned = d.left;
  poisoned.omega.x() = std::numeric_limits<double>::quiet_NaN();
  cfg.method = FusionMethod::kPaper;
  ASSERT_EQ(fuse(&poisoned, &d.right, cfg, kW, out), Status::kOk);
  EXPECT_TRUE(out.xi.allFinite());
  EXPECT_FALSE(out.valid);
}

// rms in-plane lever of the points about their own pad's centroid (pads told apart by z).
double rms_lever(const std::vector<dsp_ref::PointSample>& pts) {
  double inertia = 0.0;
  for (const double side : {1.0, -1.0}) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    int n = 0;
    for (const auto& p : pts) {
      if (p.q.z() * side > 0.0) {
        c += p.q;
        ++n;
      }
    }
    c /= n;
    for (const auto& p : pts) {
      if (p.q.z() * side > 0.0) inertia += (p.q - c).head<2>().squaredNorm();
    }
  }
  return std::sqrt(inertia / static_cast<double>(pts.size()));
}

TEST(FitQuality, RigidMotionFitsWithoutResidualOrDisagreement) {
  const Eigen::Vector3d omega(0.0, 0.0, 0.5);
  const Dual d = observe(omega, Eigen::Vector3d(2e-3, -1e-3, 0.0));
  const FitQuality q = fit_quality(&d.left, &d.right, FusionConfig{}, kW);
  EXPECT_EQ(q.pads, 2);
  EXPECT_EQ(q.rank, 3);
  EXPECT_EQ(q.min_points, std::min(d.left.points, d.right.points));
  // Flat parallel patches opposite each other: the conditioning is the expected one.
  EXPECT_NEAR(q.rcond / q.rcond_expected, 1.0, 0.05);
  // Speeds of a few mm/s read to the Q16 proxy's rounding.
  const double speed = omega.norm() * rms_lever(d.points_G);
  EXPECT_LT(q.residual_speed_m_s, 1e-3 * speed);
  EXPECT_LT(std::abs(q.disagreement_m_s), 1e-3 * speed);
}

TEST(FitQuality, APadReadingTwiceTheTorsionDisagreesByItsSpeed) {
  const Eigen::Vector3d omega(0.0, 0.0, 0.5);
  Dual d = observe(omega, kZero);
  d.right.rotation_scale.z() = 2.0;  // the right pad's own ω_n doubles; the left's stays
  const FitQuality q = fit_quality(&d.left, &d.right, FusionConfig{}, kW);
  // (ω_1 − ω_2)·n_1 · L = (0.5 − 1.0) · L.
  EXPECT_NEAR(q.disagreement_m_s / (-0.5 * rms_lever(d.points_G)), 1.0, 0.02);
}

TEST(FitQuality, ANonRigidProxyLeavesItsResidual) {
  // One pad, the proxy doubled on every point of a rigid torsion: ṽ = 2ω × r fits ω' = 2ω with
  // no residual; adding a uniform field also fits (the translation); an alternating field does
  // not. Built on the moments directly: Σ|ṽ|² grows by Σ|δ|² with δ ⟂ every rigid field.
  const Dual d = observe(Eigen::Vector3d(0.0, 0.0, 0.5), kZero);
  SensorMotion m = d.left;
  const FitQuality rigid = fit_quality(&m, nullptr, FusionConfig{}, kW);
  EXPECT_EQ(rigid.rank, 1);
  EXPECT_EQ(rigid.pads, 1);
  EXPECT_EQ(rigid.rcond, 1.0);
  // δ of size s on every point, orthogonal to the rigid fields: Σ|δ|² = N s² raises the
  // residual per equation by N s² / (2N − 3), so σ̂²/N by s² / (2N − 3).
  const double s_q16 = 1000.0;
  m.moments.svv += static_cast<std::int64_t>(m.moments.n * s_q16 * s_q16);
  const FitQuality noisy = fit_quality(&m, nullptr, FusionConfig{}, kW);
  const double n = static_cast<double>(m.moments.n);
  const double s = s_q16 * m.proxy_scale;
  const double expected =
      std::sqrt(rigid.residual_speed_m_s * rigid.residual_speed_m_s + s * s / (2.0 * n - 3.0));
  EXPECT_NEAR(noisy.residual_speed_m_s / expected, 1.0, 1e-6);
}

TEST(FitQuality, NoPadIsEmpty) {
  const FitQuality q = fit_quality(nullptr, nullptr, FusionConfig{}, kW);
  EXPECT_EQ(q.pads, 0);
  EXPECT_EQ(q.rank, 0);
  EXPECT_EQ(q.residual_speed_m_s, 0.0);
}

}  // namespace
}  // namespace tacse3::dsp
