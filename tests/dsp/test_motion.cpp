// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: per-sensor motion: moments vs brute-force stacked least squares, centroid
// translation vs analytic motion, onset/loss/area-change rules, proxy modes, degenerate contacts.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>

#include "tacse3/dsp/contact.hpp"
#include "tacse3/dsp/fixed.hpp"
#include "tacse3/dsp/motion.hpp"
#include "tacse3/dsp_ref/motion_ref.hpp"

namespace tacse3::dsp {
namespace {

using dsp_ref::RigidContactScene;
using dsp_ref::SyntheticSensorFrames;
constexpr double kDt = 1.0 / 120.0;

// Runs frame t−1 and frame t of a synthetic scene through ContactDetector + MotionEstimator.
struct Runner {
  Calibration cal;
  std::unique_ptr<ContactDetector> det = std::make_unique<ContactDetector>();
  std::unique_ptr<MotionEstimator> me = std::make_unique<MotionEstimator>();
  std::unique_ptr<ContactSet> cs = std::make_unique<ContactSet>();
  explicit Runner(const Calibration& c) : cal(c) {
    EXPECT_EQ(det->configure(cal), Status::kOk);
    EXPECT_EQ(me->configure(cal), Status::kOk);
  }
  SensorMotion frame(const ScalarField& fz, const VectorField& w, const VectorField& shear,
                     double dt = kDt) {
    GridMask valid;
    valid.fill(1);
    det->detect(fz, w, valid, *cs);
    SensorMotion out;
    EXPECT_EQ(me->update(*cs, shear, dt, out), Status::kOk);
    return out;
  }
  SensorMotion pair(const SyntheticSensorFrames& f) {
    frame(f.fz, f.w_prev, f.shear_prev);
    return frame(f.fz, f.w_now, f.shear_now);
  }
};

// Σ z q / Σ z over contact points: the sliding rule's height-weighted centroid.
Eigen::Vector3d height_weighted_centroid(const std::vector<dsp_ref::PointSample>& points) {
  Eigen::Vector3d zq = Eigen::Vector3d::Zero();
  double zs = 0.0;
  for (const auto& p : points) {
    zq += p.q.z() * p.q;
    zs += p.q.z();
  }
  EXPECT_GT(zs, 0.0);
  return zq / zs;
}

void expect_finite(const SensorMotion& m) {
  EXPECT_TRUE(m.omega.allFinite());
  EXPECT_TRUE(m.translation.allFinite());
  EXPECT_TRUE(m.centroid_m.allFinite());
  EXPECT_TRUE(m.solve.x.allFinite());
}

TEST(Motion, MomentNormalEquationsMatchBruteForceStackedLeastSquares) {
  std::mt19937 rng(40);
  std::uniform_real_distribution<double> pos(-12e-3, 12e-3), z(0.0, 1e-3), v(-2.0, 2.0);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 8; ++trial) {
    // A random contact set, written directly (the detector is tested elsewhere).
    auto cs = std::make_unique<ContactSet>();
    auto shear = std::make_unique<VectorField>();
    std::vector<dsp_ref::PointSample> pts;
    const Calibration cal;
    for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
      if (std::uniform_int_distribution<int>(0, 3)(rng) != 0) continue;
      cs->mask.v[i] = 1;
      cs->x_nm.v[i] = static_cast<std::int32_t>(std::lround(pos(rng) * 1e9));
      cs->y_nm.v[i] = static_cast<std::int32_t>(std::lround(pos(rng) * 1e9));
      cs->z_nm.v[i] = static_cast<std::int32_t>(std::lround(z(rng) * 1e9));
      shear->x.v[i] = to_q32<16>(v(rng));
      shear->y.v[i] = to_q32<16>(v(rng));
      dsp_ref::PointSample s;
      s.q = Eigen::Vector3d(cs->x_nm.v[i], cs->y_nm.v[i], cs->z_nm.v[i]) * 1e-9;
      s.v = cal.c_velocity *
            Eigen::Vector3d(from_q<16>(shear->x.v[i]), from_q<16>(shear->y.v[i]), 0.0);
      pts.push_back(s);
    }
    MotionEstimator me;
    SensorMotion out;
    ASSERT_EQ(me.update(*cs, *shear, kDt, out), Status::kOk);
    ASSERT_EQ(out.points, static_cast<int>(pts.size()));
    const MomentSums ms = to_metric(out.moments, out.proxy_scale);
    // Any rigid transform: random rotation (incl. the mirrored right-pad mount) and offset.
    Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
    q.normalize();
    Eigen::Matrix3d R = q.toRotationMatrix();
    if (trial % 2 == 1) R = R * Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
    const Eigen::Vector3d p = Eigen::Vector3d(n(rng), n(rng), n(rng)) * 0.02;
    Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Atb = Eigen::Vector3d::Zero();
    add_normal_equations(rigid_transform(ms, R, p), AtA, Atb);
    std::vector<dsp_ref::PointSample> g = pts;
    for (auto& s : g) {
      s.q = R * s.q + p;
      s.v = R * s.v;
      s.normal = R * s.normal;
    }
    const dsp_ref::StackedSystem sys = dsp_ref::stack_shear_rows(g);
    const Eigen::Matrix3d AtA_ref = sys.A.transpose() * sys.A;
    const Eigen::Vector3d Atb_ref = sys.A.transpose() * sys.b;
    EXPECT_LT((AtA - AtA_ref).cwiseAbs().maxCoeff(), 1e-13 * AtA_ref.cwiseAbs().maxCoeff());
    EXPECT_LT((Atb - Atb_ref).cwiseAbs().maxCoeff(), 1e-13 * Atb_ref.cwiseAbs().maxCoeff());
    // The same least-squares solution (same Tikhonov λ) from a QR of the stacked rows.
    Solve3Options opt;
    opt.lambda_rel = 1e-6;
    opt.lambda_abs = 0.0;
    const Solve3Result r = solve3(AtA, Atb, opt);
    const Eigen::Vector3d w_ref = dsp_ref::solve_stacked(sys, r.lambda);
    EXPECT_LT((r.x - w_ref).norm(), 1e-9 * w_ref.norm());
    // Sensor frame: the paper's own rows [0, z, −y], [−z, 0, x] (identity transform).
    Eigen::Matrix3d AtA_s = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Atb_s = Eigen::Vector3d::Zero();
    add_normal_equations(ms, AtA_s, Atb_s);
    const dsp_ref::StackedSystem sys_s = dsp_ref::stack_shear_rows(pts);
    EXPECT_LT((AtA_s - sys_s.A.transpose() * sys_s.A).cwiseAbs().maxCoeff(),
              1e-12 * AtA_s.cwiseAbs().maxCoeff());
    EXPECT_EQ(sys_s.A(0, 0), 0.0);
    EXPECT_DOUBLE_EQ(sys_s.A(0, 1), pts[0].q.z());
    EXPECT_DOUBLE_EQ(sys_s.A(0, 2), -pts[0].q.y());
    EXPECT_DOUBLE_EQ(sys_s.A(1, 0), -pts[0].q.z());
    EXPECT_DOUBLE_EQ(sys_s.A(1, 2), pts[0].q.x());
  }
}

