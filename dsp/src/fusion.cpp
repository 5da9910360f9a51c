// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: dual-sensor fusion of the per-sensor motion into one twist in the gripper frame G.
#include "tacse3/dsp/fusion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tacse3::dsp {
namespace {

bool finite_matrix(const Eigen::Matrix3d& m) noexcept {
  return m.allFinite();
}

bool rotation_ok(const Eigen::Matrix3d& R) noexcept {
  if (!finite_matrix(R)) return false;
  const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  return err < 1e-6 && R.determinant() > 0.0;
}

// A sensor's moments enter ω when it sees contact and its proxy is defined this frame.
bool enters_rotation(const SensorMotion* s) noexcept {
  return s != nullptr && s->contact && s->proxy_valid && s->moments.n > 0;
}
bool enters_translation(const SensorMotion* s) noexcept {
  return s != nullptr && s->contact && s->translation_valid;
}

void fuse_paper(const std::array<const SensorMotion*, 2>& s, const FusionConfig& cfg,
                FusedMotion& out) noexcept {
  const Eigen::Vector3d sw(cfg.sign[0], cfg.sign[1], cfg.sign[2]);
  const Eigen::Vector3d st(cfg.sign[3], cfg.sign[4], cfg.sign[5]);
  // ξ₁ as is, ξ₂ through the sign matrix S (Sec. V-B), then the mean of whoever contributed:
  // ½(ξ₁ + Sξ₂) with both, the single sensor's (signed) estimate otherwise.
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  int nw = 0, nt = 0;
  bool all_solves_valid = true;
  double rcond = 1.0;
  int rank = 3;
  for (int i = 0; i < 2; ++i) {
    const SensorMotion* m = s[static_cast<std::size_t>(i)];
    const Eigen::Vector3d signw = i == 0 ? Eigen::Vector3d::Ones() : sw;
    const Eigen::Vector3d signt = i == 0 ? Eigen::Vector3d::Ones() : st;
    if (enters_rotation(m)) {
      w += signw.cwiseProduct(m->omega);
      ++nw;
      out.rotation_sensors |= static_cast<std::uint8_t>(1u << i);
      all_solves_valid = all_solves_valid && m->solve.valid;
      rcond = std::fmin(rcond, m->solve.rcond);
      rank = rank < m->solve.rank ? rank : m->solve.rank;
    }
    if (enters_translation(m)) {
      t += signt.cwiseProduct(m->translation);
      ++nt;
      out.translation_sensors |= static_cast<std::uint8_t>(1u << i);
    }
  }
  // "then expressed in G through sensor 1's extrinsics": ω and t are free vectors here (t is a
  // contact-centroid velocity, not the velocity of a fixed point), so only R_GS applies.
  const Eigen::Matrix3d& R1 = cfg.extrinsics[0].R_GS;
  if (nw > 0) {
    out.xi.head<3>() = R1 * (w / nw);
    out.rotation_valid = all_solves_valid;
    out.rcond = rcond;
    out.rank = rank;
  }
  if (nt > 0) {
    out.xi.tail<3>() = R1 * (t / nt);
    out.translation_valid = true;
  }
}

void fuse_joint(const std::array<const SensorMotion*, 2>& s, const FusionConfig& cfg,
                double separation_m, FusedMotion& out) noexcept {
  // 1. Moments of every contributing sensor in G (points R q + p(W), proxies R ṽ).
  std::array<MomentSums, 2> g{};
  double n_total = 0.0;
  Eigen::Vector3d s1_total = Eigen::Vector3d::Zero();
  Eigen::Matrix3d scale = Eigen::Matrix3d::Zero();
  int nw = 0;
  for (int i = 0; i < 2; ++i) {
    const SensorMotion* m = s[static_cast<std::size_t>(i)];
    if (!enters_rotation(m)) continue;
    const SensorExtrinsics& e = cfg.extrinsics[static_cast<std::size_t>(i)];
    g[static_cast<std::size_t>(i)] =
        rigid_transform(to_metric(m->moments, m->proxy_scale), e.R_GS, e.p_GS(separation_m));
    n_total += g[static_cast<std::size_t>(i)].n;
    s1_total += g[static_cast<std::size_t>(i)].s1;
    scale += e.R_GS * m->rotation_scale.asDiagonal() * e.R_GS.transpose();
    ++nw;
    out.rotation_sensors |= static_cast<std::uint8_t>(1u << i);
  }
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();
  if (nw > 0 && n_total > 0.0) {
    // 2. One 3x3 system about the centroid m_N of all points. With all pad normals parallel, a
    //    uniform tangential field has zero moment about m_N, so the translation cannot leak into
    //    ω whatever the proxy gain: this is the least squares with a common in-plane translation
    //    eliminated in closed form, and the lever arm between the pads (W) stays physical.
    const Eigen::Vector3d m_n = s1_total / n_total;
    Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Atb = Eigen::Vector3d::Zero();
    for (int i = 0; i < 2; ++i) {
      if ((out.rotation_sensors & (1u << i)) == 0) continue;
      add_normal_equations(
          rigid_transform(g[static_cast<std::size_t>(i)], Eigen::Matrix3d::Identity(), -m_n), AtA,
          Atb);
    }
    Solve3Options opt;
    opt.lambda_rel = cfg.solve_lambda_rel;
    opt.lambda_abs = n_total * cfg.solve_lever_floor_m * cfg.solve_lever_floor_m;
    opt.rcond_min = cfg.solve_rcond_min;
    const Solve3Result r = solve3(AtA, Atb, opt);
    out.rcond = r.rcond;
    if (nw == 2) {
      omega = (scale / nw) * r.x;
      out.rotation_valid = r.valid;
      out.rank = r.rank;
    } else {
      // One pad: only the rotation about its normal n. A rotation about an in-plane axis shears
      // a flat pad like a translation does; the 3x3 solve would read those two components from
      // the sub-millimetre lever of the indentation's heights alone, where a few µm of shear
      // noise per frame become rad/s (a pad dropping out for a few frames of a dual grasp would
      // turn the object by degrees). They are reported as 0: the 1-D least squares along n,
      // ω = n (nᵀAᵀb)/(nᵀAᵀA n + λ), with the λ of the 3x3 solve. rank = 1 says so.
      const int i = (out.rotation_sensors & kSensor1) != 0 ? 0 : 1;
      const Eigen::Vector3d n = cfg.extrinsics[static_cast<std::size_t>(i)].R_GS.col(2);
      const double lever = n.dot(AtA * n);  // Σ of the squared levers about n
      const double num = n.dot(Atb);
      const double den = lever + r.lambda;
      const bool solvable = lever > 0.0 && std::isfinite(den) && std::isfinite(num);
      omega = solvable ? Eigen::Vector3d(scale * n * (num / den)) : Eigen::Vector3d::Zero();
      out.rotation_valid = solvable;
      out.rank = solvable ? 1 : 0;
    }
    if (!omega.allFinite()) omega.setZero();
    out.xi.head<3>() = omega;
  }

  // 3. Translation: mean of the contact-centroid velocities in G, referred to G's origin with the
  //    fitted ω (rigid body: v(c) = t + ω × c). t_z = 0 along the closing axis (unobservable).
  Eigen::Vector3d v_mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d c_mean = Eigen::Vector3d::Zero();
  int nt = 0;
  for (int i = 0; i < 2; ++i) {
    const SensorMotion* m = s[static_cast<std::size_t>(i)];
    if (!enters_translation(m)) continue;
    const SensorExtrinsics& e = cfg.extrinsics[static_cast<std::size_t>(i)];
    v_mean += e.R_GS * m->translation;
    c_mean += e.R_GS * m->translation_point_m + e.p_GS(separation_m);
    ++nt;
    out.translation_sensors |= static_cast<std::uint8_t>(1u << i);
  }
  if (nt > 0) {
    v_mean /= nt;
    c_mean /= nt;
    Eigen::Vector3d t = v_mean - omega.cross(c_mean);
    t.z() = 0.0;
    if (t.allFinite()) {
      out.xi.tail<3>() = t;
      out.translation_valid = true;
      out.reference_point = c_mean;
    }
  }
}

// In-plane Σ|r|² of a pad's points about their own centroid (r ⟂ the pad normal).
double in_plane_inertia(const MomentSums& m) noexcept {
  if (m.n <= 0.0) return 0.0;
  const Eigen::Vector3d c = m.s1 / m.n;
  const Eigen::Matrix3d s2c = m.s2 - m.n * (c * c.transpose());
  return std::fmax(s2c.trace() - m.normal.dot(s2c * m.normal), 0.0);
}

// A pad's own rotation about its normal from its points alone (about its centroid), as a vector.
Eigen::Vector3d own_normal_rotation(const MomentSums& g, double scale_n) noexcept {
  if (g.n <= 0.0) return Eigen::Vector3d::Zero();
  const MomentSums c = rigid_transform(g, Eigen::Matrix3d::Identity(), -g.s1 / g.n);
  Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
  Eigen::Vector3d Atb = Eigen::Vector3d::Zero();
  add_normal_equations(c, AtA, Atb);
  const double lever = g.normal.dot(AtA * g.normal);
  return lever > 0.0 ? Eigen::Vector3d(g.normal * (scale_n * g.normal.dot(Atb) / lever))
                     : Eigen::Vector3d::Zero();
}

}  // namespace

