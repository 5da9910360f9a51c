// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: per-sensor motion: contact-centroid translation, velocity proxy, int64 moments, ω.
#include "tacse3/dsp/motion.hpp"

#include <Eigen/Geometry>  // cross products
#include <algorithm>
#include <cmath>

#include "tacse3/dsp/fixed.hpp"

namespace tacse3::dsp {
namespace {

constexpr double kNm = 1e-9;
constexpr double kQ16Lsb = 1.0 / 65536.0;

std::int64_t clamp64(std::int64_t v, std::int64_t lo, std::int64_t hi) noexcept {
  return v < lo ? lo : (v > hi ? hi : v);
}
std::int32_t clamp_proxy(std::int64_t v) noexcept {
  return static_cast<std::int32_t>(clamp64(v, -kMaxProxyQ16, kMaxProxyQ16));
}
// ContactDetector already bounds the points; re-clamping here keeps the int64 moment bounds
// true for any ContactSet a caller may build by hand.
constexpr std::int64_t kMaxZNm = (std::int64_t{1} << 24) - 1;

// Σ ṽ and Σ q_a ṽ_b of one proxy over Ω (the q sums are shared by every proxy).
struct ProxySums {
  std::int64_t svx = 0, svy = 0, sx_vy = 0, sy_vx = 0, sz_vx = 0, sz_vy = 0, svv = 0;
  void add(std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t vx,
           std::int64_t vy) noexcept {
    svx += vx;
    svy += vy;
    sx_vy += x * vy;
    sy_vx += y * vx;
    sz_vx += z * vx;
    sz_vy += z * vy;
    svv += vx * vx + vy * vy;
  }
  void add(const ProxySums& o) noexcept {
    svx += o.svx;
    svy += o.svy;
    sx_vy += o.sx_vy;
    sy_vx += o.sy_vx;
    sz_vx += o.sz_vx;
    sz_vy += o.sz_vy;
    svv += o.svv;
  }
  void store(ContactMoments& m) const noexcept {
    m.svx = svx;
    m.svy = svy;
    m.sx_vy = sx_vy;
    m.sy_vx = sy_vx;
    m.sz_vx = sz_vx;
    m.sz_vy = sz_vy;
    m.svv = svv;
  }
};

}  // namespace

Eigen::Vector3d planar_content(const ContactMoments& m, double scale) noexcept {
  if (m.n <= 0) return Eigen::Vector3d::Zero();
  const double n = static_cast<double>(m.n);
  const double cx = static_cast<double>(m.sx) / n * kNm, cy = static_cast<double>(m.sy) / n * kNm;
  const double tx = static_cast<double>(m.svx) / n * scale;
  const double ty = static_cast<double>(m.svy) / n * scale;
  // Σ (r × ṽ)_z about the centroid and Σ |r|² in the pad plane, r = q − c.
  const double torque =
      (static_cast<double>(m.sx_vy) - static_cast<double>(m.sy_vx)) * kNm * scale -
      n * (cx * ty - cy * tx);
  const double inertia = (static_cast<double>(m.sxx) + static_cast<double>(m.syy)) * kNm * kNm -
                         n * (cx * cx + cy * cy);
  const double turn = inertia > 0.0 ? torque / std::sqrt(n * inertia) : 0.0;
  return Eigen::Vector3d(turn, tx, ty);
}

namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& a) noexcept {
  Eigen::Matrix3d m;
  m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return m;
}

}  // namespace