TEST(Motion, ExtremeMomentsAreExactInInt64) {
  auto cs = std::make_unique<ContactSet>();
  auto shear = std::make_unique<VectorField>();
  cs->mask.fill(1);
  cs->x_nm.fill(kMaxPointNm);
  cs->y_nm.fill(-kMaxPointNm);
  cs->z_nm.fill(kQ32MaxPos);  // re-clamped to 2^24 − 1 by the motion stage
  shear->x.fill(kQ32MaxPos);  // clamped to ±kMaxProxyQ16
  shear->y.fill(kQ32MaxNeg);
  MotionEstimator me;
  SensorMotion out;
  ASSERT_EQ(me.update(*cs, *shear, kDt, out), Status::kOk);
  const std::int64_t n = kGridCount, x = kMaxPointNm, z = (1 << 24) - 1, v = kMaxProxyQ16;
  EXPECT_EQ(out.moments.n, n);
  EXPECT_EQ(out.moments.sxx, n * x * x);
  EXPECT_EQ(out.moments.sxy, -n * x * x);
  EXPECT_EQ(out.moments.szz, n * z * z);
  EXPECT_EQ(out.moments.sx_vy, -n * x * v);
  EXPECT_EQ(out.moments.sz_vx, n * z * v);
  EXPECT_EQ(out.moments.svv, 2 * n * v * v);
  expect_finite(out);
}

TEST(Motion, CentroidTranslationMatchesAnalyticMotion) {
  for (VelocityProxy mode : {VelocityProxy::kVelocity, VelocityProxy::kDisplacement}) {
    Calibration cal;
    cal.velocity_proxy = mode;
    RigidContactScene sc;
    sc.contact_centre_G = Eigen::Vector3d(3e-3, -2e-3, 0.0);
    sc.t_G = Eigen::Vector3d(3e-3, -2e-3, 0.0);  // m/s
    sc.omega_G = Eigen::Vector3d(0.0, 0.0, 0.4);
    const SyntheticSensorFrames f = dsp_ref::render_rigid_contact(cal, sc);
    Runner run(cal);
    const SensorMotion m = run.pair(f);
    ASSERT_TRUE(m.translation_valid);
    // Velocity proxy: the paper's mask centroid; displacement proxy (sticking contact): the
    // mean displacement of the material points, which agrees here because nothing slides.
    EXPECT_EQ(m.translation_source, mode == VelocityProxy::kVelocity
                                        ? TranslationSource::kCentroid
                                        : TranslationSource::kCommonPoints);
    EXPECT_EQ(m.mask_change, 0.0);
    // Stick: every contact point moved by v(q)·dt, so a centroid with fixed weights moved by
    // v(centroid)·dt: the plain mean for the material points (displacement proxy), the mean
    // weighted by the height z for the sliding rule (velocity proxy; the heights come from f^z,
    // the same in both frames).
    Eigen::Vector3d c = dsp_ref::centroid(f.points_G);
    if (mode == VelocityProxy::kVelocity) {
      // The weighting is visible at this test's bound: on the coarse grid the two centroids
      // differ, and ω × Δc moves the expected translation by more than the 3e-7 m/s tolerance.
      const Eigen::Vector3d plain = c;
      c = height_weighted_centroid(f.points_G);
      EXPECT_GT(sc.omega_G.cross(c - plain).head<2>().norm(), 6e-7);
    }
    Eigen::Vector3d expect = sc.omega_G.cross(c) + sc.t_G;
    expect.z() = 0.0;
    // Positions are Q16 working px (≤ 2^-17 · 150 µm = 1.1 nm per point) and 1 nm integers:
    // ≤ ~2 nm per frame / dt = 2.4e-7 m/s.
    EXPECT_LT((m.translation - expect).norm(), 3e-7) << static_cast<int>(mode);
    EXPECT_EQ(m.translation.z(), 0.0);
  }
}

TEST(Motion, RotationFromRigidShearMatchesTruthAndReference) {
  for (VelocityProxy mode : {VelocityProxy::kVelocity, VelocityProxy::kDisplacement}) {
    Calibration cal;
    cal.velocity_proxy = mode;
    cal.solve_lambda_rel = 0.0;
    cal.solve_lever_floor_m = 0.0;
    RigidContactScene sc;
    sc.contact_centre_G = Eigen::Vector3d(2e-3, 1e-3, 0.0);
    sc.radius_m = 5e-3;
    sc.peak_fz = 0.15;
    sc.omega_G = Eigen::Vector3d(0.2, -0.3, 0.5);  // about the pad origin, t = 0
    const SyntheticSensorFrames f = dsp_ref::render_rigid_contact(cal, sc);
    Runner run(cal);
    const SensorMotion m = run.pair(f);
    ASSERT_TRUE(m.contact);
    EXPECT_TRUE(m.rotation_valid);
    EXPECT_EQ(m.solve.rank, 3);
    // Rigid data with t = 0 is fitted exactly by the own-frame shear-only model; what is left
    // is Q16 shear quantisation (≤ 2^-17 · c_v per point) amplified by the small z lever.
    EXPECT_LT((m.omega - sc.omega_G).norm(), 1e-4 * sc.omega_G.norm()) << static_cast<int>(mode);
    EXPECT_LT(std::abs(m.omega.z() - sc.omega_G.z()), 1e-5);

    // Double reference, same rules, same λ (= 0 here).
    dsp_ref::ContactDetectorRef rdet(cal);
    dsp_ref::MotionRef rme(cal);
    auto shear_d = [](const VectorField& s, bool x) {
      std::vector<double> v(static_cast<std::size_t>(kGridCount));
      for (std::size_t i = 0; i < v.size(); ++i) v[i] = from_q<16>(x ? s.x.v[i] : s.y.v[i]);
      return v;
    };
    std::vector<double> fz(static_cast<std::size_t>(kGridCount));
    for (std::size_t i = 0; i < fz.size(); ++i) fz[i] = from_q<16>(f.fz.v[i]);
    rme.update(rdet.detect(fz, f.w_prev, f.valid), shear_d(f.shear_prev, true),
               shear_d(f.shear_prev, false), kDt);
    const dsp_ref::SensorMotionRef r =
        rme.update(rdet.detect(fz, f.w_now, f.valid), shear_d(f.shear_now, true),
                   shear_d(f.shear_now, false), kDt);
    EXPECT_EQ(r.points, m.points);
    // Fixed path vs double of the same Q16 inputs: only z (Q16 filter → nm) and nm rounding.
    EXPECT_LT((m.omega - r.omega).norm(), 2e-5 * r.omega.norm());
    // ≤ 0.5 nm position rounding per point and frame: ≤ 1 nm / dt = 1.2e-7 m/s.
    EXPECT_LT((m.translation - r.translation).norm(), 1.2e-7);
    // The point the translation applies at (the weighted centroid for kVelocity): same within
    // the rounding of positions (0.5 nm) and heights (z goes through the Q16 filter: a few nm).
    EXPECT_EQ(m.translation_source, static_cast<TranslationSource>(r.translation_source));
    EXPECT_LT((m.translation_point_m - r.translation_point).norm(), 1e-8);
  }
}

TEST(Motion, SlidingCentroidFallsBackToThePlainMeanWithoutHeights) {
  // height_gain_m = 0: every contact point has z = 0, so there is nothing to weight by. The
  // sliding rule reads the plain mask centroid and refers the translation to it.
  Calibration cal;
  cal.velocity_proxy = VelocityProxy::kVelocity;
  cal.height_gain_m = 0.0;
  RigidContactScene sc;
  sc.contact_centre_G = Eigen::Vector3d(3e-3, -2e-3, 0.0);
  sc.t_G = Eigen::Vector3d(3e-3, -2e-3, 0.0);
  sc.omega_G = Eigen::Vector3d(0.0, 0.0, 0.4);
  const SyntheticSensorFrames f = dsp_ref::render_rigid_contact(cal, sc);
  Runner run(cal);
  const SensorMotion m = run.pair(f);
  ASSERT_TRUE(m.translation_valid);
  EXPECT_EQ(m.translation_source, TranslationSource::kCentroid);
  EXPECT_EQ(m.centroid_m.z(), 0.0);
  EXPECT_EQ(m.translation_point_m, m.centroid_m);
  const Eigen::Vector3d c = dsp_ref::centroid(f.points_G);
  Eigen::Vector3d expect = sc.omega_G.cross(c) + sc.t_G;
  expect.z() = 0.0;
  EXPECT_LT((m.translation - expect).norm(), 3e-7);
}

