// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: brute-force stacked least squares and per-sensor motion in double.
#include "tacse3/dsp_ref/motion_ref.hpp"

#include <Eigen/Dense>
#include <cmath>

#include "tacse3/dsp/fixed.hpp"
#include "tacse3/dsp/geometry.hpp"

namespace tacse3::dsp_ref {
namespace {

// Any orthonormal tangent basis of n (the LS is invariant to its choice).
void tangent_basis(const Eigen::Vector3d& n, Eigen::Vector3d& e1, Eigen::Vector3d& e2) {
  const Eigen::Vector3d a =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  e1 = (a - a.dot(n) * n).normalized();
  e2 = n.cross(e1);
}

}  // namespace

StackedSystem stack_shear_rows(const std::vector<PointSample>& pts) {
  StackedSystem s;
  const auto n = static_cast<Eigen::Index>(pts.size());
  s.A.resize(2 * n, 3);
  s.b.resize(2 * n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const PointSample& p = pts[static_cast<std::size_t>(i)];
    Eigen::Vector3d e[2];
    if (p.normal.isApprox(Eigen::Vector3d::UnitZ())) {
      e[0] = Eigen::Vector3d::UnitX();  // the paper's rows exactly
      e[1] = Eigen::Vector3d::UnitY();
    } else {
      tangent_basis(p.normal.normalized(), e[0], e[1]);
    }
    for (int k = 0; k < 2; ++k) {
      // e·(ω × q) = ω·(q × e)
      s.A.row(2 * i + k) = p.q.cross(e[k]).transpose();
      s.b(2 * i + k) = e[k].dot(p.v);
    }
  }
  return s;
}

Eigen::Vector3d solve_stacked(const StackedSystem& s, double lambda) {
  const Eigen::Index m = s.A.rows();
  Eigen::MatrixXd A(m + 3, 3);
  Eigen::VectorXd b(m + 3);
  A.topRows(m) = s.A;
  A.bottomRows(3) = std::sqrt(std::max(lambda, 0.0)) * Eigen::Matrix3d::Identity();
  b.head(m) = s.b;
  b.tail(3).setZero();
  return A.colPivHouseholderQr().solve(b);
}

Eigen::Vector3d centroid(const std::vector<PointSample>& pts) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : pts) c += p.q;
  return pts.empty() ? c : Eigen::Vector3d(c / static_cast<double>(pts.size()));
}

std::vector<PointSample> shifted(const std::vector<PointSample>& pts, const Eigen::Vector3d& c) {
  std::vector<PointSample> out = pts;
  for (auto& p : out) p.q -= c;
  return out;
}

MotionRef::MotionRef(const dsp::Calibration& cal) : cal_(cal) {
  reset();
}

void MotionRef::reset() {
  const auto n = static_cast<std::size_t>(dsp::kGridCount);
  prev_mask_.assign(n, 0);
  prev_q_.assign(n, Eigen::Vector3d::Zero());
  prev_sx_.assign(n, 0.0);
  prev_sy_.assign(n, 0.0);
  have_prev_shear_ = false;
}

SensorMotionRef MotionRef::update(const ContactSetRef& c, const std::vector<double>& shear_x,
                                  const std::vector<double>& shear_y, double dt) {
  const auto n = static_cast<std::size_t>(dsp::kGridCount);
  const bool disp = cal_.velocity_proxy == dsp::VelocityProxy::kDisplacement;
  SensorMotionRef out;
  out.proxy_valid = !disp || have_prev_shear_;
  int prev_count = 0, common = 0;
  Eigen::Vector3d sum_now = Eigen::Vector3d::Zero(), sum_prev = Eigen::Vector3d::Zero();
  Eigen::Vector3d sum_common = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    if (prev_mask_[i] != 0) {
      ++prev_count;
      sum_prev += prev_q_[i];
    }
    if (c.mask[i] == 0) continue;
    PointSample s;
    s.q = c.q[i];
    if (!disp) {
      s.v = cal_.c_velocity * Eigen::Vector3d(shear_x[i], shear_y[i], 0.0);
    } else if (have_prev_shear_) {
      s.v = cal_.c_displacement / dt *
            Eigen::Vector3d(shear_x[i] - prev_sx_[i], shear_y[i] - prev_sy_[i], 0.0);
    }
    out.samples.push_back(s);
    sum_now += s.q;
    if (prev_mask_[i] != 0) {
      ++common;
      sum_common += s.q - prev_q_[i];
    }
  }
  out.points = static_cast<int>(out.samples.size());
  out.contact = out.points > 0;
  const Eigen::Vector3d tscale(cal_.translation_scale[0], cal_.translation_scale[1],
                               cal_.translation_scale[2]);
  const Eigen::Vector3d wscale(cal_.rotation_scale[0], cal_.rotation_scale[1],
                               cal_.rotation_scale[2]);
  if (out.points > 0 && prev_count > 0) {
    const int uni = out.points + prev_count - common;
    const double change = 1.0 - static_cast<double>(common) / uni;
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    const bool sticking = cal_.velocity_proxy == dsp::VelocityProxy::kDisplacement;
    if (sticking && common > 0) {
      d = sum_common / common;
      out.translation_source = 2;
      out.translation_valid = true;
    } else if (change <= cal_.max_mask_change) {
      d = sum_now / out.points - sum_prev / prev_count;
      out.translation_source = 1;
      out.translation_valid = true;
    } else if (common > 0) {
      d = sum_common / common;
      out.translation_source = 2;
      out.translation_valid = true;
    }
    d.z() = 0.0;
    out.translation = tscale.cwiseProduct(d / dt);
  }
  if (out.points > 0) {
    out.centroid = sum_now / out.points;
    const StackedSystem sys = stack_shear_rows(out.samples);
    const Eigen::Matrix3d AtA = sys.A.transpose() * sys.A;
    const double lambda = cal_.solve_lambda_rel * AtA.trace() / 3.0 +
                          out.points * cal_.solve_lever_floor_m * cal_.solve_lever_floor_m;
    out.omega = wscale.cwiseProduct(solve_stacked(sys, lambda));
  }
  prev_mask_ = c.mask;
  prev_q_ = c.q;
  prev_sx_ = shear_x;
  prev_sy_ = shear_y;
  have_prev_shear_ = true;
  return out;
}

