// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: the whole dual-sensor pipeline chained from the double-precision stages.
#include "tacse3/dsp_ref/pipeline_ref.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "tacse3/dsp/luma.hpp"
#include "tacse3/dsp_ref/density_ref.hpp"
#include "tacse3/dsp_ref/force_map_ref.hpp"

namespace tacse3::dsp_ref {

SensorPipelineRef::SensorPipelineRef(const dsp::PipelineConfig& config, const dsp::Calibration& cal,
                                     const ReferenceOptions& options)
    : config_(config),
      cal_(cal),
      flow_stage_(config.flow),
      nhhd_stage_(config.nhhd),
      contact_stage_(cal),
      motion_stage_(cal) {
  flow_stage_.set_fixed_point_sampling(options.fixed_point_sampling);
}

void SensorPipelineRef::tare() {
  if (flow_stage_.has_reference()) flow_stage_.tare(last_work_);  // else the next frame's own
  nhhd_stage_.reset();
  contact_stage_.reset();
  motion_stage_.reset();
}

bool SensorPipelineRef::process(const dsp::FrameView& frame, double dt_s, SensorMotionRef& out,
                                bool& degraded, const FixedDecisions* follow) {
  out = SensorMotionRef{};
  motion_ = SensorMotionRef{};
  degraded = false;
  // The luma stage is exact integer arithmetic (test_luma holds it against luma_ref), so the
  // reference starts from the same working image.
  if (dsp::frame_to_work_image(frame, last_work_, dsp::work_image_filter(cal_)) != dsp::Status::kOk)
    return false;
  const bool reference = !flow_stage_.has_reference();  // this frame becomes it: not degraded
  std::vector<std::uint8_t> valid;
  flow_stage_.track(last_work_, flow_.x, flow_.y, valid,
                    follow != nullptr ? &follow->flow : nullptr);
  flow_valid_.assign(valid.begin(), valid.end());
  int tracked = 0;
  for (auto v : valid) tracked += v != 0 ? 1 : 0;

  smooth_ref(flow_, flow_valid_, config_.smoothing, smoothed_, smoothed_valid_);
  density_ = gaussian_density_ref(smoothed_, smoothed_valid_, config_.density);
  nhhd_stage_.decompose(smoothed_, smoothed_valid_, d_, r_, k_);

  const dsp::GridMask mask_q = grid_mask_to(smoothed_valid_);
  dsp::ScalarField density_q{};
  for (int i = 0; i < dsp::kGridCount; ++i) {
    density_q.v[static_cast<std::size_t>(i)] =
        static_cast<std::int32_t>(std::lround(density_[static_cast<std::size_t>(i)] * 65536.0));
  }
  const ForceFieldsRef forces =
      force_map_ref(cal_, density_q, grid_vector_to_q16(d_), grid_vector_to_q16(r_),
                    grid_vector_to_q16(k_), mask_q);
  fz_ = forces.fz;
  shear_x_ = forces.fx;
  shear_y_ = forces.fy;
  contact_ = contact_stage_.detect(fz_, grid_vector_to_q16(smoothed_), mask_q,
                                   follow != nullptr ? follow->contact : nullptr);
  const ContactSetRef& contact = contact_;

  const int min_tracked = static_cast<int>(
      std::ceil(config_.min_tracked_fraction * static_cast<double>(dsp::kGridCount)));
  if (!reference && tracked < min_tracked) {
    degraded = true;
    motion_stage_.reset();
    return true;
  }
  const double dt = (std::isfinite(dt_s) && dt_s > 0.0 && dt_s <= 1.0) ? dt_s : 1.0 / 120.0;
  out = motion_stage_.update(contact, shear_x_, shear_y_, dt,
                             follow != nullptr ? follow->slip : nullptr);
  motion_ = out;
  return true;
}

DualPipelineRef::DualPipelineRef(const dsp::DualConfig& config,
                                 const std::array<dsp::Calibration, 2>& cal,
                                 const ReferenceOptions& options)
    : config_(config), cal_(cal), payback_(cal[0].slip_catchup_frames) {
  sensors_.emplace_back(config.pipeline, cal[0], options);
  sensors_.emplace_back(config.pipeline, cal[1], options);
  confidence_.configure(dsp::confidence_config(config.pipeline, cal[0]));
}

void DualPipelineRef::process(const dsp::FrameView* left, const dsp::FrameView* right,
                              std::int64_t t_ns, DualResultRef& out,
                              const std::array<FixedDecisions, 2>* follow) {
  out = DualResultRef{};
  double dt = config_.nominal_frame_period_s;
  bool gap = false;
  if (have_last_t_ && t_ns > last_t_ns_) {
    dt = static_cast<double>(t_ns - last_t_ns_) * 1e-9;
    if (dt > config_.max_frame_gap_s) {
      gap = true;
      dt = config_.nominal_frame_period_s;
    }
  }
  last_t_ns_ = t_ns;
  have_last_t_ = true;

  const dsp::FrameView* frames[2] = {left, right};
  std::array<SensorMotionRef, 2> m{};
  std::array<bool, 2> ok{false, false};
  for (int i = 0; i < 2; ++i) {
    if (frames[i] == nullptr) continue;
    bool degraded = false;
    const FixedDecisions* f = follow != nullptr ? &(*follow)[static_cast<std::size_t>(i)] : nullptr;
    if (sensors_[static_cast<std::size_t>(i)].process(
            *frames[i], dt, m[static_cast<std::size_t>(i)], degraded, f)) {
      ok[static_cast<std::size_t>(i)] = !degraded;
    }
  }

  // One fusion of the per-sensor readings: the chosen ones, or (velocity) the velocity proxy's.
  const dsp::FusionConfig& fc = config_.fusion;
  auto fuse = [&](bool velocity, bool& rotation_valid) {
    Eigen::Vector3d omega = Eigen::Vector3d::Zero();
    Eigen::Vector3d t = Eigen::Vector3d::Zero();
    rotation_valid = false;
    auto samples = [&](const SensorMotionRef& s) -> const std::vector<PointSample>& {
      return velocity ? s.velocity_samples : s.samples;
    };
    // A sensor enters ω with a defined proxy and at least one point (dsp::fuse's rule).
    auto proxy_valid = [&](const SensorMotionRef& s) {
      return ((velocity && s.velocity_differs) || s.proxy_valid) && !samples(s).empty();
    };
    auto translation = [&](const SensorMotionRef& s) {
      return velocity ? s.velocity_translation : s.translation;
    };
    auto translation_valid = [&](const SensorMotionRef& s) {
      return velocity ? s.velocity_translation_valid : s.translation_valid;
    };
    if (fc.method == dsp::FusionMethod::kJoint) {
      // Every contact point and its proxy in G, one stacked shear-only least squares about the
      // centroid of all points (dsp/fusion.cpp), λ as in solve3.
      std::vector<PointSample> all;
      Eigen::Matrix3d scale = Eigen::Matrix3d::Zero();
      Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // of the last contributing pad, in G
      int nw = 0;
      for (int i = 0; i < 2; ++i) {
        const auto& s = m[static_cast<std::size_t>(i)];
        if (!ok[static_cast<std::size_t>(i)] || !s.contact || !proxy_valid(s)) continue;
        const dsp::SensorExtrinsics& e = fc.extrinsics[static_cast<std::size_t>(i)];
        const Eigen::Vector3d p = e.p_GS(config_.finger_separation_m);
        for (const PointSample& ps : samples(s)) {
          PointSample g;
          g.q = e.R_GS * ps.q + p;
          g.v = e.R_GS * ps.v;
          g.normal = e.R_GS * ps.normal;
          all.push_back(g);
        }
        const Eigen::Vector3d& rs = velocity ? s.velocity_rotation_scale : s.rotation_scale;
        scale += e.R_GS * rs.asDiagonal() * e.R_GS.transpose();
        normal = e.R_GS * Eigen::Vector3d::UnitZ();
        ++nw;
      }
      if (!all.empty()) {
        const std::vector<PointSample> about = shifted(all, centroid(all));
        const StackedSystem sys = stack_shear_rows(about);
        const double n = static_cast<double>(all.size());
        const double lambda = fc.solve_lambda_rel * sys.A.squaredNorm() / 3.0 +
                              n * fc.solve_lever_floor_m * fc.solve_lever_floor_m;
        if (nw == 2) {
          omega = (scale / nw) * solve_stacked(sys, lambda);
          rotation_valid = true;
        } else {
          // One pad: ω along its normal only, ω = n argmin_s ‖A n s − b‖² + λ s² (dsp/fusion.cpp).
          const Eigen::VectorXd column = sys.A * normal;
          const double lever = column.squaredNorm();
          if (lever > 0.0) omega = scale * normal * (column.dot(sys.b) / (lever + lambda));
          rotation_valid = lever > 0.0;
        }
      }
      Eigen::Vector3d v_mean = Eigen::Vector3d::Zero();
      Eigen::Vector3d c_mean = Eigen::Vector3d::Zero();
      int nt = 0;
      for (int i = 0; i < 2; ++i) {
        const auto& s = m[static_cast<std::size_t>(i)];
        if (!ok[static_cast<std::size_t>(i)] || !s.contact || !translation_valid(s)) continue;
        const dsp::SensorExtrinsics& e = fc.extrinsics[static_cast<std::size_t>(i)];
        v_mean += e.R_GS * translation(s);
        const Eigen::Vector3d& point =
            velocity ? s.velocity_translation_point : s.translation_point;
        c_mean += e.R_GS * point + e.p_GS(config_.finger_separation_m);
        ++nt;
      }
      if (nt > 0) {
        t = v_mean / nt - omega.cross(c_mean / nt);
        t.z() = 0.0;
      }
    } else {
      // Paper Sec. V-B: ξ = ½(ξ₁ + S ξ₂), then R_GS of sensor 1.
      int nw = 0, nt = 0;
      for (int i = 0; i < 2; ++i) {
        const auto& s = m[static_cast<std::size_t>(i)];
        if (!ok[static_cast<std::size_t>(i)] || !s.contact) continue;
        Eigen::Vector3d sw = Eigen::Vector3d::Ones(), st = Eigen::Vector3d::Ones();
        if (i == 1) {
          sw = Eigen::Vector3d(fc.sign[0], fc.sign[1], fc.sign[2]);
          st = Eigen::Vector3d(fc.sign[3], fc.sign[4], fc.sign[5]);
        }
        if (proxy_valid(s)) {
          omega += sw.cwiseProduct(velocity ? s.velocity_omega : s.omega);
          ++nw;
        }
        if (translation_valid(s)) {
          t += st.cwiseProduct(translation(s));
          ++nt;
        }
      }
      const Eigen::Matrix3d& R1 = fc.extrinsics[0].R_GS;
      if (nw > 0) omega = R1 * (omega / nw);
      if (nt > 0) t = R1 * (t / nt);
      rotation_valid = nw > 0;
    }
    dsp::Vector6d xi;
    xi.head<3>() = omega;
    xi.tail<3>() = t;
    return xi;
  };
  out.fused = fuse(false, out.rotation_valid);

  // kAuto: slip payback of the velocity readings' fused difference (dsp/slip_payback.hpp).
  bool contact = false, differs = false, onset = false, confirmed = true, ignored = false;
  for (std::size_t i = 0; i < 2; ++i) {
    if (!ok[i]) continue;
    differs = differs || m[i].velocity_differs;
    if (!m[i].contact) continue;
    contact = true;
    onset = onset || m[i].slip_onset;
    confirmed = confirmed && m[i].stick_confirmed;
  }
  const dsp::Vector6d velocity = differs ? fuse(true, ignored) : out.fused;

  // Confidence: the chosen readings' fit (dsp::fuse's rule for entering ω) and their slip state.
  std::array<const SensorMotionRef*, 2> pads{nullptr, nullptr};
  bool slipping = false;
  for (std::size_t i = 0; i < 2; ++i) {
    if (!ok[i] || !m[i].contact || !m[i].proxy_valid || m[i].samples.empty()) continue;
    pads[i] = &m[i];
    slipping = slipping || m[i].slipping;
  }
  out.quality = fit_quality_ref(pads, fc, config_.finger_separation_m);
  out.confidence = confidence_.update(out.quality, slipping, onset, dt).value;
  const dsp::Vector6d paid =
      payback_.update(out.fused, velocity, differs, contact, onset, confirmed, gap, dt);

  // Moving average as an explicit mean over the last L frames.
  const auto L = static_cast<std::size_t>(cal_[0].moving_average_length);
  window_.push_back(paid);
  if (window_.size() > L) window_.erase(window_.begin());
  dsp::Vector6d sum = dsp::Vector6d::Zero();
  for (const auto& x : window_) sum += x;
  out.twist = sum / static_cast<double>(window_.size());

  pose_ = dsp::integrate_spatial(pose_, out.twist, dt);
  out.pose = pose_;
}

dsp::FitQuality fit_quality_ref(const std::array<const SensorMotionRef*, 2>& pads,
                                const dsp::FusionConfig& cfg, double separation_m) {
  dsp::FitQuality q;
  std::array<std::vector<PointSample>, 2> g;
  std::vector<PointSample> all;
  for (std::size_t i = 0; i < 2; ++i) {
    if (pads[i] == nullptr) continue;
    const dsp::SensorExtrinsics& e = cfg.extrinsics[i];
    for (const PointSample& ps : pads[i]->samples) {
      PointSample p;
      p.q = e.R_GS * ps.q + e.p_GS(separation_m);
      p.v = e.R_GS * ps.v;
      p.normal = e.R_GS * ps.normal;
      g[i].push_back(p);
      all.push_back(p);
    }
    q.min_points = q.pads == 0 ? pads[i]->points : std::min(q.min_points, pads[i]->points);
    ++q.pads;
  }
  if (all.empty()) return dsp::FitQuality{};
  const double n = static_cast<double>(all.size());
  const Eigen::Vector3d m_n = centroid(all);
  const StackedSystem sys = stack_shear_rows(shifted(all, m_n));
  const Eigen::Matrix3d AtA = sys.A.transpose() * sys.A;
  const double lambda = cfg.solve_lambda_rel * AtA.trace() / 3.0 +
                        n * cfg.solve_lever_floor_m * cfg.solve_lever_floor_m;
  // Per pad: the lever of its centroid along its normal, its in-plane Σ|r|², its own ω_n.
  double levers_n = 0.0, inertia = 0.0;
  std::array<Eigen::Vector3d, 2> own{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  for (std::size_t i = 0; i < 2; ++i) {
    if (g[i].empty()) continue;
    const Eigen::Vector3d c = centroid(g[i]);
    const Eigen::Vector3d nn = g[i].front().normal;
    levers_n += static_cast<double>(g[i].size()) * std::pow(nn.dot(c - m_n), 2);
    for (const PointSample& p : g[i]) {
      const Eigen::Vector3d r = p.q - c;
      inertia += (r - nn * nn.dot(r)).squaredNorm();
    }
    const StackedSystem own_sys = stack_shear_rows(shifted(g[i], c));
    const Eigen::VectorXd column = own_sys.A * nn;
    const double lever = column.squaredNorm();
    if (lever > 0.0) own[i] = nn * (pads[i]->rotation_scale.z() * column.dot(own_sys.b) / lever);
  }
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  if (q.pads == 2) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(AtA, Eigen::EigenvaluesOnly);
    const Eigen::Vector3d ev = eig.eigenvalues();
    q.rank = 3;
    q.rcond = ev(2) > 0.0 ? std::max(ev(0), 0.0) / ev(2) : 0.0;
    q.rcond_expected = levers_n > 0.0 && inertia > 0.0
                           ? std::min(levers_n, inertia) / std::max(levers_n, inertia)
                           : 0.0;
    q.disagreement_m_s = (own[0] - own[1]).dot(g[0].front().normal) * std::sqrt(inertia / n);
    w = solve_stacked(sys, lambda);
  } else {
    const Eigen::Vector3d nn = all.front().normal;
    const Eigen::VectorXd column = sys.A * nn;
    const double lever = column.squaredNorm();
    q.rank = lever > 0.0 ? 1 : 0;
    q.rcond = q.rcond_expected = 1.0;
    if (lever > 0.0) w = nn * (column.dot(sys.b) / (lever + lambda));
  }
  // Residual of ṽ = t̄ + ω × q on the tangential components, t̄ the mean proxy, point by point.
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  for (const PointSample& p : all) t += p.v;
  t /= n;
  double e = 0.0;
  for (const PointSample& p : all) {
    const Eigen::Vector3d r = p.v - t - w.cross(p.q - m_n);
    e += (r - p.normal * p.normal.dot(r)).squaredNorm();
  }
  const double dof = 2.0 * n - q.rank - 2.0;
  q.residual_speed_m_s =
      dof > 0.0 ? std::sqrt(e / dof / n) : std::numeric_limits<double>::infinity();
  return q;
}

}  // namespace tacse3::dsp_ref