TEST(Motion, DisjointMasksGiveNoTranslation) {
  // One contact vanishes as another appears 8 mm away: no cell is in both masks. That is not a
  // slide (a patch moves by a fraction of its size per frame), so there is no translation,
  // whatever max_mask_change says.
  for (double gate : {1.0, 0.3}) {
    Calibration cal;
    cal.velocity_proxy = VelocityProxy::kVelocity;
    cal.max_mask_change = gate;
    RigidContactScene a, b;
    a.contact_centre_G = Eigen::Vector3d(-4e-3, 0.0, 0.0);
    b.contact_centre_G = Eigen::Vector3d(4e-3, 0.0, 0.0);
    a.radius_m = b.radius_m = 3e-3;
    const SyntheticSensorFrames fa = dsp_ref::render_rigid_contact(cal, a);
    const SyntheticSensorFrames fb = dsp_ref::render_rigid_contact(cal, b);
    const VectorField still;  // zero-initialised: the gel does not move
    Runner run(cal);
    (void)run.frame(fa.fz, still, still);
    const SensorMotion m = run.frame(fb.fz, still, still);
    ASSERT_TRUE(m.contact);
    EXPECT_EQ(m.mask_change, 1.0);
    EXPECT_FALSE(m.translation_valid) << gate;
    EXPECT_EQ(m.translation_source, TranslationSource::kNone);
    EXPECT_EQ(m.translation, Eigen::Vector3d::Zero());
    expect_finite(m);
  }
}

TEST(Motion, DefaultRegularisationBiasIsSmall) {
  const Calibration cal;  // λ_rel = 1e-6, lever floor 10 µm
  RigidContactScene sc;
  sc.radius_m = 5e-3;
  sc.peak_fz = 0.15;  // z up to 0.75 mm
  sc.omega_G = Eigen::Vector3d(0.2, -0.3, 0.5);
  Runner run(cal);
  const SensorMotion m = run.pair(dsp_ref::render_rigid_contact(cal, sc));
  // λ ≈ N · (10 µm)² against Σ z² ≈ N · (0.3 mm)²: ~0.1 % shrinkage of ω_x, ω_y.
  EXPECT_LT((m.omega - sc.omega_G).norm(), 1e-3 * sc.omega_G.norm());
  EXPECT_TRUE(m.rotation_valid);
}

TEST(Motion, DisplacementModeNeedsOnePreviousFrame) {
  Calibration cal;
  cal.velocity_proxy = VelocityProxy::kDisplacement;
  RigidContactScene sc;
  sc.omega_G = Eigen::Vector3d(0.0, 0.0, 0.5);
  const SyntheticSensorFrames f = dsp_ref::render_rigid_contact(cal, sc);
  Runner run(cal);
  const SensorMotion first = run.frame(f.fz, f.w_prev, f.shear_prev);
  EXPECT_TRUE(first.contact);
  EXPECT_FALSE(first.proxy_valid);
  EXPECT_FALSE(first.rotation_valid);
  EXPECT_EQ(first.omega, Eigen::Vector3d::Zero());
  const SensorMotion second = run.frame(f.fz, f.w_now, f.shear_now);
  EXPECT_TRUE(second.proxy_valid);
  EXPECT_NEAR(second.omega.z(), 0.5, 1e-4);
  // After reset the first frame is again without proxy.
  run.me->reset();
  EXPECT_FALSE(run.frame(f.fz, f.w_now, f.shear_now).proxy_valid);
}

// The displacement proxy reads increments only where the cell was in Ω at both frames: a cell
// that enters Ω holds whatever shear it had outside the patch (stale, untracked), and its first
// increment would be that catch-up, read as motion at the largest lever.
TEST(Motion, DisplacementIncrementsOnlyFromCellsInBothMasks) {
  Calibration cal;
  cal.velocity_proxy = VelocityProxy::kDisplacement;
  RigidContactScene small, large;
  small.radius_m = 3e-3;
  large.radius_m = 4.5e-3;
  small.omega_G = large.omega_G = Eigen::Vector3d(0.0, 0.0, 0.5);
  const SyntheticSensorFrames fs = dsp_ref::render_rigid_contact(cal, small);
  const SyntheticSensorFrames fl = dsp_ref::render_rigid_contact(cal, large);
  Runner run(cal);
  (void)run.frame(fs.fz, fl.w_prev, fl.shear_prev);
  const GridMask before = run.cs->mask;
  // The ring that enters Ω this frame carries a stale shear 20 times the true increment.
  auto stale = std::make_unique<VectorField>(fl.shear_now);
  run.det->detect(
      fl.fz, fl.w_now,
      [] {
        GridMask v;
        v.fill(1);
        return v;
      }(),
      *run.cs);
  int entering = 0, both = 0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    if (run.cs->mask.v[i] == 0) continue;
    if (before.v[i] == 0) {
      stale->x.v[i] *= 20;
      stale->y.v[i] *= 20;
      ++entering;
    } else {
      ++both;
    }
  }
  ASSERT_GT(entering, 10);
  SensorMotion m;
  ASSERT_EQ(run.me->update(*run.cs, *stale, kDt, m), Status::kOk);
  EXPECT_EQ(m.points, entering + both);
  EXPECT_EQ(m.moments.n, both);  // the proxy's moments: the cells in both masks
  ASSERT_TRUE(m.rotation_valid);
  EXPECT_NEAR(m.omega.z(), 0.5, 1e-4);
}

// kDisplacement without the solve's regularisation (λ and the lever floor at 0), so a rigid
// increment is read exactly.
Calibration exact_displacement_cal() {
  Calibration cal;
  cal.velocity_proxy = VelocityProxy::kDisplacement;
  cal.solve_lambda_rel = 0.0;
  cal.solve_lever_floor_m = 0.0;
  return cal;
}

// The double reference fed the same frames: each scene's f^z and valid set, its shear, and the
// fixed path's reported mask of that frame (so both read the same Ω). One result per frame.
std::vector<dsp_ref::SensorMotionRef> reference_run(
    const Calibration& cal, const std::vector<const SyntheticSensorFrames*>& scenes,
    const std::vector<const VectorField*>& shears, const std::vector<GridMask>& masks) {
  dsp_ref::ContactDetectorRef rdet(cal);
  dsp_ref::MotionRef rme(cal);
  std::vector<dsp_ref::SensorMotionRef> out;
  for (std::size_t k = 0; k < scenes.size(); ++k) {
    std::vector<double> fz(static_cast<std::size_t>(kGridCount)), sx(fz.size()), sy(fz.size());
    for (std::size_t i = 0; i < fz.size(); ++i) {
      fz[i] = from_q<16>(scenes[k]->fz.v[i]);
      sx[i] = from_q<16>(shears[k]->x.v[i]);
      sy[i] = from_q<16>(shears[k]->y.v[i]);
    }
    out.push_back(
        rme.update(rdet.detect(fz, scenes[k]->w_now, scenes[k]->valid, &masks[k]), sx, sy, kDt));
  }
  return out;
}