SyntheticSensorFrames render_rigid_contact(const dsp::Calibration& cal,
                                           const RigidContactScene& sc) {
  using dsp::kGridHeight;
  using dsp::kGridWidth;
  SyntheticSensorFrames f;
  f.valid.fill(1);
  const double px = cal.pixel_pitch_m, py = cal.pixel_pitch_m * cal.pixel_aspect_y;
  const Eigen::Vector3d c_S = sc.R_GS.transpose() * (sc.contact_centre_G - sc.p_GS);
  std::vector<double> fz(static_cast<std::size_t>(dsp::kGridCount), 0.0);
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const double x = (dsp::grid_sensor_x(gx) - dsp::kPadCentreX) * px;
      const double y = (dsp::grid_sensor_y(gy) - dsp::kPadCentreY) * py;
      const double r2 = ((x - c_S.x()) * (x - c_S.x()) + (y - c_S.y()) * (y - c_S.y())) /
                        (sc.radius_m * sc.radius_m);
      const double v = r2 < 1.0 ? sc.peak_fz * (1.0 - r2) : 0.0;
      f.fz(gx, gy) = dsp::to_q32<16>(v);
      fz[static_cast<std::size_t>(gy * kGridWidth + gx)] = dsp::from_q<16>(f.fz(gx, gy));
    }
  }
  // The contact points exactly as the detector builds them (w = 0 at frame t).
  dsp::VectorField zero;
  ContactDetectorRef det(cal);
  const ContactSetRef cs = det.detect(fz, zero, f.valid);
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const auto i = static_cast<std::size_t>(gy * kGridWidth + gx);
      // Every grid point moves rigidly; off-contact points carry z = 0.
      const Eigen::Vector3d q_S =
          cs.mask[i] != 0 ? cs.q[i]
                          : Eigen::Vector3d((dsp::grid_sensor_x(gx) - dsp::kPadCentreX) * px,
                                            (dsp::grid_sensor_y(gy) - dsp::kPadCentreY) * py, 0.0);
      const Eigen::Vector3d q_G = sc.R_GS * q_S + sc.p_GS;
      const Eigen::Vector3d v_G = sc.omega_G.cross(q_G) + sc.t_G;
      Eigen::Vector3d v_S = sc.R_GS.transpose() * v_G;
      v_S.z() = 0.0;
      // Positions at t−1 in working px (1 working px = 2 sensor px).
      f.w_prev.x(gx, gy) = dsp::to_q32<16>(-v_S.x() * sc.dt / (dsp::kWorkScale * px));
      f.w_prev.y(gx, gy) = dsp::to_q32<16>(-v_S.y() * sc.dt / (dsp::kWorkScale * py));
      if (cal.velocity_proxy == dsp::VelocityProxy::kVelocity) {
        f.shear_now.x(gx, gy) = dsp::to_q32<16>(v_S.x() / cal.c_velocity);
        f.shear_now.y(gx, gy) = dsp::to_q32<16>(v_S.y() / cal.c_velocity);
        f.shear_prev.x(gx, gy) = f.shear_now.x(gx, gy);
        f.shear_prev.y(gx, gy) = f.shear_now.y(gx, gy);
      } else {
        f.shear_now.x(gx, gy) = dsp::to_q32<16>(v_S.x() * sc.dt / cal.c_displacement);
        f.shear_now.y(gx, gy) = dsp::to_q32<16>(v_S.y() * sc.dt / cal.c_displacement);
      }
      if (cs.mask[i] != 0) {
        PointSample s;
        s.q = q_G;
        s.v = sc.R_GS * v_S;
        s.normal = sc.R_GS * Eigen::Vector3d::UnitZ();
        f.points_G.push_back(s);
      }
    }
  }
  return f;
}

}  // namespace tacse3::dsp_ref