MomentSums to_metric(const ContactMoments& m, double proxy_scale) noexcept {
  MomentSums r;
  r.n = static_cast<double>(m.n);
  r.s1 = Eigen::Vector3d(static_cast<double>(m.sx), static_cast<double>(m.sy),
                         static_cast<double>(m.sz)) *
         kNm;
  const double sxx = static_cast<double>(m.sxx), sxy = static_cast<double>(m.sxy);
  const double sxz = static_cast<double>(m.sxz), syy = static_cast<double>(m.syy);
  const double syz = static_cast<double>(m.syz), szz = static_cast<double>(m.szz);
  r.s2 << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
  r.s2 *= kNm * kNm;
  r.sv = Eigen::Vector3d(static_cast<double>(m.svx), static_cast<double>(m.svy), 0.0) * proxy_scale;
  // q × ṽ with ṽ_z = 0: (−q_z ṽ_y, q_z ṽ_x, q_x ṽ_y − q_y ṽ_x).
  r.sqxv = Eigen::Vector3d(-static_cast<double>(m.sz_vy), static_cast<double>(m.sz_vx),
                           static_cast<double>(m.sx_vy) - static_cast<double>(m.sy_vx)) *
           (kNm * proxy_scale);
  r.svv = static_cast<double>(m.svv) * proxy_scale * proxy_scale;
  r.normal = Eigen::Vector3d::UnitZ();
  return r;
}

MomentSums rigid_transform(const MomentSums& m, const Eigen::Matrix3d& R,
                           const Eigen::Vector3d& p) noexcept {
  MomentSums r;
  r.n = m.n;
  const Eigen::Vector3d Rs1 = R * m.s1;
  r.s1 = Rs1 + m.n * p;
  r.s2 = R * m.s2 * R.transpose() + Rs1 * p.transpose() + p * Rs1.transpose() +
         m.n * (p * p.transpose());
  r.sv = R * m.sv;
  r.sqxv = R * m.sqxv + p.cross(r.sv);
  r.svv = m.svv;
  r.normal = R * m.normal;
  return r;
}

void add_normal_equations(const MomentSums& m, Eigen::Matrix3d& AtA,
                          Eigen::Vector3d& Atb) noexcept {
  // Σ_i [q_i]×ᵀ P [q_i]× with P = I − n nᵀ, written with the second moment only.
  const Eigen::Matrix3d N = skew(m.normal);
  AtA += m.s2.trace() * Eigen::Matrix3d::Identity() - m.s2 - N * m.s2 * N.transpose();
  // Aᵀb = Σ −[q]×ᵀ P ṽ = Σ q × ṽ, since Pṽ = ṽ for a tangential proxy.
  Atb += m.sqxv;
}

bool velocity_reads_anchor(const Eigen::Vector3d& shear_content, std::int64_t held,
                           std::int64_t anchor_cells, std::int64_t contact_cells) noexcept {
  // The ratio test compares two parts in the same units (strict, so a shear-free frame reads
  // Ω); the overlap test is in double, exact for cell counts.
  const bool drag =
      shear_content.tail<2>().norm() > kVelocityAnchorDragRatio * std::abs(shear_content.x());
  const auto smaller_set = static_cast<double>(std::min(anchor_cells, contact_cells));
  return drag && held > 0 && static_cast<double>(held) >= kVelocityAnchorMinOverlap * smaller_set;
}

SensorMotion velocity_reading(const SensorMotion& m) noexcept {
  SensorMotion v = m;
  if (!m.velocity_differs) return v;
  v.moments = m.velocity_moments;
  v.proxy_scale = m.velocity_proxy_scale;
  v.rotation_scale = m.velocity_rotation_scale;
  v.proxy_valid = m.contact;  // the velocity proxy needs no previous frame
  v.omega = m.velocity_omega;
  v.solve = m.velocity_solve;
  v.rotation_valid = v.proxy_valid && m.velocity_solve.valid;
  v.translation = m.velocity_translation;
  v.translation_valid = m.velocity_translation_valid;
  v.translation_point_m = m.velocity_translation_point_m;
  v.velocity_differs = false;
  return v;
}

MotionEstimator::MotionEstimator() noexcept {
  (void)configure(Calibration{});
  reset();
}