// A held tangential load stretches the gel behind the patch, and 𝒢 reads the stretch as normal
// load: Ω grows over gel that follows the object only partly. The displacement proxy reads its
// increments over the patch as it was while the contact was tangentially unloaded
// (docs/dsp/motion.md, patch anchor).
// Here: an unloaded patch of radius 3 mm, then a torsion that grows Ω to 4.5 mm, the ring
// gaining half the rigid increment. The anchored reading is the rigid torsion; over the whole
// Ω_t ∩ Ω_{t−1} the ring would dilute it. Fixed path and double reference alike.
TEST(Motion, AHeldTangentialLoadIsReadOverThePatchNotTheStretchedGel) {
  const Calibration cal = exact_displacement_cal();
  RigidContactScene small, large;
  small.radius_m = 3e-3;
  large.radius_m = 4.5e-3;
  small.omega_G = large.omega_G = Eigen::Vector3d(0.0, 0.0, 3.0);
  const SyntheticSensorFrames fs = dsp_ref::render_rigid_contact(cal, small);
  const SyntheticSensorFrames fl = dsp_ref::render_rigid_contact(cal, large);
  // Per-cell rigid increment of one frame (Q16 shear units) at the large patch's cells.
  VectorField inc;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    inc.x.v[i] = fl.shear_now.x.v[i] - fl.shear_prev.x.v[i];
    inc.y.v[i] = fl.shear_now.y.v[i] - fl.shear_prev.y.v[i];
  }
  VectorField zero;
  zero.x.fill(0);
  zero.y.fill(0);

  Runner run(cal);
  const SensorMotion a = run.frame(fs.fz, fs.w_now, zero);  // the grasp: no tangential load
  EXPECT_TRUE(a.anchor_set);
  const GridMask patch = run.cs->mask;
  std::array<GridMask, 3> masks{patch, {}, {}};
  // Frame b: Ω grows to the large patch; every cell gains its increment, the ring half of it.
  auto s1 = std::make_unique<VectorField>(zero);
  const auto add_increment = [&](VectorField& s) {
    for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
      const int k = patch.v[i] != 0 ? 2 : 1;
      s.x.v[i] += inc.x.v[i] * k / 2;
      s.y.v[i] += inc.y.v[i] * k / 2;
    }
  };
  add_increment(*s1);
  const SensorMotion b = run.frame(fl.fz, fl.w_now, *s1);
  EXPECT_FALSE(b.anchor_set) << "loaded: |X| above slip_min_shift_m";
  masks[1] = run.cs->mask;
  int ring = 0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i)
    ring += run.cs->mask.v[i] != 0 && patch.v[i] == 0 ? 1 : 0;
  ASSERT_GT(ring, 20);
  auto s2 = std::make_unique<VectorField>(*s1);
  add_increment(*s2);
  const SensorMotion c = run.frame(fl.fz, fl.w_now, *s2);
  ASSERT_TRUE(c.rotation_valid);
  masks[2] = run.cs->mask;
  int in_patch = 0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i)
    in_patch += run.cs->mask.v[i] != 0 && patch.v[i] != 0 ? 1 : 0;
  EXPECT_EQ(c.moments.n, in_patch);
  EXPECT_NEAR(c.omega.z(), 3.0, 3e-3);
  // What Ω_t ∩ Ω_{t−1} would read: the rigid fit of the same increments with the ring's halved.
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    if (run.cs->mask.v[i] == 0) continue;
    const double x = run.cs->x_nm.v[i] * 1e-9, y = run.cs->y_nm.v[i] * 1e-9;
    const double k = patch.v[i] != 0 ? 1.0 : 0.5;
    num += k * 3.0 * (x * x + y * y);
    den += x * x + y * y;
  }
  std::printf("anchored torsion %.4f rad/s for 3; over all of Omega %.3f\n", c.omega.z(),
              num / den);
  EXPECT_LT(num / den, 2.5);

  // The double reference, on the same masks, takes the same anchor.
  dsp_ref::ContactDetectorRef rdet(cal);
  dsp_ref::MotionRef rme(cal);
  auto shear_d = [](const VectorField& s, bool x) {
    std::vector<double> v(static_cast<std::size_t>(kGridCount));
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = from_q<16>(x ? s.x.v[i] : s.y.v[i]);
    return v;
  };
  auto fz_d = [](const ScalarField& f) {
    std::vector<double> v(static_cast<std::size_t>(kGridCount));
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = from_q<16>(f.v[i]);
    return v;
  };
  const dsp_ref::SensorMotionRef ra =
      rme.update(rdet.detect(fz_d(fs.fz), fs.w_now, fs.valid, &masks[0]), shear_d(zero, true),
                 shear_d(zero, false), kDt);
  EXPECT_TRUE(ra.anchor_set);
  const dsp_ref::SensorMotionRef rb =
      rme.update(rdet.detect(fz_d(fl.fz), fl.w_now, fl.valid, &masks[1]), shear_d(*s1, true),
                 shear_d(*s1, false), kDt);
  EXPECT_FALSE(rb.anchor_set);
  const dsp_ref::SensorMotionRef rc =
      rme.update(rdet.detect(fz_d(fl.fz), fl.w_now, fl.valid, &masks[2]), shear_d(*s2, true),
                 shear_d(*s2, false), kDt);
  EXPECT_EQ(static_cast<int>(rc.samples.size()), in_patch);
  EXPECT_NEAR(rc.omega.z(), c.omega.z(), 1e-3);

  // A gap in the stream or a missed frame (restart()) keeps the anchor: the load is still held
  // and the stretched Ω is not taken for the patch. The first frame after it has no increment.
  run.me->restart();
  const SensorMotion d = run.frame(fl.fz, fl.w_now, *s2);
  EXPECT_FALSE(d.anchor_set);
  EXPECT_FALSE(d.proxy_valid);
  auto s3 = std::make_unique<VectorField>(*s2);
  add_increment(*s3);
  const SensorMotion e = run.frame(fl.fz, fl.w_now, *s3);
  ASSERT_TRUE(e.rotation_valid);
  EXPECT_EQ(e.moments.n, in_patch);
  EXPECT_NEAR(e.omega.z(), 3.0, 3e-3);
  // reset() (tare, degraded frame) forgets it: the next frame anchors the stretched Ω.
  run.me->reset();
  EXPECT_TRUE(run.frame(fl.fz, fl.w_now, *s3).anchor_set);
  auto s4 = std::make_unique<VectorField>(*s3);
  add_increment(*s4);
  const SensorMotion g = run.frame(fl.fz, fl.w_now, *s4);
  ASSERT_TRUE(g.rotation_valid);
  int all = 0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i)
    all += run.cs->mask.v[i] != 0 ? 1 : 0;
  EXPECT_EQ(g.moments.n, all);
  EXPECT_NEAR(g.omega.z(), num / den, 0.01);
}

