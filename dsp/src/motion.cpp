// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: per-sensor motion: contact-centroid translation, velocity proxy, int64 moments, ω.
#include "tacse3/dsp/motion.hpp"

#include <Eigen/Geometry>  // cross products
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
  return Status::kOk;
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
}

Status MotionEstimator::update(const ContactSet& contact, const VectorField& shear, double dt_s,
                               SensorMotion& out) noexcept {
  out = SensorMotion{};
  out.rotation_scale = rotation_scale_;
  if (!std::isfinite(dt_s) || !(dt_s > 0.0) || dt_s > 1.0) return Status::kBadArgument;

  const bool displacement = mode_ == VelocityProxy::kDisplacement;
  out.proxy_valid = !displacement || have_prev_shear_;
  out.proxy_scale = displacement ? c_displacement_ * kQ16Lsb / dt_s : c_velocity_ * kQ16Lsb;

  // One pass over Ω: moments (Eq. twist_ls sufficient statistics) and the bookkeeping of the
  // translation rules (intersection with the previous mask).
  ContactMoments m;
  std::int64_t common = 0, common_dx = 0, common_dy = 0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    if (contact.mask.v[i] == 0) continue;
    const std::int64_t x = clamp64(contact.x_nm.v[i], -kMaxPointNm, kMaxPointNm);
    const std::int64_t y = clamp64(contact.y_nm.v[i], -kMaxPointNm, kMaxPointNm);
    const std::int64_t z = clamp64(contact.z_nm.v[i], 0, kMaxZNm);
    std::int64_t vx = 0, vy = 0;
    if (!displacement) {
      vx = clamp_proxy(shear.x.v[i]);
      vy = clamp_proxy(shear.y.v[i]);
    } else if (have_prev_shear_) {
      vx = clamp_proxy(static_cast<std::int64_t>(shear.x.v[i]) - prev_shear_.x.v[i]);
      vy = clamp_proxy(static_cast<std::int64_t>(shear.y.v[i]) - prev_shear_.y.v[i]);
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
    m.svx += vx;
    m.svy += vy;
    m.sx_vy += x * vy;
    m.sy_vx += y * vx;
    m.sz_vx += z * vx;
    m.sz_vy += z * vy;
    if (prev_mask_.v[i] != 0) {
      ++common;
      common_dx += x - clamp64(prev_x_nm_.v[i], -kMaxPointNm, kMaxPointNm);
      common_dy += y - clamp64(prev_y_nm_.v[i], -kMaxPointNm, kMaxPointNm);
    }
  }
  out.moments = m;
  out.points = static_cast<int>(m.n);
  out.contact = m.n > 0;

  // --- translation: contact-centroid planar displacement (paper Sec. IV-D), t_z = 0.
  const std::int64_t uni = m.n + prev_count_ - common;
  out.mask_change = uni > 0 ? 1.0 - static_cast<double>(common) / static_cast<double>(uni) : 1.0;
  if (m.n > 0 && prev_count_ > 0) {
    Eigen::Vector3d disp = Eigen::Vector3d::Zero();
    if (displacement && common > 0) {
      // While the contact sticks the gel material moves with the object, so the mean displacement
      // of the material points in both masks is the contact displacement itself. The mask
      // centroid is not used here: a tangential load stretches the gel behind the patch and
      // compresses it ahead, which moves Ω (read from 𝒢) backwards although nothing slid.
      const double nc = static_cast<double>(common);
      disp.x() = static_cast<double>(common_dx) / nc * kNm;
      disp.y() = static_cast<double>(common_dy) / nc * kNm;
      out.translation_source = TranslationSource::kCommonPoints;
      out.translation_valid = true;
    } else if (out.mask_change <= max_mask_change_) {
      const double nt = static_cast<double>(m.n), np = static_cast<double>(prev_count_);
      disp.x() = (static_cast<double>(m.sx) / nt - static_cast<double>(prev_sx_) / np) * kNm;
      disp.y() = (static_cast<double>(m.sy) / nt - static_cast<double>(prev_sy_) / np) * kNm;
      out.translation_source = TranslationSource::kCentroid;
      out.translation_valid = true;
    } else if (common > 0) {
      const double nc = static_cast<double>(common);
      disp.x() = static_cast<double>(common_dx) / nc * kNm;
      disp.y() = static_cast<double>(common_dy) / nc * kNm;
      out.translation_source = TranslationSource::kCommonPoints;
      out.translation_valid = true;
    }
    out.translation = translation_scale_.cwiseProduct(disp / dt_s);
  }

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