Status MotionEstimator::configure(const Calibration& cal) noexcept {
  const Status s = validate(cal);
  if (s != Status::kOk) return s;
  const bool was_auto = mode_ == VelocityProxy::kAuto;
  mode_ = cal.velocity_proxy;
  c_velocity_ = cal.c_velocity;
  c_displacement_ = cal.c_displacement;
  max_mask_change_ = cal.max_mask_change;
  max_mask_area_ratio_ = cal.max_mask_area_ratio;
  rotation_scale_ =
      Eigen::Vector3d(cal.rotation_scale[0], cal.rotation_scale[1], cal.rotation_scale[2]);
  displacement_rotation_scale_ = rotation_scale_.cwiseProduct(
      Eigen::Vector3d(cal.displacement_rotation_ratio[0], cal.displacement_rotation_ratio[1],
                      cal.displacement_rotation_ratio[2]));
  translation_scale_ =
      Eigen::Vector3d(cal.translation_scale[0], cal.translation_scale[1], cal.translation_scale[2]);
  solve_options_.lambda_rel = cal.solve_lambda_rel;
  solve_options_.lambda_abs = 0.0;
  solve_options_.rcond_min = cal.solve_rcond_min;
  lever_floor_m_ = cal.solve_lever_floor_m;
  min_shift_m_ = cal.slip_min_shift_m;
  detector_.configure(cal);
  release_.configure(cal);
  // Entering or leaving kAuto starts the detector afresh.
  if (was_auto != (mode_ == VelocityProxy::kAuto)) detector_.reset();
  return Status::kOk;
}

void MotionEstimator::reset() noexcept {
  anchor_mask_.fill(0);
  have_anchor_ = false;
  anchor_count_ = 0;
  restart();
}

void MotionEstimator::restart() noexcept {
  // A slide in progress may end during the gap, where its end (which re-anchors) is never seen:
  // the patch anchored before the slide is stale, so the next frame anchors its own Ω.
  if (detector_.slipping()) have_anchor_ = false;
  prev_mask_.fill(0);
  prev_x_nm_.fill(0);
  prev_y_nm_.fill(0);
  prev_count_ = 0;
  prev_sx_ = 0;
  prev_sy_ = 0;
  prev_sz_ = 0;
  prev_sxz_ = 0;
  prev_syz_ = 0;
  prev_shear_.x.fill(0);
  prev_shear_.y.fill(0);
  have_prev_shear_ = false;
  release_.reset();
  detector_.reset();
}

namespace {

// Mean displacement (m) of n material points from their summed steps (nm); 0 for none.
Eigen::Vector2d mean_step(std::int64_t dx, std::int64_t dy, std::int64_t n) noexcept {
  return n > 0 ? Eigen::Vector2d(Eigen::Vector2d(static_cast<double>(dx), static_cast<double>(dy)) /
                                 static_cast<double>(n) * kNm)
               : Eigen::Vector2d::Zero();
}

}  // namespace