FitQuality fit_quality(const SensorMotion* s1, const SensorMotion* s2, const FusionConfig& cfg,
                       double separation_m) noexcept {
  FitQuality q;
  const std::array<const SensorMotion*, 2> s{s1, s2};
  std::array<MomentSums, 2> g{};
  std::array<Eigen::Vector3d, 2> own{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  double n = 0.0, inertia = 0.0;
  Eigen::Vector3d s1_total = Eigen::Vector3d::Zero(), sv_total = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < 2; ++i) {
    if (!enters_rotation(s[i])) continue;
    const SensorExtrinsics& e = cfg.extrinsics[i];
    g[i] =
        rigid_transform(to_metric(s[i]->moments, s[i]->proxy_scale), e.R_GS, e.p_GS(separation_m));
    own[i] = own_normal_rotation(g[i], s[i]->rotation_scale.z());
    n += g[i].n;
    inertia += in_plane_inertia(g[i]);
    s1_total += g[i].s1;
    sv_total += g[i].sv;
    q.min_points = q.pads == 0 ? s[i]->points : std::min(q.min_points, s[i]->points);
    ++q.pads;
  }
  if (q.pads == 0 || !(n > 0.0)) return FitQuality{};
  // The joint system about the common centroid (as fuse_joint solves it) and its solution.
  const Eigen::Vector3d m_n = s1_total / n;
  Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
  Eigen::Vector3d Atb = Eigen::Vector3d::Zero();
  double svv = 0.0, levers_n = 0.0;
  for (std::size_t i = 0; i < 2; ++i) {
    if (g[i].n <= 0.0) continue;
    add_normal_equations(rigid_transform(g[i], Eigen::Matrix3d::Identity(), -m_n), AtA, Atb);
    svv += g[i].svv;
    const double d = g[i].normal.dot(g[i].s1 / g[i].n - m_n);
    levers_n += g[i].n * d * d;
  }
  Solve3Options opt;
  opt.lambda_rel = cfg.solve_lambda_rel;
  opt.lambda_abs = n * cfg.solve_lever_floor_m * cfg.solve_lever_floor_m;
  opt.rcond_min = cfg.solve_rcond_min;
  const Solve3Result r = solve3(AtA, Atb, opt);
  Eigen::Vector3d w = r.x;
  if (q.pads == 2) {
    q.rank = 3;
    q.rcond = r.rcond;
    const double a = levers_n, b = inertia;  // expected eigenvalues (double, single)
    q.rcond_expected = a > 0.0 && b > 0.0 ? std::fmin(a, b) / std::fmax(a, b) : 0.0;
    q.disagreement_m_s = (own[0] - own[1]).dot(g[0].normal) * std::sqrt(inertia / n);
  } else {
    const Eigen::Vector3d nn = g[0].n > 0.0 ? g[0].normal : g[1].normal;
    const double lever = nn.dot(AtA * nn);
    q.rank = lever > 0.0 ? 1 : 0;
    q.rcond = q.rcond_expected = 1.0;
    w = lever > 0.0 ? Eigen::Vector3d(nn * (nn.dot(Atb) / (lever + r.lambda)))
                    : Eigen::Vector3d::Zero();
  }
  // Residual of ṽ = t + ω × q over the tangential equations, t the mean proxy (a uniform
  // tangential field has no moment about m_N): Σ|ṽ|² − |Σṽ|²/N − 2ωᵀAᵀb + ωᵀAᵀAω.
  const double e = svv - sv_total.squaredNorm() / n - 2.0 * w.dot(Atb) + w.dot(AtA * w);
  const double dof = 2.0 * n - q.rank - 2.0;
  // Too few points to estimate it: an unknown residual counts as an infinite one.
  q.residual_speed_m_s = dof > 0.0 && std::isfinite(e) ? std::sqrt(std::fmax(e, 0.0) / dof / n)
                                                       : std::numeric_limits<double>::infinity();
  if (!std::isfinite(q.disagreement_m_s)) q.disagreement_m_s = 0.0;
  return q;
}

