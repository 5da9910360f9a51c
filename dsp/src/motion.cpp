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

// Largest |deficit| per cell (Q16 shear units, 16384 working px): far beyond any real shear, it
// only keeps the int32 state and the payback products (|A| · h < 2^30 · 2^31 < 2^63) in range.
constexpr std::int32_t kMaxDeficitQ16 = std::int32_t{1} << 30;
// Q16 factors of the deficit bookkeeping are clamped to this (a ratio of 32768).
constexpr std::int64_t kMaxFactorQ16 = std::int64_t{1} << 31;

// Σ ṽ and Σ q_a ṽ_b of one proxy over Ω (the q sums are shared by every proxy).
struct ProxySums {
  std::int64_t svx = 0, svy = 0, sx_vy = 0, sy_vx = 0, sz_vx = 0, sz_vy = 0;
  void add(std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t vx,
           std::int64_t vy) noexcept {
    svx += vx;
    svy += vy;
    sx_vy += x * vy;
    sy_vx += y * vx;
    sz_vx += z * vx;
    sz_vy += z * vy;
  }
  void add(const ProxySums& o) noexcept {
    svx += o.svx;
    svy += o.svy;
    sx_vy += o.sx_vy;
    sy_vx += o.sy_vx;
    sz_vx += o.sz_vx;
    sz_vy += o.sz_vy;
  }
  void store(ContactMoments& m) const noexcept {
    m.svx = svx;
    m.svy = svy;
    m.sx_vy = sx_vy;
    m.sy_vx = sy_vx;
    m.sz_vx = sz_vx;
    m.sz_vy = sz_vy;
  }
};

// a · f (f a Q16 factor ≥ 0), rounded to nearest: |a| < 2^31, f ≤ 2^31, no overflow.
std::int64_t mul_q16(std::int64_t a, std::int64_t f) noexcept {
  return (a * f + (std::int64_t{1} << 15)) >> 16;
}
std::int64_t factor_q16(double f) noexcept {
  if (!(f > 0.0)) return 0;
  const double q = std::round(f * 65536.0);
  return q >= static_cast<double>(kMaxFactorQ16) ? kMaxFactorQ16 : static_cast<std::int64_t>(q);
}

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

double content_alpha(double dt_s, double smoothing_s) noexcept {
  return smoothing_s > 0.0 ? dt_s / (smoothing_s + dt_s) : 1.0;
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
  rotation_scale_ =
      Eigen::Vector3d(cal.rotation_scale[0], cal.rotation_scale[1], cal.rotation_scale[2]);
  translation_scale_ =
      Eigen::Vector3d(cal.translation_scale[0], cal.translation_scale[1], cal.translation_scale[2]);
  solve_options_.lambda_rel = cal.solve_lambda_rel;
  solve_options_.lambda_abs = 0.0;
  solve_options_.rcond_min = cal.solve_rcond_min;
  lever_floor_m_ = cal.solve_lever_floor_m;
  relax_rate_on_ = cal.slip_relax_rate_on;
  on_frames_ = cal.slip_on_frames;
  min_shift_m_ = cal.slip_min_shift_m;
  exit_fraction_ = cal.slip_exit_fraction;
  rest_speed_ = cal.stick_rest_speed_m_s;
  confirm_s_ = cal.stick_confirm_s;
  catchup_frames_ = cal.slip_catchup_frames;
  smoothing_s_ = cal.slip_smoothing_s;
  // Entering or leaving kAuto starts the detector afresh (its deficit belongs to one mode).
  if (was_auto != (mode_ == VelocityProxy::kAuto)) reset_detector();
  return Status::kOk;
}

void MotionEstimator::reset_detector() noexcept {
  slipping_ = false;
  evidence_frames_ = 0;
  rest_s_ = 0.0;
  peak_shift_m_ = 0.0;
  catchup_left_ = 0;
  deficit_x_.fill(0);
  deficit_y_.fill(0);
  deficit_t_.setZero();
  content_.setZero();
  have_content_ = false;
}

