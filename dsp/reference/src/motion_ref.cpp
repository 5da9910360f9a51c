// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: brute-force stacked least squares and per-sensor motion in double.
#include "tacse3/dsp_ref/motion_ref.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "tacse3/dsp/fixed.hpp"
#include "tacse3/dsp/geometry.hpp"
#include "tacse3/dsp/motion.hpp"  // velocity_reads_anchor, planar_content

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
  detector_.configure(cal);
  release_.configure(cal);
  reset();
}

void MotionRef::reset() {
  const auto n = static_cast<std::size_t>(dsp::kGridCount);
  prev_mask_.assign(n, 0);
  anchor_.assign(n, 0);
  have_anchor_ = false;
  anchor_count_ = 0;
  prev_q_.assign(n, Eigen::Vector3d::Zero());
  prev_sx_.assign(n, 0.0);
  prev_sy_.assign(n, 0.0);
  have_prev_shear_ = false;
  release_.reset();
  detector_.reset();
}

SensorMotionRef MotionRef::update(const ContactSetRef& c, const std::vector<double>& shear_x,
                                  const std::vector<double>& shear_y, double dt,
                                  const SlipDecision* follow) {
  const auto n = static_cast<std::size_t>(dsp::kGridCount);
  const bool automatic = cal_.velocity_proxy == dsp::VelocityProxy::kAuto;
  // The releasing decision is followed in every mode, the slip decisions only in kAuto.
  const SlipDecision* const release_follow = follow;
  if (!automatic) follow = nullptr;
  SensorMotionRef out;
  if (follow != nullptr && follow->slipping != detector_.slipping()) {
    // The followed detector switched at the end of the previous frame: onset or exit (the
    // detector restarts, as dsp::MotionEstimator does).
    detector_.set_slipping(follow->slipping);
    if (!follow->slipping) {
      // dsp::MotionEstimator set its anchor to Ω at the end of the frame the slide ended.
      if (!release_follow->has_anchor &&
          std::find(prev_mask_.begin(), prev_mask_.end(), 1) != prev_mask_.end()) {
        anchor_ = prev_mask_;
        anchor_count_ = static_cast<int>(std::count(anchor_.begin(), anchor_.end(), 1));
        have_anchor_ = true;
      }
    }
  }
  int prev_count = 0, common = 0;
  Eigen::Vector3d sum_now = Eigen::Vector3d::Zero(), sum_prev = Eigen::Vector3d::Zero();
  // Height-weighted sums for the sliding rule's centroid (dsp::MotionEstimator's rule).
  Eigen::Vector3d zsum_now = Eigen::Vector3d::Zero(), zsum_prev = Eigen::Vector3d::Zero();
  double z_now = 0.0, z_prev = 0.0;
  Eigen::Vector3d sum_common = Eigen::Vector3d::Zero(),
                  sum_anchored_common = Eigen::Vector3d::Zero();
  int anchored_common = 0;
  // Per point: shear (velocity reading, over Ω and over Ω ∩ anchor), increment (displacement
  // reading).
  std::vector<PointSample> shear_pts, held_pts, incr_pts, anchored_pts;
  for (std::size_t i = 0; i < n; ++i) {
    if (prev_mask_[i] != 0) {
      ++prev_count;
      sum_prev += prev_q_[i];
      zsum_prev += prev_q_[i].z() * prev_q_[i];
      z_prev += prev_q_[i].z();
    }
    if (c.mask[i] == 0) continue;
    PointSample s;
    s.q = c.q[i];
    const Eigen::Vector3d sv(shear_x[i], shear_y[i], 0.0);
    // Increments only for cells also in the previous Ω (dsp::MotionEstimator's rule).
    const bool stayed = prev_mask_[i] != 0;
    Eigen::Vector3d dv = Eigen::Vector3d::Zero();
    if (have_prev_shear_ && stayed)
      dv = Eigen::Vector3d(shear_x[i] - prev_sx_[i], shear_y[i] - prev_sy_[i], 0.0);
    s.v = sv;
    shear_pts.push_back(s);
    const bool anchored = have_anchor_ && anchor_[i] != 0;
    if (anchored) held_pts.push_back(s);
    if (stayed) {
      s.v = dv;
      incr_pts.push_back(s);
      if (anchored) anchored_pts.push_back(s);
    }
    sum_now += s.q;
    zsum_now += s.q.z() * s.q;
    z_now += s.q.z();
    if (prev_mask_[i] != 0) {
      ++common;
      sum_common += s.q - prev_q_[i];
      if (anchored) {
        ++anchored_common;
        sum_anchored_common += s.q - prev_q_[i];
      }
    }
  }
  out.points = static_cast<int>(shear_pts.size());
  out.contact = out.points > 0;
  auto solve = [&](const std::vector<PointSample>& pts) {
    const StackedSystem sys = stack_shear_rows(pts);
    const Eigen::Matrix3d AtA = sys.A.transpose() * sys.A;
    const double lambda_floor =
        static_cast<double>(pts.size()) * cal_.solve_lever_floor_m * cal_.solve_lever_floor_m;
    return solve_stacked(sys, cal_.solve_lambda_rel * AtA.trace() / 3.0 + lambda_floor);
  };

  // Normal load Σ z over Ω, smoothed like X, and its relative rate of fall ρ_L (every mode).
  // L_{t−1} is z_prev (Σ z over the previous mask); a contact's first frame starts the EMA.
  if (out.points > 0) out.load_drop_rate = release_.update(z_now, prev_count > 0, z_prev, dt);
  const bool unloading_fast = release_.unloading_fast(out.load_drop_rate);

  // Planar rigid-body content of the shear read as a contact displacement (brute force).
  auto planar = [&](const std::vector<PointSample>& pts) -> Eigen::Vector3d {
    if (pts.empty()) return Eigen::Vector3d::Zero();
    const double k = static_cast<double>(pts.size());
    Eigen::Vector3d cen = Eigen::Vector3d::Zero();
    for (const auto& p : pts) cen += p.q;
    cen /= k;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    double torque = 0.0, inertia = 0.0;
    for (const auto& p : pts) {
      const Eigen::Vector2d r = (p.q - cen).head<2>();
      const Eigen::Vector2d v = cal_.c_displacement * p.v.head<2>();
      mean += v;
      torque += r.x() * v.y() - r.y() * v.x();
      inertia += r.squaredNorm();
    }
    mean /= k;
    return {inertia > 0.0 ? torque / std::sqrt(k * inertia) : 0.0, mean.x(), mean.y()};
  };
  const bool sticking =
      automatic ? !detector_.slipping() : cal_.velocity_proxy == dsp::VelocityProxy::kDisplacement;
  bool slide_ended = false;
  const Eigen::Vector3d shear_content = planar(shear_pts);
  const double anchor_shift = shear_content.norm();  // |X| unsmoothed, for the anchor rule
  // The velocity proxy's region (dsp::kVelocityAnchorDragRatio's rule): Ω ∩ anchor while the
  // shear is a drag and Ω and the anchor share enough cells; the followed decision if given.
  // A followed choice the reference's own anchor cannot serve (its anchor differs) reads Ω.
  const bool own_rule = dsp::velocity_reads_anchor(
      shear_content, static_cast<std::int64_t>(held_pts.size()), anchor_count_, out.points);
  out.velocity_anchored =
      !held_pts.empty() &&
      (release_follow != nullptr && release_follow->has_anchor ? release_follow->velocity_anchored
                                                               : own_rule);
  if (automatic) {
    if (out.points == 0) {
      detector_.reset();
    } else {
      // X over Ω, its change over Ω_t ∩ Ω_{t−1} (the increments); the shared detector smooths
      // and decides, or only smooths while the decisions are followed.
      const Eigen::Vector3d step = planar(incr_pts);
      if (follow != nullptr) {
        detector_.observe(shear_content, step, out.load_drop_rate, dt);
        // Transitions come from the followed decisions (next frame's `slipping`).
        out.slip_onset = follow->slip_onset;
        if (!detector_.slipping() && follow->stick_confirmed) out.stick_confirmed = true;
      } else {
        const dsp::SlipDetector::Step st =
            detector_.update(shear_content, step, out.load_drop_rate, dt);
        out.slip_onset = st.onset;
        out.stick_confirmed = st.confirmed;
        slide_ended = st.ended;
      }
      const dsp::SlipDetector::Features& f = detector_.features();
      out.shear_shift_m = f.shift_m;
      out.shear_rate_m_s = f.rate_m_s;
      out.slip_relax_rate = f.relax_rate;
    }
    out.slipping = !sticking;
  }
  // A sticking contact losing its load faster than release_load_rate is being let go: its
  // chosen reading is dropped (dsp::MotionEstimator's rule; the followed decision if given).
  out.releasing = release_follow != nullptr ? release_follow->releasing
                                            : sticking && out.points > 0 && unloading_fast;
  out.proxy_valid = (!sticking || have_prev_shear_) && !out.releasing;
  out.velocity_differs = automatic && sticking;
  for (auto& p : shear_pts) p.v *= cal_.c_velocity;
  for (auto& p : held_pts) p.v *= cal_.c_velocity;
  const std::vector<PointSample>& velocity_pts = out.velocity_anchored ? held_pts : shear_pts;
  if (sticking) {
    // Increments over the anchored patch (dsp::MotionEstimator's rule), Ω_t ∩ Ω_{t−1} if none.
    out.samples = anchored_pts.empty() ? incr_pts : anchored_pts;
    for (auto& p : out.samples) p.v *= have_prev_shear_ ? cal_.c_displacement / dt : 0.0;
  } else {
    out.samples = velocity_pts;
  }

  const Eigen::Vector3d tscale(cal_.translation_scale[0], cal_.translation_scale[1],
                               cal_.translation_scale[2]);
  // Per-axis rotation scales of the velocity proxy, and of the displacement proxy (× ratio).
  const Eigen::Vector3d wscale(cal_.rotation_scale[0], cal_.rotation_scale[1],
                               cal_.rotation_scale[2]);
  out.rotation_scale =
      sticking ? Eigen::Vector3d(wscale.cwiseProduct(Eigen::Vector3d(
                     cal_.displacement_rotation_ratio[0], cal_.displacement_rotation_ratio[1],
                     cal_.displacement_rotation_ratio[2])))
               : wscale;
  if (out.points > 0) out.centroid = sum_now / out.points;
  // The sliding rule's centroid, weighted by the points' height (dsp::MotionEstimator's rule).
  const bool weighted = z_now > 0.0 && z_prev > 0.0;
  const Eigen::Vector3d slide_point = weighted ? Eigen::Vector3d(zsum_now / z_now) : out.centroid;
  out.translation_point = out.centroid;
  if (out.points > 0 && prev_count > 0) {
    const int uni = out.points + prev_count - common;
    const double change = 1.0 - static_cast<double>(common) / uni;
    Eigen::Vector3d slide = Eigen::Vector3d::Zero(), common_d = Eigen::Vector3d::Zero();
    int slide_source = 0;
    if (common > 0) common_d = sum_common / common;
    if (common == 0) {
      // No cell in both masks: unrelated contacts, no translation (dsp::MotionEstimator's rule).
    } else if (change <= cal_.max_mask_change &&
               std::max(out.points, prev_count) <=
                   cal_.max_mask_area_ratio * std::min(out.points, prev_count)) {
      // A forming or vanishing contact (area ratio above the bound) reads the common points.
      slide = weighted ? Eigen::Vector3d(zsum_now / z_now - zsum_prev / z_prev)
                       : Eigen::Vector3d(sum_now / out.points - sum_prev / prev_count);
      slide_source = 1;
    } else {
      slide = common_d;
      slide_source = 2;
    }
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    if (sticking && common > 0) {
      // The anchored patch's common points if any (dsp::MotionEstimator's rule).
      d = anchored_common > 0 ? Eigen::Vector3d(sum_anchored_common / anchored_common) : common_d;
      out.translation_source = 2;
      out.translation_valid = true;
    } else if (slide_source != 0) {
      d = slide;
      out.translation_source = slide_source;
      out.translation_valid = true;
      if (slide_source == 1) out.translation_point = slide_point;
    }
    if (out.releasing) {
      d.setZero();
      out.translation_valid = false;
      out.translation_source = 0;
    }
    d.z() = 0.0;
    out.translation = tscale.cwiseProduct(d / dt);
    if (out.velocity_differs && slide_source != 0) {
      slide.z() = 0.0;
      out.velocity_translation = tscale.cwiseProduct(slide / dt);
      out.velocity_translation_valid = true;
      out.velocity_translation_point = slide_source == 1 ? slide_point : out.centroid;
    }
  }
  if (!out.samples.empty() && !out.releasing) {
    out.omega = out.rotation_scale.cwiseProduct(solve(out.samples));
  }
  if (out.velocity_differs) {
    out.velocity_samples = velocity_pts;
    out.velocity_rotation_scale = wscale;
    if (out.points > 0) out.velocity_omega = wscale.cwiseProduct(solve(velocity_pts));
  } else {
    out.velocity_samples = out.samples;
    out.velocity_rotation_scale = out.rotation_scale;
    out.velocity_omega = out.omega;
    out.velocity_translation = out.translation;
    out.velocity_translation_valid = out.translation_valid;
    out.velocity_translation_point = out.translation_point;
  }
  if (out.points == 0) {
    have_anchor_ = false;
  } else if (release_follow != nullptr && release_follow->has_anchor
                 ? release_follow->anchor_set
                 : (!have_anchor_ || slide_ended || anchor_shift <= cal_.slip_min_shift_m)) {
    anchor_ = c.mask;
    anchor_count_ = out.points;
    have_anchor_ = true;
    out.anchor_set = true;
  }
  prev_mask_ = c.mask;
  prev_q_ = c.q;
  prev_sx_ = shear_x;
  prev_sy_ = shear_y;
  have_prev_shear_ = true;
  return out;
}

dsp::Vector6d SlipPaybackRef::update(const dsp::Vector6d& chosen, const dsp::Vector6d& velocity,
                                     bool differs, bool contact, bool onset, bool confirmed,
                                     bool gap, double dt) {
  if (!contact || gap) {
    deficit_.setZero();
    left_ = 0;
  }
  if (!contact) return chosen;
  if (differs) deficit_ += (velocity - chosen) * dt;
  if (confirmed && left_ == 0) {  // a payback under way is not cut (dsp::SlipPayback)
    deficit_.setZero();
    return chosen;
  }
  if (onset) left_ = std::max(1, catchup_frames_);
  if (left_ == 0) return chosen;
  const dsp::Vector6d pay = deficit_ / static_cast<double>(left_);
  deficit_ -= pay;
  --left_;
  return chosen + pay / dt;
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