SensorExtrinsics left_pad_extrinsics() noexcept {
  SensorExtrinsics e;
  e.R_GS = Eigen::Matrix3d::Identity();
  e.separation_sign = 1.0;
  return e;
}

SensorExtrinsics right_pad_extrinsics() noexcept {
  SensorExtrinsics e;
  e.R_GS = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
  e.separation_sign = -1.0;
  return e;
}

Status validate(const FusionConfig& cfg) noexcept {
  if (cfg.method != FusionMethod::kPaper && cfg.method != FusionMethod::kJoint) {
    return Status::kBadArgument;
  }
  for (double s : cfg.sign) {
    if (s != 1.0 && s != -1.0) return Status::kBadArgument;
  }
  for (const SensorExtrinsics& e : cfg.extrinsics) {
    if (!rotation_ok(e.R_GS) || !e.offset_m.allFinite() || !std::isfinite(e.separation_sign)) {
      return Status::kBadArgument;
    }
  }
  const bool reg_ok = std::isfinite(cfg.solve_lambda_rel) && cfg.solve_lambda_rel >= 0.0 &&
                      cfg.solve_lambda_rel <= 1.0 && std::isfinite(cfg.solve_lever_floor_m) &&
                      cfg.solve_lever_floor_m >= 0.0 && cfg.solve_lever_floor_m <= 1e-2 &&
                      std::isfinite(cfg.solve_rcond_min) && cfg.solve_rcond_min >= 0.0 &&
                      cfg.solve_rcond_min < 1.0;
  return reg_ok ? Status::kOk : Status::kBadArgument;
}