// The same stretch under a stick translation: the material points of the patch move with the
// object, those of the ring Ω grows over move half as far. The stick rule reads the mean
// displacement of the anchored patch's common points, the object's own; over all of
// Ω_t ∩ Ω_{t−1} the ring would dilute it. Fixed path and double reference alike.
TEST(Motion, AStickTranslationIsReadOverThePatchNotTheStretchedGel) {
  const Calibration cal = exact_displacement_cal();
  RigidContactScene small, large;
  small.radius_m = 3e-3;
  large.radius_m = 4.5e-3;
  SyntheticSensorFrames fs = dsp_ref::render_rigid_contact(cal, small);
  SyntheticSensorFrames fl = dsp_ref::render_rigid_contact(cal, large);
  VectorField zero;
  zero.x.fill(0);
  zero.y.fill(0);
  fs.w_now = zero;
  Runner run(cal);
  (void)run.frame(fs.fz, fs.w_now, zero);  // the grasp, unloaded: anchors the patch
  const GridMask patch = run.cs->mask;
  // A tangential load along x: a uniform shear whose content is far above slip_min_shift_m, so
  // the anchor is kept; the patch's material moves by k·step, the ring's by k·step/2.
  constexpr std::int32_t kStepQ16 = 1 << 15;  // half a working-grid pixel per frame
  VectorField shear = zero;
  shear.x.fill(std::int32_t{1} << 20);
  const auto loaded = [&](int k) {
    SyntheticSensorFrames f = fl;
    f.w_now = zero;
    for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i)
      f.w_now.x.v[i] = patch.v[i] != 0 ? k * kStepQ16 : k * kStepQ16 / 2;
    return f;
  };
  const SyntheticSensorFrames f1 = loaded(1), f2 = loaded(2);
  std::vector<GridMask> masks{patch};
  const SensorMotion b = run.frame(f1.fz, f1.w_now, shear);
  EXPECT_FALSE(b.anchor_set);
  masks.push_back(run.cs->mask);
  const ContactSet before = *run.cs;
  const SensorMotion c = run.frame(f2.fz, f2.w_now, shear);
  masks.push_back(run.cs->mask);
  // The patch's displacement (nm) and the mean over every common point.
  double patch_dx = 0.0, all_dx = 0.0;
  int n_patch = 0, n_all = 0, ring = 0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    if (run.cs->mask.v[i] == 0 || before.mask.v[i] == 0) continue;
    const double dx = run.cs->x_nm.v[i] - before.x_nm.v[i];
    all_dx += dx;
    ++n_all;
    if (patch.v[i] != 0) {
      patch_dx += dx;
      ++n_patch;
    } else {
      ++ring;
    }
  }
  ASSERT_GT(ring, 20);
  ASSERT_GT(n_patch, 20);
  patch_dx /= n_patch;
  all_dx /= n_all;
  ASSERT_TRUE(c.translation_valid);
  EXPECT_EQ(c.translation_source, TranslationSource::kCommonPoints);
  EXPECT_NEAR(c.translation.x() * kDt * 1e9, patch_dx, 1.0);
  EXPECT_NEAR(c.translation.y(), 0.0, 1e-9);
  EXPECT_LT(all_dx, 0.9 * patch_dx) << "the ring dilutes the mean: the test tells the rules apart";

  const std::vector<dsp_ref::SensorMotionRef> r =
      reference_run(cal, {&fs, &f1, &f2}, {&zero, &shear, &shear}, masks);
  ASSERT_TRUE(r[2].translation_valid);
  EXPECT_NEAR(r[2].translation.x(), c.translation.x(), 1e-4 * std::abs(c.translation.x()));
}

// The anchor's fallback: a contact that has left every anchored cell while loaded (here the
// patch moves off it in one frame, a tangential load held) is read over Ω_t ∩ Ω_{t−1} rather
// than from nothing. Fixed path and double reference alike.
TEST(Motion, AContactThatLeftItsAnchoredCellsIsReadOverTheCellsItKept) {
  const Calibration cal = exact_displacement_cal();
  RigidContactScene first, moved;
  first.radius_m = moved.radius_m = 2.5e-3;
  first.contact_centre_G = Eigen::Vector3d(-4e-3, 0.0, 0.0);
  moved.contact_centre_G = Eigen::Vector3d(4e-3, 0.0, 0.0);
  moved.omega_G = Eigen::Vector3d(0.0, 0.0, 3.0);
  const SyntheticSensorFrames fa = dsp_ref::render_rigid_contact(cal, first);
  const SyntheticSensorFrames fb = dsp_ref::render_rigid_contact(cal, moved);
  // A held tangential load: a uniform 100 µm shift, 5 times slip_min_shift_m.
  const std::int32_t load_q16 = to_q32<16>(100e-6 / cal.c_displacement);
  VectorField zero;
  zero.x.fill(0);
  zero.y.fill(0);
  auto loaded_b = std::make_unique<VectorField>(zero);
  auto loaded_c = std::make_unique<VectorField>(fb.shear_now);
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    loaded_b->x.v[i] += load_q16;
    loaded_c->x.v[i] += load_q16;
  }
  Runner run(cal);
  EXPECT_TRUE(run.frame(fa.fz, fa.w_now, zero).anchor_set);
  const GridMask anchor = run.cs->mask;
  const SensorMotion b = run.frame(fb.fz, fb.w_now, *loaded_b);
  EXPECT_FALSE(b.anchor_set);
  const GridMask mask_b = run.cs->mask;
  const SensorMotion c = run.frame(fb.fz, fb.w_now, *loaded_c);
  EXPECT_FALSE(c.anchor_set);
  int kept = 0, anchored = 0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    kept += run.cs->mask.v[i] != 0 && mask_b.v[i] != 0 ? 1 : 0;
    anchored += run.cs->mask.v[i] != 0 && anchor.v[i] != 0 ? 1 : 0;
  }
  ASSERT_EQ(anchored, 0);
  ASSERT_GT(kept, 20);
  ASSERT_TRUE(c.rotation_valid);
  EXPECT_EQ(c.moments.n, kept);
  EXPECT_NEAR(c.omega.z(), 3.0, 3e-3);

  const std::vector<dsp_ref::SensorMotionRef> refs =
      reference_run(cal, {&fa, &fb, &fb}, {&zero, loaded_b.get(), loaded_c.get()},
                    {anchor, mask_b, run.cs->mask});
  for (std::size_t k = 0; k < refs.size(); ++k)
    EXPECT_EQ(refs[k].anchor_set, k == 0) << "frame " << k;
  const dsp_ref::SensorMotionRef& r = refs.back();
  EXPECT_EQ(static_cast<int>(r.samples.size()), kept);
  EXPECT_NEAR(r.omega.z(), c.omega.z(), 1e-3);
}