// One pass over Ω: moments (Eq. twist_ls sufficient statistics) of the shear (velocity proxy)
// and of its increment (displacement proxy), and the bookkeeping of the translation rules
// (intersection with the previous mask).
// m: every cell of Ω_t (translation, shear). Increments only over the cells also in Ω_{t−1}: a
// cell that (re-)enters Ω was usually not tracked by the flow while it was out, holds a stale
// shear, and its first increment would be the whole catch-up at the patch rim, read as rotation.
// held: the cells of Ω in the anchor (the velocity proxy's region while the shear is a drag).
MotionEstimator::Pass MotionEstimator::gather(const ContactSet& contact,
                                              const VectorField& shear) const noexcept {
  Pass p;
  ContactMoments m_stayed, m_anchored;
  ProxySums sum_shear, sum_increment, sum_anchored, sum_held;
  const auto add_point = [](ContactMoments& c, std::int64_t x, std::int64_t y, std::int64_t z) {
    ++c.n;
    c.sx += x;
    c.sy += y;
    c.sz += z;
    c.sxx += x * x;
    c.sxy += x * y;
    c.sxz += x * z;
    c.syy += y * y;
    c.syz += y * z;
    c.szz += z * z;
  };
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    if (contact.mask.v[i] == 0) continue;
    const std::int64_t x = clamp64(contact.x_nm.v[i], -kMaxPointNm, kMaxPointNm);
    const std::int64_t y = clamp64(contact.y_nm.v[i], -kMaxPointNm, kMaxPointNm);
    const std::int64_t z = clamp64(contact.z_nm.v[i], 0, kMaxZNm);
    const std::int64_t sx = clamp_proxy(shear.x.v[i]);
    const std::int64_t sy = clamp_proxy(shear.y.v[i]);
    const bool stayed = prev_mask_.v[i] != 0;
    add_point(p.m, x, y, z);
    sum_shear.add(x, y, z, sx, sy);
    const bool anchored = have_anchor_ && anchor_mask_.v[i] != 0;
    if (anchored) {
      add_point(p.held, x, y, z);
      sum_held.add(x, y, z, sx, sy);
    }
    if (!stayed) continue;
    std::int64_t dx = 0, dy = 0;
    if (have_prev_shear_) {
      dx = clamp_proxy(static_cast<std::int64_t>(shear.x.v[i]) - prev_shear_.x.v[i]);
      dy = clamp_proxy(static_cast<std::int64_t>(shear.y.v[i]) - prev_shear_.y.v[i]);
    }
    add_point(m_stayed, x, y, z);
    sum_increment.add(x, y, z, dx, dy);
    if (anchored) {
      add_point(m_anchored, x, y, z);
      sum_anchored.add(x, y, z, dx, dy);
    }
    const std::int64_t step_x = x - clamp64(prev_x_nm_.v[i], -kMaxPointNm, kMaxPointNm);
    const std::int64_t step_y = y - clamp64(prev_y_nm_.v[i], -kMaxPointNm, kMaxPointNm);
    ++p.common;
    p.common_dx += step_x;
    p.common_dy += step_y;
    if (anchored) {
      ++p.anchored_common;
      p.anchored_dx += step_x;
      p.anchored_dy += step_y;
    }
  }
  // The proxies' moments: the shear over Ω (velocity) and its increment over Ω_t ∩ Ω_{t−1}.
  p.shear = p.m;
  sum_shear.store(p.shear);
  p.increment = m_stayed;
  sum_increment.store(p.increment);
  p.anchored_increment = m_anchored;
  sum_anchored.store(p.anchored_increment);
  sum_held.store(p.held);
  return p;
}

// kAuto: the stick/slip detector on the rigid-body content of the shear and its increment.
// Returns whether this frame reads the displacement proxy: the regime decided up to the previous
// frame. Sets *slide_ended when the detector saw a slide end in this frame.
bool MotionEstimator::decide_proxy(const Pass& p, const Eigen::Vector3d& shear_content, double dt_s,
                                   bool* slide_ended, SensorMotion& out) noexcept {
  if (mode_ != VelocityProxy::kAuto) return mode_ == VelocityProxy::kDisplacement;
  const bool sticking = !detector_.slipping();
  if (p.m.n == 0) {
    detector_.reset();  // no contact: the next contact starts sticking (static friction first)
  } else {
    const SlipDetector::Step step =
        detector_.update(shear_content, planar_content(p.increment, c_displacement_ * kQ16Lsb),
                         out.load_drop_rate, dt_s);
    const SlipDetector::Features& f = detector_.features();
    out.shear_shift_m = f.shift_m;
    out.shear_rate_m_s = f.rate_m_s;
    out.slip_relax_rate = f.relax_rate;
    out.slip_onset = step.onset;
    out.stick_confirmed = step.confirmed;
    *slide_ended = step.ended;
  }
  out.slipping = !sticking;
  return sticking;
}

