// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: equivariance (paper Sec. IV-E) of the joint method: the same object motion seen
// at shifted contact locations, or through rotated sensor mounts, gives the same twist in G.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <vector>

#include "tacse3/dsp/contact.hpp"
#include "tacse3/dsp/fusion.hpp"
#include "tacse3/dsp/motion.hpp"
#include "tacse3/dsp_ref/motion_ref.hpp"

namespace tacse3::dsp {
namespace {

constexpr double kDt = 1.0 / 120.0;
constexpr double kW = 30e-3;
constexpr double kPi = 3.14159265358979323846;

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

// The object motion used throughout: a general twist in G with t_z = 0 (the closing axis,
// unobservable by two parallel pads and reported as 0).
Vector6d object_twist() {
  Vector6d xi;
  xi << 0.3, -0.25, 0.4, 4e-3, -3e-3, 0.0;
  return xi;
}

// Contact centres (x, y) in G on the left and right pads, and the mount rotation about each
// sensor's normal (in-plane rotation of the sensor in its extrinsics).
struct Layout {
  Eigen::Vector2d left_xy, right_xy;
  double mount_angle = 0.0;
  VelocityProxy proxy = VelocityProxy::kVelocity;
};

FusedMotion observe(const Layout& s, const Vector6d& xi) {
  Calibration cal;
  cal.velocity_proxy = s.proxy;
  FusionConfig cfg;
  cfg.method = FusionMethod::kJoint;
  const Eigen::Matrix3d Rz =
      Eigen::AngleAxisd(s.mount_angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  cfg.extrinsics[0].R_GS = cfg.extrinsics[0].R_GS * Rz;
  cfg.extrinsics[1].R_GS = cfg.extrinsics[1].R_GS * Rz;
  SensorMotion m[2];
  for (int i = 0; i < 2; ++i) {
    const SensorExtrinsics& e = cfg.extrinsics[static_cast<std::size_t>(i)];
    dsp_ref::RigidContactScene sc;
    sc.R_GS = e.R_GS;
    sc.p_GS = e.p_GS(kW);
    const Eigen::Vector2d c = i == 0 ? s.left_xy : s.right_xy;
    sc.contact_centre_G = Eigen::Vector3d(c.x(), c.y(), sc.p_GS.z());
    sc.omega_G = xi.head<3>();
    sc.t_G = xi.tail<3>();
    const auto f =
        std::make_unique<dsp_ref::SyntheticSensorFrames>(dsp_ref::render_rigid_contact(cal, sc));
    m[i] = run_pad(cal, *f);
    EXPECT_GT(m[i].points, 50);
  }
  FusedMotion out;
  EXPECT_EQ(fuse(&m[0], &m[1], cfg, kW, out), Status::kOk);
  EXPECT_TRUE(out.valid);
  return out;
}

// Tolerances: ω from Q16 shear (≤ 2^-17 shear units per point) and nm positions: relative 2e-4;
// t from Q16 positions over one frame plus ω × (lever ~15 mm): 1e-6 m/s.
void expect_same_twist(const Vector6d& a, const Vector6d& b, const char* what) {
  EXPECT_LT((a.head<3>() - b.head<3>()).norm(), 2e-4 * b.head<3>().norm()) << what;
  EXPECT_LT((a.tail<3>() - b.tail<3>()).norm(), 1e-6) << what;
}

TEST(Equivariance, ShiftedContactLocationsGiveTheSameTwistInG) {
  const Vector6d xi = object_twist();
  const std::vector<Layout> layouts = {
      {{0.0, 0.0}, {0.0, 0.0}},
      {{4e-3, -3e-3}, {4e-3, -3e-3}},
      {{-6e-3, 2e-3}, {-6e-3, 2e-3}},
      // Not opposite each other: the two pads touch the object at unrelated places.
      {{3e-3, 0.0}, {-2e-3, 4e-3}},
      {{-5e-3, -4e-3}, {5e-3, 3e-3}},
  };
  const FusedMotion first = observe(layouts[0], xi);
  expect_same_twist(first.xi, xi, "truth");
  for (std::size_t i = 1; i < layouts.size(); ++i) {
    const FusedMotion f = observe(layouts[i], xi);
    expect_same_twist(f.xi, first.xi, "shifted contact");
    expect_same_twist(f.xi, xi, "truth");
  }
}

TEST(Equivariance, RotatedSensorMountGivesTheSameTwistInG) {
  const Vector6d xi = object_twist();
  const FusedMotion base = observe({{2e-3, 1e-3}, {2e-3, 1e-3}, 0.0}, xi);
  for (double deg : {30.0, 90.0, -45.0, 180.0}) {
    const FusedMotion f = observe({{2e-3, 1e-3}, {2e-3, 1e-3}, deg * kPi / 180.0}, xi);
    expect_same_twist(f.xi, base.xi, "rotated mount");
    expect_same_twist(f.xi, xi, "truth");
  }
}

TEST(Equivariance, HoldsInDisplacementModeToo) {
  const Vector6d xi = object_twist();
  Layout a{{0.0, 0.0}, {0.0, 0.0}, 0.0, VelocityProxy::kDisplacement};
  Layout b{{-4e-3, 3e-3}, {1e-3, -2e-3}, 60.0 * kPi / 180.0, VelocityProxy::kDisplacement};
  const FusedMotion fa = observe(a, xi), fb = observe(b, xi);
  expect_same_twist(fa.xi, xi, "truth");
  expect_same_twist(fb.xi, fa.xi, "displacement mode");
}

TEST(Equivariance, TwistTransformsWithTheObjectMotion) {
  // The estimate is tied to G, not to the images: rotating the object motion by a rotation Q
  // about G's z axis (a symmetry of the gripper) rotates the estimated twist by Q.
  const Vector6d xi = object_twist();
  const Eigen::Matrix3d Q = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Vector6d xq;
  xq << Q * xi.head<3>(), Q * xi.tail<3>();
  const Layout s{{1e-3, -1e-3}, {1e-3, -1e-3}};
  const FusedMotion f = observe(s, xi);
  // Same contact geometry rotated with Q.
  const Eigen::Vector2d cq = (Q * Eigen::Vector3d(1e-3, -1e-3, 0.0)).head<2>();
  const FusedMotion fq = observe({cq, cq}, xq);
  Vector6d rotated;
  rotated << Q * f.xi.head<3>(), Q * f.xi.tail<3>();
  expect_same_twist(fq.xi, rotated, "rotated motion");
}

}  // namespace
}  // namespace tacse3::dsp