// A drag (the gel over the patch dragged along by a slide about an in-plane axis, or a
// translation) stretches the gel behind the patch, 𝒢 reads the stretch as load and Ω leaves
// the patch for gel whose shear has decayed, so a reading over Ω would depend on the slide's
// speed (docs/dsp/motion.md, drag region). The velocity proxy then reads over Ω ∩ anchor.
// Here: a grasp of radius 3 mm (anchored, no load), then Ω grown to 4.5 mm with the ring carrying
// half the rigid velocity. A drag (ω about x) is read over the anchored cells, exactly; a
// torsion (ω about z: no divergence, Ω is not displaced, and an elongated patch turns away from
// its anchor) and a patch that has left most of its anchor are read over all of Ω. The double
// reference decides the same.
TEST(Motion, ADragIsReadOverTheAnchoredPatchNotTheGelItStretched) {
  Calibration cal;
  cal.velocity_proxy = VelocityProxy::kVelocity;
  cal.solve_lambda_rel = 0.0;
  cal.solve_lever_floor_m = 0.0;
  struct Case {
    const char* name;
    Eigen::Vector3d omega;
    Eigen::Vector3d centre;
    bool anchored;
  };
  const std::array<Case, 3> cases{{
      {"drag", Eigen::Vector3d(2.0, 0.0, 0.0), Eigen::Vector3d::Zero(), true},
      {"torsion", Eigen::Vector3d(0.0, 0.0, 3.0), Eigen::Vector3d::Zero(), false},
      {"patch moved on", Eigen::Vector3d(2.0, 0.0, 0.0), Eigen::Vector3d(5e-3, 0.0, 0.0), false},
  }};
  RigidContactScene grasp;
  grasp.radius_m = 3e-3;
  const SyntheticSensorFrames fg = dsp_ref::render_rigid_contact(cal, grasp);
  VectorField zero;
  zero.x.fill(0);
  zero.y.fill(0);
  for (const Case& k : cases) {
    RigidContactScene grown;
    grown.radius_m = 4.5e-3;
    grown.contact_centre_G = k.centre;
    grown.omega_G = k.omega;
    const SyntheticSensorFrames fl = dsp_ref::render_rigid_contact(cal, grown);
    Runner run(cal);
    const SensorMotion a = run.frame(fg.fz, fg.w_now, zero);
    EXPECT_TRUE(a.anchor_set);
    EXPECT_FALSE(a.velocity_anchored) << "no anchor yet when the first frame is read";
    const GridMask patch = run.cs->mask;
    // The ring outside the anchored patch carries half the rigid shear.
    auto shear = std::make_unique<VectorField>(fl.shear_now);
    for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
      if (patch.v[i] != 0) continue;
      shear->x.v[i] /= 2;
      shear->y.v[i] /= 2;
    }
    const SensorMotion b = run.frame(fl.fz, fl.w_now, *shear);
    ASSERT_TRUE(b.rotation_valid) << k.name;
    int held = 0, ring = 0;
    double num = 0.0, den = 0.0;  // the rigid fit over all of Ω of the drag's s_y = −ω_x z
    for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
      if (run.cs->mask.v[i] == 0) continue;
      held += patch.v[i] != 0 ? 1 : 0;
      ring += patch.v[i] == 0 ? 1 : 0;
      const double z = run.cs->z_nm.v[i] * 1e-9, f = patch.v[i] != 0 ? 1.0 : 0.5;
      num += f * k.omega.x() * z * z;
      den += z * z;
    }
    ASSERT_GT(ring, 20) << k.name;
    EXPECT_EQ(b.velocity_anchored, k.anchored) << k.name;
    EXPECT_EQ(b.moments.n, k.anchored ? held : b.points) << k.name;
    EXPECT_EQ(b.velocity_points, b.moments.n) << k.name;
    if (k.anchored) {
      // Exact over the anchored cells; over all of Ω the halved ring would dilute it.
      EXPECT_LT((b.omega - k.omega).norm(), 1e-3 * k.omega.norm()) << k.name;
      std::printf("drag read over the anchored patch %.4f rad/s for 2; over all of Omega %.3f\n",
                  b.omega.x(), num / den);
      EXPECT_LT(num / den, 0.9 * k.omega.x());
    } else {
      const auto anchor_cells = std::count(patch.v.begin(), patch.v.end(), 1);
      if (k.centre.isZero()) {
        EXPECT_GE(held * 2, anchor_cells) << k.name;  // the anchor is held: torsion decides
      } else {
        EXPECT_LT(held * 2, anchor_cells) << k.name;
      }
    }

    const dsp_ref::SensorMotionRef r =
        reference_run(cal, {&fg, &fl}, {&zero, shear.get()}, {patch, run.cs->mask}).back();
    EXPECT_EQ(r.velocity_anchored, b.velocity_anchored) << k.name;
    EXPECT_EQ(static_cast<int>(r.samples.size()), b.moments.n) << k.name;
    EXPECT_LT((r.omega - b.omega).norm(), 1e-4 * k.omega.norm()) << k.name;
  }
}

// rotation_scale serves the velocity proxy; the displacement proxy's frames use rotation_scale
// ⊙ displacement_rotation_ratio, and kAuto reports each reading with its own scales.
TEST(Motion, DisplacementRotationRatioScalesOnlyTheDisplacementProxy) {
  for (const VelocityProxy mode :
       {VelocityProxy::kVelocity, VelocityProxy::kDisplacement, VelocityProxy::kAuto}) {
    Calibration cal;
    cal.velocity_proxy = mode;
    cal.rotation_scale = {1.0, 1.0, 2.0};
    cal.displacement_rotation_ratio = {1.0, 1.0, 0.25};
    RigidContactScene sc;
    sc.omega_G = Eigen::Vector3d(0.0, 0.0, 0.5);
    Calibration render = cal;
    render.velocity_proxy =
        mode == VelocityProxy::kVelocity ? VelocityProxy::kVelocity : VelocityProxy::kDisplacement;
    const SyntheticSensorFrames f = dsp_ref::render_rigid_contact(render, sc);
    Runner run(cal);
    const SensorMotion m = run.pair(f);
    ASSERT_TRUE(m.rotation_valid) << static_cast<int>(mode);
    if (mode == VelocityProxy::kVelocity) {
      EXPECT_NEAR(m.omega.z(), 2.0 * 0.5, 2e-4);
      EXPECT_FALSE(m.velocity_differs);
    } else {
      EXPECT_NEAR(m.omega.z(), 0.5 * 0.5, 1e-4) << static_cast<int>(mode);
      EXPECT_EQ(m.rotation_scale, Eigen::Vector3d(1.0, 1.0, 0.5));
    }
    if (mode == VelocityProxy::kAuto) {
      // Sticking: the velocity reading beside it, with rotation_scale alone.
      EXPECT_TRUE(m.velocity_differs);
      EXPECT_EQ(m.velocity_rotation_scale, Eigen::Vector3d(1.0, 1.0, 2.0));
      EXPECT_EQ(velocity_reading(m).rotation_scale, Eigen::Vector3d(1.0, 1.0, 2.0));
    }
  }
}

TEST(Motion, OnsetAndLossGiveNoTranslationAndNoNan) {
  const Calibration cal;
  RigidContactScene sc;
  sc.t_G = Eigen::Vector3d(5e-3, 0.0, 0.0);
  const SyntheticSensorFrames f = dsp_ref::render_rigid_contact(cal, sc);
  Runner run(cal);
  auto empty = std::make_unique<SyntheticSensorFrames>();
  // Nothing → nothing.
  SensorMotion m = run.frame(empty->fz, empty->w_now, empty->shear_now);
  EXPECT_FALSE(m.contact);
  EXPECT_FALSE(m.rotation_valid);
  EXPECT_FALSE(m.translation_valid);
  EXPECT_EQ(m.omega, Eigen::Vector3d::Zero());
  EXPECT_EQ(m.translation, Eigen::Vector3d::Zero());
  EXPECT_FALSE(m.solve.valid);
  expect_finite(m);
  // Onset: contact appears. The centroid jumps from "nowhere": no translation this frame.
  m = run.frame(f.fz, f.w_now, f.shear_now);
  EXPECT_TRUE(m.contact);
  EXPECT_FALSE(m.translation_valid);
  EXPECT_EQ(m.translation_source, TranslationSource::kNone);
  EXPECT_EQ(m.translation, Eigen::Vector3d::Zero());
  EXPECT_EQ(m.mask_change, 1.0);
  // Loss: contact disappears.
  m = run.frame(empty->fz, empty->w_now, empty->shear_now);
  EXPECT_FALSE(m.contact);
  EXPECT_FALSE(m.translation_valid);
  EXPECT_EQ(m.translation, Eigen::Vector3d::Zero());
  expect_finite(m);
}