Status fuse(const SensorMotion* s1, const SensorMotion* s2, const FusionConfig& cfg,
            double separation_m, FusedMotion& out) noexcept {
  out = FusedMotion{};
  out.method = cfg.method;
  out.contact = {s1 != nullptr && s1->contact, s2 != nullptr && s2->contact};
  Status st = validate(cfg);
  if (st == Status::kOk &&
      (!std::isfinite(separation_m) || separation_m < 0.0 || separation_m > 0.5)) {
    st = Status::kBadArgument;
  }
  if (st != Status::kOk) {
    out.status = st;
    return st;
  }
  const std::array<const SensorMotion*, 2> s{s1, s2};
  if (cfg.method == FusionMethod::kPaper) {
    fuse_paper(s, cfg, out);
  } else {
    fuse_joint(s, cfg, separation_m, out);
  }
  if (!out.xi.allFinite()) {  // defensive: inputs from outside the pipeline could hold NaN
    out.xi.setZero();
    out.rotation_valid = out.translation_valid = false;
  }
  const std::uint8_t any = out.rotation_sensors | out.translation_sensors;
  out.single_sensor = any == kSensor1 || any == kSensor2;
  out.valid = out.rotation_valid && out.translation_valid;
  out.quality = fit_quality(s1, s2, cfg, separation_m);
  return Status::kOk;
}

}  // namespace tacse3::dsp