void MotionEstimator::reset() noexcept {
  prev_mask_.fill(0);
  prev_x_nm_.fill(0);
  prev_y_nm_.fill(0);
  prev_count_ = 0;
  prev_sx_ = 0;
  prev_sy_ = 0;
  prev_shear_.x.fill(0);
  prev_shear_.y.fill(0);
  have_prev_shear_ = false;
  reset_detector();
}

Status MotionEstimator::update(const ContactSet& contact, const VectorField& shear, double dt_s,
                               SensorMotion& out) noexcept {
  out = SensorMotion{};
  out.rotation_scale = rotation_scale_;
  if (!std::isfinite(dt_s) || !(dt_s > 0.0) || dt_s > 1.0) return Status::kBadArgument;

  const bool automatic = mode_ == VelocityProxy::kAuto;
  const double velocity_scale = c_velocity_ * kQ16Lsb;                 // (m/s) per LSB of shear
  const double displacement_scale = c_displacement_ * kQ16Lsb / dt_s;  // (m/s) per LSB of Δshear
  // kAuto bookkeeping in the pass (state decided by the previous frames): a sticking contact
  // accumulates the deficit g·shear − Δshear, g = c_velocity Δt / c_displacement; a slipping one
  // that is paying back adds h·A/left to its velocity proxy, h = c_displacement/(c_velocity Δt),
  // and removes A/left from A.
  const bool accumulate = automatic && !slipping_ && have_prev_shear_;
  const int left = automatic && slipping_ ? catchup_left_ : 0;
  const std::int64_t g_q16 = accumulate ? factor_q16(c_velocity_ * dt_s / c_displacement_) : 0;
  const std::int64_t h_q16 = left > 0 ? factor_q16(c_displacement_ / (c_velocity_ * dt_s)) : 0;

  // One pass over Ω: moments (Eq. twist_ls sufficient statistics) of the shear (velocity proxy)
  // and of its increment (displacement proxy), the payback, and the bookkeeping of the
  // translation rules (intersection with the previous mask).
  ContactMoments m;
  ProxySums sum_shear, sum_increment, sum_payback;
  std::int64_t common = 0, common_dx = 0, common_dy = 0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    // A cell outside Ω keeps its deficit: the grid is fixed to the gel material, and a cell at the
    // patch border that flickers out of Ω for a frame carries the largest lever of a torsion.
    if (contact.mask.v[i] == 0) continue;
    const std::int64_t x = clamp64(contact.x_nm.v[i], -kMaxPointNm, kMaxPointNm);
    const std::int64_t y = clamp64(contact.y_nm.v[i], -kMaxPointNm, kMaxPointNm);
    const std::int64_t z = clamp64(contact.z_nm.v[i], 0, kMaxZNm);
    const std::int64_t sx = clamp_proxy(shear.x.v[i]);
    const std::int64_t sy = clamp_proxy(shear.y.v[i]);
    std::int64_t dx = 0, dy = 0;
    if (have_prev_shear_) {
      dx = clamp_proxy(static_cast<std::int64_t>(shear.x.v[i]) - prev_shear_.x.v[i]);
      dy = clamp_proxy(static_cast<std::int64_t>(shear.y.v[i]) - prev_shear_.y.v[i]);
    }
    ++m.n;
    m.sx += x;
    m.sy += y;
    m.sz += z;
    m.sxx += x * x;
    m.sxy += x * y;
    m.sxz += x * z;
    m.syy += y * y;
    m.syz += y * z;
    m.szz += z * z;
    sum_shear.add(x, y, z, sx, sy);
    sum_increment.add(x, y, z, dx, dy);
    if (accumulate) {
      deficit_x_.v[i] = static_cast<std::int32_t>(
          clamp64(deficit_x_.v[i] + mul_q16(sx, g_q16) - dx, -kMaxDeficitQ16, kMaxDeficitQ16));
      deficit_y_.v[i] = static_cast<std::int32_t>(
          clamp64(deficit_y_.v[i] + mul_q16(sy, g_q16) - dy, -kMaxDeficitQ16, kMaxDeficitQ16));
    } else if (left > 0) {
      const std::int64_t px = deficit_x_.v[i] / left, py = deficit_y_.v[i] / left;
      deficit_x_.v[i] = static_cast<std::int32_t>(deficit_x_.v[i] - px);
      deficit_y_.v[i] = static_cast<std::int32_t>(deficit_y_.v[i] - py);
      sum_payback.add(x, y, z, clamp_proxy(mul_q16(px, h_q16)), clamp_proxy(mul_q16(py, h_q16)));
    }
    if (prev_mask_.v[i] != 0) {
      ++common;
      common_dx += x - clamp64(prev_x_nm_.v[i], -kMaxPointNm, kMaxPointNm);
      common_dy += y - clamp64(prev_y_nm_.v[i], -kMaxPointNm, kMaxPointNm);
    }
  }
  out.points = static_cast<int>(m.n);
  out.contact = m.n > 0;

  // --- kAuto: the stick/slip detector on the rigid-body content of the shear and its increment.
  // The proxy of this frame is the one decided up to the previous frame: the deficit bookkeeping
  // of the pass above already treated this frame as sticking (or paying back).
  const bool sticking = automatic ? !slipping_ : mode_ == VelocityProxy::kDisplacement;
  if (automatic) {
    if (m.n == 0) {
      reset_detector();  // no contact: the next contact starts sticking (static friction first)
    } else {
      // Planar rigid-body content of the shear read as a contact displacement, smoothed.
      ContactMoments ms = m;
      sum_shear.store(ms);
      const Eigen::Vector3d raw = planar_content(ms, c_displacement_ * kQ16Lsb);
      const Eigen::Vector3d before = content_;
      content_ =
          have_content_
              ? Eigen::Vector3d(content_ + content_alpha(dt_s, smoothing_s_) * (raw - content_))
              : raw;
      const Eigen::Vector3d change =
          have_content_ ? Eigen::Vector3d(content_ - before) : Eigen::Vector3d::Zero();
      have_content_ = true;
      const double x2 = content_.squaredNorm();
      out.shear_shift_m = std::sqrt(x2);
      out.shear_rate_m_s = change.norm() / dt_s;
      out.slip_relax_rate = x2 > 0.0 ? -content_.dot(change) / (x2 * dt_s) : 0.0;
      const bool rest = out.shear_rate_m_s < rest_speed_;
      if (!slipping_) {
        const bool relaxing =
            out.shear_shift_m > min_shift_m_ && out.slip_relax_rate > relax_rate_on_;
        evidence_frames_ = relaxing ? evidence_frames_ + 1 : 0;
        rest_s_ = rest ? rest_s_ + dt_s : 0.0;
        if (evidence_frames_ >= on_frames_) {
          slipping_ = true;
          out.slip_onset = true;
          evidence_frames_ = 0;
          peak_shift_m_ = out.shear_shift_m;
          catchup_left_ = catchup_frames_;
        } else if (rest_s_ >= confirm_s_) {
          out.stick_confirmed = true;
          deficit_x_.fill(0);
          deficit_y_.fill(0);
          deficit_t_.setZero();
        }
      } else {
        peak_shift_m_ = std::max(peak_shift_m_, out.shear_shift_m);
        if (rest && out.shear_shift_m <= exit_fraction_ * peak_shift_m_) {
          // The slide is over and the gel has relaxed: stick again from here (increments only,
          // so the residual shear does not move the pose).
          reset_detector();
        }
      }
    }
    out.slipping = !sticking;
  }

  // Final proxy of this frame.
  ProxySums final_sums = sticking ? sum_increment : sum_shear;
  const bool paying = left > 0;
  if (paying) final_sums.add(sum_payback);
  final_sums.store(m);
  out.moments = m;
  out.proxy_valid = !sticking || have_prev_shear_;
  out.proxy_scale = sticking ? displacement_scale : velocity_scale;

  // --- translation: contact-centroid planar displacement (paper Sec. IV-D), t_z = 0.
  const std::int64_t uni = m.n + prev_count_ - common;
  out.mask_change = uni > 0 ? 1.0 - static_cast<double>(common) / static_cast<double>(uni) : 1.0;
  if (m.n > 0 && prev_count_ > 0) {
    // Rule of the sliding regime: mask centroid, or the common points if the mask jumped.
    Eigen::Vector2d slide_disp = Eigen::Vector2d::Zero();
    TranslationSource slide_source = TranslationSource::kNone;
    Eigen::Vector2d common_disp = Eigen::Vector2d::Zero();
    if (common > 0) {
      const double nc = static_cast<double>(common);
      common_disp =
          Eigen::Vector2d(static_cast<double>(common_dx), static_cast<double>(common_dy)) / nc *
          kNm;
    }
    if (out.mask_change <= max_mask_change_) {
      const double nt = static_cast<double>(m.n), np = static_cast<double>(prev_count_);
      slide_disp.x() = (static_cast<double>(m.sx) / nt - static_cast<double>(prev_sx_) / np) * kNm;
      slide_disp.y() = (static_cast<double>(m.sy) / nt - static_cast<double>(prev_sy_) / np) * kNm;
      slide_source = TranslationSource::kCentroid;
    } else if (common > 0) {
      slide_disp = common_disp;
      slide_source = TranslationSource::kCommonPoints;
    }
    Eigen::Vector2d disp = Eigen::Vector2d::Zero();
    if (sticking && common > 0) {
      // While the contact sticks the gel material moves with the object, so the mean displacement
      // of the material points in both masks is the contact displacement itself. The mask
      // centroid is not used here: a tangential load stretches the gel behind the patch and
      // compresses it ahead, which moves Ω (read from 𝒢) backwards although nothing slid.
      disp = common_disp;
      out.translation_source = TranslationSource::kCommonPoints;
      out.translation_valid = true;
      if (automatic && slide_source != TranslationSource::kNone) {
        deficit_t_ += slide_disp - common_disp;
      }
    } else if (slide_source != TranslationSource::kNone) {
      disp = slide_disp;
      out.translation_source = slide_source;
      out.translation_valid = true;
    }
    if (paying) {
      const Eigen::Vector2d pay = deficit_t_ / static_cast<double>(left);
      deficit_t_ -= pay;
      disp += pay;
    }
    out.translation =
        translation_scale_.cwiseProduct(Eigen::Vector3d(disp.x(), disp.y(), 0.0) / dt_s);
  }
  if (paying && slipping_) catchup_left_ = left - 1;  // (an exit this frame reset it)

  // --- rotation: own-frame shear-only least squares, fixed 3x3 solve.
  if (m.n > 0) {
    const MomentSums ms = to_metric(m, out.proxy_scale);
    out.centroid_m = ms.s1 / ms.n;
    Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Atb = Eigen::Vector3d::Zero();
    add_normal_equations(ms, AtA, Atb);
    Solve3Options opt = solve_options_;
    opt.lambda_abs = ms.n * lever_floor_m_ * lever_floor_m_;
    out.solve = solve3(AtA, Atb, opt);
    out.omega = rotation_scale_.cwiseProduct(out.solve.x);
    out.rotation_valid = out.proxy_valid && out.solve.valid;
  }

  // --- state for the next frame.
  prev_mask_ = contact.mask;
  prev_x_nm_ = contact.x_nm;
  prev_y_nm_ = contact.y_nm;
  prev_count_ = m.n;
  prev_sx_ = m.sx;
  prev_sy_ = m.sy;
  prev_shear_ = shear;
  have_prev_shear_ = true;
  return Status::kOk;
}

}  // namespace tacse3::dsp