TEST(Motion, LargeAreaChangeUsesCommonPointsInsteadOfTheCentroidJump) {
  // The gate is off by default (max_mask_change = 1, see the next test); a press-dominated
  // installation can set it, and then a jump reads the material points.
  Calibration cal;
  cal.max_mask_change = 0.3;
  const Eigen::Vector3d v(4e-3, 1e-3, 0.0);  // object translation, m/s
  // Frame t−1: small patch; frame t: a much larger patch grown towards +x (pressing harder on
  // a tilted object). Every material point moves by v·dt.
  RigidContactScene small;
  small.contact_centre_G = Eigen::Vector3d(-2e-3, 0.0, 0.0);
  small.radius_m = 3e-3;
  small.t_G = v;
  RigidContactScene big = small;
  big.contact_centre_G = Eigen::Vector3d(1e-3, 0.0, 0.0);
  big.radius_m = 5e-3;
  const SyntheticSensorFrames fs = dsp_ref::render_rigid_contact(cal, small);
  const SyntheticSensorFrames fb = dsp_ref::render_rigid_contact(cal, big);
  Runner run(cal);
  const SensorMotion m0 = run.frame(fs.fz, fb.w_prev, fs.shear_now);
  const SensorMotion m1 = run.frame(fb.fz, fb.w_now, fb.shear_now);
  ASSERT_GT(m1.mask_change, cal.max_mask_change);
  EXPECT_TRUE(m1.translation_valid);
  EXPECT_EQ(m1.translation_source, TranslationSource::kCommonPoints);
  EXPECT_LT((m1.translation - v).norm(), 3e-7);
  // What the plain centroid difference would have reported: a spike of ~0.3 m/s.
  const double naive = (m1.centroid_m.x() - m0.centroid_m.x()) / kDt;
  EXPECT_GT(std::abs(naive - v.x()), 0.1);
  // A small change (a few edge cells) keeps the paper's mask-centroid rule.
  RigidContactScene bigger = big;
  bigger.radius_m = 5.2e-3;
  const SyntheticSensorFrames fg = dsp_ref::render_rigid_contact(cal, bigger);
  const SensorMotion m2 = run.frame(fg.fz, fb.w_now, fg.shear_now);
  EXPECT_LE(m2.mask_change, cal.max_mask_change);
  EXPECT_GT(m2.mask_change, 0.0);
  EXPECT_EQ(m2.translation_source, TranslationSource::kCentroid);
}

TEST(Motion, AContactFormingAtACornerReadsTheMaterialPointsNotTheCentroidJump) {
  // A flat face is first seen at one corner (a few cells), and a frame later over most of its
  // face: the mask's centroid jumps by millimetres while nothing moves (docs/dsp/motion.md,
  // translation). The area-ratio bound (default 1.5) reads that frame from the material points
  // in both masks; with the bound off (1e4) the sliding rule reports the jump as a translation.
  // The face then shrinks (pressure released) by a cell-count ratio just under 1.5, which keeps
  // the centroid rule; at a bound equal to that ratio still the centroid, just below it the
  // material points. The double reference decides the same on every frame.
  struct Chain {
    SensorMotion corner, face, smaller;
  };
  auto run_chain = [](double bound) {
    Calibration cal;
    cal.velocity_proxy = VelocityProxy::kVelocity;
    cal.max_mask_area_ratio = bound;
    RigidContactScene corner, face, smaller_face;
    corner.contact_centre_G = Eigen::Vector3d(-3e-3, 2e-3, 0.0);
    corner.radius_m = 1.5e-3;
    face.radius_m = 5e-3;
    smaller_face.radius_m = 3.9e-3;
    const VectorField still;  // zero-initialised: the gel does not move
    Runner run(cal);
    dsp_ref::ContactDetectorRef rdet(cal);
    dsp_ref::MotionRef rme(cal);
    const std::vector<double> zero(static_cast<std::size_t>(kGridCount), 0.0);
    auto both = [&](const RigidContactScene& sc) {
      const SyntheticSensorFrames f = dsp_ref::render_rigid_contact(cal, sc);
      const SensorMotion m = run.frame(f.fz, still, still);
      std::vector<double> fz(static_cast<std::size_t>(kGridCount));
      for (std::size_t i = 0; i < fz.size(); ++i) fz[i] = from_q<16>(f.fz.v[i]);
      const dsp_ref::SensorMotionRef r =
          rme.update(rdet.detect(fz, still, f.valid), zero, zero, kDt);
      EXPECT_EQ(r.points, m.points);
      EXPECT_EQ(m.translation_source, static_cast<TranslationSource>(r.translation_source));
      // Positions are rounded to 0.5 nm and the heights that weight the centroid go through
      // the Q16 filter: a few nm per frame on a patch at rest, and a small relative error on the
      // jump frame, where the weights themselves change.
      EXPECT_LT((m.translation - r.translation).norm(), 1e-6 + 2e-5 * r.translation.norm());
      return m;
    };
    Chain c;
    c.corner = both(corner);
    c.face = both(face);
    c.smaller = both(smaller_face);
    return c;
  };
  for (double bound : {1.5, 1e4}) {
    const Chain c = run_chain(bound);
    ASSERT_GT(c.face.points, 1.5 * c.corner.points);
    ASSERT_TRUE(c.face.translation_valid);
    if (bound == 1.5) {
      EXPECT_EQ(c.face.translation_source, TranslationSource::kCommonPoints);
      EXPECT_LT(c.face.translation.norm(), 1e-6);
    } else {
      EXPECT_EQ(c.face.translation_source, TranslationSource::kCentroid);
      EXPECT_GT(c.face.translation.norm(), 0.2);
    }
  }
  const Chain c = run_chain(1.5);
  const double ratio = static_cast<double>(c.face.points) / static_cast<double>(c.smaller.points);
  std::printf("corner %d cells, face %d, smaller face %d: ratio %.4f\n", c.corner.points,
              c.face.points, c.smaller.points, ratio);
  ASSERT_GT(ratio, 1.3);  // a real shrink, close to the bound
  ASSERT_LT(ratio, 1.5);
  EXPECT_EQ(c.smaller.translation_source, TranslationSource::kCentroid);
  // The bound is inclusive: a ratio equal to it reads the centroid, one above it does not. Both
  // implementations test larger <= bound * smaller, so the ratio must round-trip exactly.
  ASSERT_EQ(ratio * static_cast<double>(c.smaller.points), static_cast<double>(c.face.points));
  EXPECT_EQ(run_chain(ratio).smaller.translation_source, TranslationSource::kCentroid);
  EXPECT_EQ(run_chain(std::nextafter(ratio, 1.0)).smaller.translation_source,
            TranslationSource::kCommonPoints);
}

TEST(Motion, SlidingTranslationTelescopesThroughMaskBursts) {
  // A sliding patch whose mask advances in bursts, as Ω read from 𝒢 does in a slide (a third
  // of the cells entering or leaving in one frame): the patch stands still for three frames,
  // then jumps 1.5 mm. The gel does not move (w = 0: it slides). With the default calibration
  // the per-frame centroid differences telescope, so their sum is the centroid's whole
  // displacement (9 mm; the centroid weighted by the points' height, the sliding rule's). With
  // a mask-change gate at 0.3 every jump frame reads the material points (zero in a slide) and
  // the motion is lost, which is why the gate is off by default.
  for (bool gated : {false, true}) {
    Calibration cal;  // the default gate (off) unless `gated`
    cal.velocity_proxy = VelocityProxy::kVelocity;
    if (gated) cal.max_mask_change = 0.3;
    Runner run(cal);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Vector3d first = Eigen::Vector3d::Zero(), last = Eigen::Vector3d::Zero();
    int jumps = 0;
    for (int k = 0; k < 25; ++k) {
      RigidContactScene sc;
      sc.contact_centre_G = Eigen::Vector3d(-4.5e-3 + 1.5e-3 * (k / 4), 0.5e-3, 0.0);
      sc.radius_m = 3e-3;
      const SyntheticSensorFrames f = dsp_ref::render_rigid_contact(cal, sc);
      const VectorField still;  // zero-initialised: the gel does not move
      const SensorMotion m = run.frame(f.fz, still, still);
      ASSERT_TRUE(m.contact);
      // The sliding rule's centroid, from the contact points the detector built (nm → m).
      std::vector<dsp_ref::PointSample> points;
      for (std::size_t i = 0; i < run.cs->mask.v.size(); ++i) {
        if (run.cs->mask.v[i] == 0) continue;
        dsp_ref::PointSample p;
        p.q = Eigen::Vector3d(run.cs->x_nm.v[i], run.cs->y_nm.v[i], run.cs->z_nm.v[i]) * 1e-9;
        points.push_back(p);
      }
      const Eigen::Vector3d c = height_weighted_centroid(points);
      if (k == 0) {
        first = c;
        continue;
      }
      ASSERT_TRUE(m.translation_valid) << k;
      if (m.mask_change > 0.3) ++jumps;
      sum += m.translation * kDt;
      last = c;
    }
    ASSERT_EQ(jumps, 6);  // every fourth frame
    const Eigen::Vector3d whole(last.x() - first.x(), last.y() - first.y(), 0.0);
    EXPECT_NEAR(whole.x(), 9e-3, 2e-4);
    if (!gated) {
      // 1 nm positions and Q16 rounding: a few nm per frame at most.
      EXPECT_LT((sum - whole).norm(), 1e-7);
    } else {
      EXPECT_LT(std::abs(sum.x()), 1e-6);  // every 1.5 mm jump lost
    }
  }
}

