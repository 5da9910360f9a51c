// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: dual-sensor fusion of the per-sensor motion into one twist in the gripper frame G.
#include "tacse3/dsp/fusion.hpp"

#include <cmath>

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
    out.confidence = rcond;
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
    out.confidence = r.rcond;
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

}  // namespace

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
  return Status::kOk;
}

}  // namespace tacse3::dsp