// The sliding regime's planar step since the last frame: the mask centroid (height-weighted), or
// the common points' mean step if the mask jumped; none if Ω_t and Ω_{t−1} share no cell.
MotionEstimator::SlideStep MotionEstimator::slide_step(
    const Pass& p, double mask_change, const Eigen::Vector3d& centroid) const noexcept {
  const ContactMoments& m = p.m;
  SlideStep r;
  r.point = centroid;
  // Cells at the rim of Ω carry z ≈ 0, so the cells that flicker in and out of Ω there, and
  // those the hysteresis keeps in Ω after the patch has moved on, hardly move the weighted
  // centroid. Without any height (flat contact, height_gain 0) the plain mean.
  const bool weighted = m.sz > 0 && prev_sz_ > 0;
  // Area ratio, larger cell count over smaller (exact in double: counts ≤ kGridCount).
  const std::int64_t larger = std::max(m.n, prev_count_), smaller = std::min(m.n, prev_count_);
  const bool area_steady =
      static_cast<double>(larger) <= max_mask_area_ratio_ * static_cast<double>(smaller);
  if (p.common == 0) {
    // Unrelated contacts (one vanished as another appeared), not a slide, which moves a patch
    // by a fraction of its size per frame. No translation.
  } else if (mask_change <= max_mask_change_ && area_steady) {
    if (weighted) {
      const double wt = static_cast<double>(m.sz), wp = static_cast<double>(prev_sz_);
      r.disp.x() = (static_cast<double>(m.sxz) / wt - static_cast<double>(prev_sxz_) / wp) * kNm;
      r.disp.y() = (static_cast<double>(m.syz) / wt - static_cast<double>(prev_syz_) / wp) * kNm;
      r.point =
          Eigen::Vector3d(Eigen::Vector3d(static_cast<double>(m.sxz), static_cast<double>(m.syz),
                                          static_cast<double>(m.szz)) *
                          kNm / static_cast<double>(m.sz));
    } else {
      const double nt = static_cast<double>(m.n), np = static_cast<double>(prev_count_);
      r.disp.x() = (static_cast<double>(m.sx) / nt - static_cast<double>(prev_sx_) / np) * kNm;
      r.disp.y() = (static_cast<double>(m.sy) / nt - static_cast<double>(prev_sy_) / np) * kNm;
    }
    r.source = TranslationSource::kCentroid;
  } else {
    r.disp = mean_step(p.common_dx, p.common_dy, p.common);
    r.source = TranslationSource::kCommonPoints;
  }
  return r;
}

// Translation: the contact-centroid planar displacement (paper Sec. IV-D), t_z = 0.
void MotionEstimator::translate(const Pass& p, bool sticking, double dt_s,
                                SensorMotion& out) const noexcept {
  const ContactMoments& m = p.m;
  if (m.n > 0) {
    out.centroid_m =
        Eigen::Vector3d(Eigen::Vector3d(static_cast<double>(m.sx), static_cast<double>(m.sy),
                                        static_cast<double>(m.sz)) *
                        kNm) /
        static_cast<double>(m.n);
  }
  out.translation_point_m = out.centroid_m;
  const std::int64_t uni = m.n + prev_count_ - p.common;
  out.mask_change = uni > 0 ? 1.0 - static_cast<double>(p.common) / static_cast<double>(uni) : 1.0;
  if (m.n == 0 || prev_count_ == 0) return;
  const SlideStep slide = slide_step(p, out.mask_change, out.centroid_m);
  Eigen::Vector2d disp = Eigen::Vector2d::Zero();
  if (sticking && p.common > 0) {
    // While the contact sticks the gel material moves with the object, so the mean displacement
    // of the material points in both masks is the contact displacement itself. The mask
    // centroid is not used here: a tangential load stretches the gel behind the patch and
    // compresses it ahead, which moves Ω (read from 𝒢) backwards although nothing slid. For
    // the same reason the mean is over the anchored patch when it has common points: Ω grows
    // over stretched gel that lags the object, which would dilute the mean.
    disp = p.anchored_common > 0 ? mean_step(p.anchored_dx, p.anchored_dy, p.anchored_common)
                                 : mean_step(p.common_dx, p.common_dy, p.common);
    out.translation_source = TranslationSource::kCommonPoints;
    out.translation_valid = true;
  } else if (slide.source != TranslationSource::kNone) {
    disp = slide.disp;
    out.translation_source = slide.source;
    out.translation_valid = true;
    if (slide.source == TranslationSource::kCentroid) out.translation_point_m = slide.point;
  }
  if (out.releasing) {
    disp.setZero();
    out.translation_valid = false;
    out.translation_source = TranslationSource::kNone;
  }
  out.translation =
      translation_scale_.cwiseProduct(Eigen::Vector3d(disp.x(), disp.y(), 0.0) / dt_s);
  if (out.velocity_differs && slide.source != TranslationSource::kNone) {
    out.velocity_translation = translation_scale_.cwiseProduct(
        Eigen::Vector3d(slide.disp.x(), slide.disp.y(), 0.0) / dt_s);
    out.velocity_translation_valid = true;
    out.velocity_translation_point_m = slide.point;
  }
}