TEST(Motion, SlidingCentroidIsWeightedByHeightSoAHysteresisTrailHardlyMovesIt) {
  // A patch slides 6 mm along x in one step (kVelocity, sliding rule). Where it was, f^z stays
  // at 1.5 τ_off: above the threshold that keeps last frame's cells in Ω, below the one that
  // admits new cells, the trail a slide leaves behind. Those cells stay in Ω, at a small
  // height. The plain mask centroid is pulled back by them; the height-weighted one, which the
  // sliding rule reads, much less.
  Calibration cal;
  cal.velocity_proxy = VelocityProxy::kVelocity;
  // The one-frame 6 mm step with its trail doubles Ω's area, which the area-ratio bound would
  // read as a contact forming (AContactFormingAtACorner… above); this test isolates the weighting.
  cal.max_mask_area_ratio = 1e4;
  RigidContactScene before, after;
  before.contact_centre_G = Eigen::Vector3d(-3e-3, 0.0, 0.0);
  after.contact_centre_G = Eigen::Vector3d(3e-3, 0.0, 0.0);
  const SyntheticSensorFrames f0 = dsp_ref::render_rigid_contact(cal, before);
  const SyntheticSensorFrames f1 = dsp_ref::render_rigid_contact(cal, after);
  ScalarField trail = f1.fz;
  const std::int32_t weak = to_q32<16>(1.5 * cal.contact_tau_off);
  int trail_cells = 0;
  for (std::size_t i = 0; i < trail.v.size(); ++i) {
    if (f0.fz.v[i] > to_q32<16>(cal.contact_tau_on) && f1.fz.v[i] < weak) {
      trail.v[i] = weak;
      ++trail_cells;
    }
  }
  ASSERT_GT(trail_cells, 30);
  const VectorField still;  // zero-initialised: the gel does not move
  Runner run(cal);
  const SensorMotion m0 = run.frame(f0.fz, still, still);
  const SensorMotion m1 = run.frame(trail, still, still);
  ASSERT_TRUE(m1.translation_valid);
  ASSERT_EQ(m1.translation_source, TranslationSource::kCentroid);
  // Truth: the patch moved 6 mm. The plain centroid reads little more than half of it.
  const double plain_error = std::abs((m1.centroid_m.x() - m0.centroid_m.x()) - 6e-3);
  const double weighted_error = std::abs(m1.translation.x() * kDt - 6e-3);
  std::printf("6 mm step with a trail: plain centroid error %.2f mm, weighted %.2f mm\n",
              plain_error * 1e3, weighted_error * 1e3);
  EXPECT_GT(plain_error, 2.5e-3);
  EXPECT_LT(weighted_error, 0.5 * plain_error) << weighted_error;
  // translation_point_m is the weighted centroid, on the patch side of the plain one.
  EXPECT_GT(m1.translation_point_m.x(), m1.centroid_m.x() + 1e-3);
}

TEST(Motion, DegenerateContactsAreFlaggedAndFinite) {
  // Flat contact (z ≡ 0): ω_x, ω_y unobservable from shear, ω_z still exact.
  Calibration cal;
  cal.height_gain_m = 0.0;
  RigidContactScene sc;
  sc.omega_G = Eigen::Vector3d(0.3, 0.3, 0.5);
  {
    Runner run(cal);
    const SensorMotion m = run.pair(dsp_ref::render_rigid_contact(cal, sc));
    EXPECT_FALSE(m.rotation_valid);
    EXPECT_EQ(m.solve.rank, 1);
    EXPECT_NEAR(m.omega.z(), 0.5, 1e-4);
    // With z = 0, Aᵀb has no ω_x, ω_y component: regularised to exactly 0.
    EXPECT_EQ(m.omega.x(), 0.0);
    EXPECT_EQ(m.omega.y(), 0.0);
    expect_finite(m);
  }
  // A single contact point (min area 1): two equations for three unknowns.
  Calibration one;
  one.contact_min_area_cells = 1;
  {
    Runner run(one);
    auto f = std::make_unique<SyntheticSensorFrames>(dsp_ref::render_rigid_contact(one, sc));
    f->fz.fill(0);
    f->fz(20, 15) = to_q32<16>(1.0);  // the filter spreads it; keep only the centre above τ_on
    Calibration c = one;
    c.contact_tau_on = c.contact_tau_off = 0.2;
    ASSERT_EQ(run.det->configure(c), Status::kOk);
    const SensorMotion m = run.pair(*f);
    EXPECT_EQ(m.points, 1);
    EXPECT_FALSE(m.rotation_valid);
    EXPECT_LE(m.solve.rank, 2);
    expect_finite(m);
  }
  // Collinear points on a flat strip: rank 1.
  {
    Runner run(cal);
    auto f = std::make_unique<SyntheticSensorFrames>(dsp_ref::render_rigid_contact(cal, sc));
    f->fz.fill(0);
    for (int gx = 5; gx < 35; ++gx) f->fz(gx, 15) = to_q32<16>(0.05);  // filter 0.025 on it
    const SensorMotion m = run.pair(*f);
    EXPECT_EQ(m.points, 28);
    EXPECT_FALSE(m.rotation_valid);
    EXPECT_EQ(m.solve.rank, 1);
    expect_finite(m);
  }
}

TEST(Motion, BadDtIsRejectedAndLeavesStateUntouched) {
  const Calibration cal;
  RigidContactScene sc;
  sc.t_G = Eigen::Vector3d(2e-3, 0.0, 0.0);
  const SyntheticSensorFrames f = dsp_ref::render_rigid_contact(cal, sc);
  Runner a(cal), b(cal);
  a.frame(f.fz, f.w_prev, f.shear_prev);
  b.frame(f.fz, f.w_prev, f.shear_prev);
  GridMask valid;
  valid.fill(1);
  for (double dt : {std::numeric_limits<double>::quiet_NaN(), 0.0, -kDt, 2.0,
                    std::numeric_limits<double>::infinity()}) {
    b.det->detect(f.fz, f.w_now, valid, *b.cs);
    SensorMotion out;
    out.omega.setConstant(7.0);
    EXPECT_EQ(b.me->update(*b.cs, f.shear_now, dt, out), Status::kBadArgument);
    EXPECT_FALSE(out.contact);
    EXPECT_EQ(out.omega, Eigen::Vector3d::Zero());
  }
  const SensorMotion ma = a.frame(f.fz, f.w_now, f.shear_now);
  const SensorMotion mb = b.frame(f.fz, f.w_now, f.shear_now);
  EXPECT_EQ(ma.translation, mb.translation);
  EXPECT_EQ(ma.omega, mb.omega);
  EXPECT_TRUE(mb.translation_valid);
}

}  // namespace
}  // namespace tacse3::dsp