// Rotation: own-frame shear-only least squares (Eq. twist_ls), fixed 3x3 solve.
Eigen::Vector3d MotionEstimator::solve_rotation(const ContactMoments& sums, double scale,
                                                const Eigen::Vector3d& axis_scale,
                                                Solve3Result& result) const noexcept {
  const MomentSums ms = to_metric(sums, scale);
  Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
  Eigen::Vector3d Atb = Eigen::Vector3d::Zero();
  add_normal_equations(ms, AtA, Atb);
  Solve3Options opt = solve_options_;
  opt.lambda_abs = ms.n * lever_floor_m_ * lever_floor_m_;
  result = solve3(AtA, Atb, opt);
  return Eigen::Vector3d(axis_scale.cwiseProduct(result.x));
}

// The chosen proxy's rotation and, while kAuto sticks, the velocity proxy's beside it (over
// `velocity`, read at `velocity_scale`).
void MotionEstimator::rotate(const ContactMoments& velocity, double velocity_scale,
                             std::int64_t contact_cells, SensorMotion& out) const noexcept {
  if (out.moments.n > 0 && !out.releasing) {
    out.omega = solve_rotation(out.moments, out.proxy_scale, out.rotation_scale, out.solve);
    out.rotation_valid = out.proxy_valid && out.solve.valid;
  }
  if (out.velocity_differs) {
    out.velocity_moments = velocity;
    out.velocity_proxy_scale = velocity_scale;
    out.velocity_rotation_scale = rotation_scale_;
    if (contact_cells > 0) {
      out.velocity_omega =
          solve_rotation(velocity, velocity_scale, rotation_scale_, out.velocity_solve);
    }
    return;
  }
  out.velocity_moments = out.moments;
  out.velocity_proxy_scale = out.proxy_scale;
  out.velocity_rotation_scale = out.rotation_scale;
  out.velocity_omega = out.omega;
  out.velocity_solve = out.solve;
  out.velocity_translation = out.translation;
  out.velocity_translation_valid = out.translation_valid;
  out.velocity_translation_point_m = out.translation_point_m;
}

// State for the next frame. The anchor follows Ω while the contact is tangentially unloaded
// (the grasp: a few µm of planar shear content), from its first frame, and from the frame a
// slide ended (the patch is where the slide left it); it stays while a tangential load is held.
void MotionEstimator::remember(const ContactSet& contact, const VectorField& shear,
                               const ContactMoments& m, double shear_shift_m, bool slide_ended,
                               SensorMotion& out) noexcept {
  if (m.n == 0) {
    have_anchor_ = false;
  } else if (!have_anchor_ || slide_ended || shear_shift_m <= min_shift_m_) {
    anchor_mask_ = contact.mask;
    anchor_count_ = m.n;
    have_anchor_ = true;
    out.anchor_set = true;
  }
  prev_mask_ = contact.mask;
  prev_x_nm_ = contact.x_nm;
  prev_y_nm_ = contact.y_nm;
  prev_count_ = m.n;
  prev_sx_ = m.sx;
  prev_sy_ = m.sy;
  prev_sz_ = m.sz;
  prev_sxz_ = m.sxz;
  prev_syz_ = m.syz;
  prev_shear_ = shear;
  have_prev_shear_ = true;
}

Status MotionEstimator::update(const ContactSet& contact, const VectorField& shear, double dt_s,
                               SensorMotion& out) noexcept {
  out = SensorMotion{};
  out.rotation_scale = rotation_scale_;
  if (!std::isfinite(dt_s) || !(dt_s > 0.0) || dt_s > 1.0) return Status::kBadArgument;

  const double velocity_scale = c_velocity_ * kQ16Lsb;                 // (m/s) per LSB of shear
  const double displacement_scale = c_displacement_ * kQ16Lsb / dt_s;  // (m/s) per LSB of Δshear
  const Pass p = gather(contact, shear);
  out.points = static_cast<int>(p.m.n);
  out.contact = p.m.n > 0;
  // Planar rigid content X of the shear over Ω read as a contact displacement, unsmoothed: the
  // velocity proxy's region test below, the detector's raw X and the anchor rule all read it.
  const Eigen::Vector3d shear_content = planar_content(p.shear, c_displacement_ * kQ16Lsb);
  // The velocity proxy's region (kVelocityAnchorDragRatio above): Ω ∩ anchor while the shear over
  // Ω is a drag and Ω and the anchor still share enough cells, else Ω.
  out.velocity_anchored = velocity_reads_anchor(shear_content, p.held.n, anchor_count_, p.m.n);
  const ContactMoments& mvel = out.velocity_anchored ? p.held : p.shear;
  out.velocity_points = static_cast<int>(mvel.n);
  out.anchor_overlap_points = static_cast<int>(p.held.n);

  // Normal load L = Σ z over Ω (the height estimate: p ∝ indentation in a thin layer) and its
  // relative rate of fall (LoadRelease, docs/dsp/motion.md, release).
  if (p.m.n > 0) {
    out.load_drop_rate = release_.update(static_cast<double>(p.m.sz), prev_count_ > 0,
                                         static_cast<double>(prev_sz_), dt_s);
  }
  bool slide_ended = false;
  const bool sticking = decide_proxy(p, shear_content, dt_s, &slide_ended, out);

  // Final proxy of this frame, and (kAuto while sticking) the velocity proxy's reading beside it.
  // The displacement proxy reads its increments over the anchored patch: a tangential load
  // stretches the gel behind the patch, 𝒢 reads the stretch as normal load and Ω grows over gel
  // that does not move with the object, which would dilute the mean increment more the larger
  // the motion (docs/dsp/motion.md, patch anchor). Over Ω_t ∩ Ω_{t−1} alone if the anchor and
  // Ω no longer share a cell.
  out.velocity_differs = mode_ == VelocityProxy::kAuto && sticking;
  out.moments = sticking ? (p.anchored_increment.n > 0 ? p.anchored_increment : p.increment) : mvel;
  // A sticking contact whose load falls faster than release_load_rate is being let go: the
  // displacement proxy's increments are the gel springing back, not the object, so this frame's
  // chosen reading is dropped (rotation and translation; the velocity reading beside it stays).
  out.releasing = sticking && out.contact && release_.unloading_fast(out.load_drop_rate);
  out.proxy_valid = (!sticking || have_prev_shear_) && !out.releasing;
  out.proxy_scale = sticking ? displacement_scale : velocity_scale;
  out.rotation_scale = sticking ? displacement_rotation_scale_ : rotation_scale_;

  translate(p, sticking, dt_s, out);
  rotate(mvel, velocity_scale, p.m.n, out);
  remember(contact, shear, p.m, shear_content.norm(), slide_ended, out);
  return Status::kOk;
}

}  // namespace tacse3::dsp
