// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: truth interpolation/differentiation and error metrics.
#include "tacse3/tools/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace tacse3::tools {

namespace rec = tacse3::recording;

namespace {
constexpr double kDeg = 180.0 / std::numbers::pi;
}

dsp::Pose to_pose(const rec::TruthSample& s) noexcept {
  dsp::Pose p;
  p.q = Eigen::Quaterniond(s.qw, s.qx, s.qy, s.qz).normalized();
  p.p = Eigen::Vector3d(s.px, s.py, s.pz);
  return p;
}

dsp::Pose truth_pose_at(const std::vector<rec::TruthSample>& truth, std::int64_t t_ns) {
  if (truth.empty()) return dsp::Pose{};
  if (t_ns <= truth.front().t_ns) return to_pose(truth.front());
  if (t_ns >= truth.back().t_ns) return to_pose(truth.back());
  const auto it =
      std::lower_bound(truth.begin(), truth.end(), t_ns,
                       [](const rec::TruthSample& s, std::int64_t t) { return s.t_ns < t; });
  if (it->t_ns == t_ns) return to_pose(*it);
  const rec::TruthSample& b = *it;
  const rec::TruthSample& a = *(it - 1);
  const double u = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  const dsp::Pose pa = to_pose(a), pb = to_pose(b);
  dsp::Pose p;
  p.q = pa.q.slerp(u, pb.q).normalized();
  p.p = (1.0 - u) * pa.p + u * pb.p;
  return p;
}

std::vector<dsp::Vector6d> truth_twists(const std::vector<rec::TruthSample>& truth,
                                        const std::vector<std::int64_t>& t_ns) {
  std::vector<dsp::Vector6d> out(t_ns.size(), dsp::Vector6d::Zero());
  if (truth.empty() || t_ns.size() < 2) return out;
  std::vector<dsp::Pose> poses(t_ns.size());
  for (std::size_t i = 0; i < t_ns.size(); ++i) poses[i] = truth_pose_at(truth, t_ns[i]);
  for (std::size_t i = 0; i < t_ns.size(); ++i) {
    const std::size_t a = i == 0 ? 0 : i - 1;
    const std::size_t b = i + 1 < t_ns.size() ? i + 1 : i;
    if (a == b) continue;
    const double dt = static_cast<double>(t_ns[b] - t_ns[a]) * 1e-9;
    if (!(dt > 0.0)) continue;
    // T(b) = exp(ξ̂ dt) T(a)  ⇒  ξ = log(T(b) T(a)⁻¹) / dt  (spatial twist in G).
    const dsp::Pose rel = dsp::compose(poses[b], dsp::inverse(poses[a]));
    out[i] = dsp::se3_log(rel) / dt;
  }
  return out;
}

double rotation_error_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) noexcept {
  const double d = std::clamp(std::abs(a.normalized().dot(b.normalized())), 0.0, 1.0);
  return 2.0 * std::acos(d) * kDeg;
}

double rotation_angle_deg(const Eigen::Quaterniond& q) noexcept {
  return rotation_error_deg(q, Eigen::Quaterniond::Identity());
}

PoseErrors pose_errors(const std::vector<dsp::Pose>& estimate,
                       const std::vector<rec::TruthSample>& truth,
                       const std::vector<std::int64_t>& t_ns) {
  PoseErrors e;
  const std::size_t n = std::min(estimate.size(), t_ns.size());
  if (n == 0 || truth.empty()) return e;
  for (std::size_t i = 0; i < n; ++i) {
    const dsp::Pose t = truth_pose_at(truth, t_ns[i]);
    const double r = rotation_error_deg(estimate[i].q, t.q);
    const double p = (estimate[i].p - t.p).norm() * 1e3;
    e.max_rotation_error_deg = std::max(e.max_rotation_error_deg, r);
    e.max_translation_error_mm = std::max(e.max_translation_error_mm, p);
    if (i + 1 == n) {
      e.final_rotation_error_deg = r;
      e.final_translation_error_mm = p;
      e.true_rotation_deg = rotation_angle_deg(t.q);
      e.estimated_rotation_deg = rotation_angle_deg(estimate[i].q);
      e.true_translation_mm = t.p.norm() * 1e3;
      e.estimated_translation_mm = estimate[i].p.norm() * 1e3;
      e.final_rotation_vector_deg = dsp::so3_log(estimate[i].q) * kDeg;
      e.true_rotation_vector_deg = dsp::so3_log(t.q) * kDeg;
    }
  }
  return e;
}

namespace {

// The truth's own noise, per component (deg or mm): from second differences, which a smooth
// motion hardly moves (a 10 mm minimum-jerk move in 1 s at 120 Hz: < 0.005 mm) while white noise
// of sigma gives sqrt(6) sigma; robust through the median absolute value (1.4826 MAD).
double truth_noise_sigma(const std::vector<Eigen::Vector3d>& x) {
  std::vector<double> d;
  for (std::size_t i = 1; i + 1 < x.size(); ++i) {
    const Eigen::Vector3d a = x[i + 1] - 2.0 * x[i] + x[i - 1];
    for (int k = 0; k < 3; ++k) d.push_back(std::abs(a[k]));
  }
  if (d.empty()) return 0.0;
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return 1.4826 * d[d.size() / 2] / std::sqrt(6.0);
}

}  // namespace

std::int64_t motion_start_ns(const std::vector<rec::TruthSample>& truth) {
  if (truth.empty()) return 0;
  const dsp::Pose first = to_pose(truth.front());
  std::vector<double> rot(truth.size()), trans(truth.size());
  std::vector<Eigen::Vector3d> rv(truth.size()), pv(truth.size());
  double rot_max = 0.0, trans_max = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const dsp::Pose p = to_pose(truth[i]);
    rot[i] = rotation_error_deg(p.q, first.q);
    trans[i] = (p.p - first.p).norm() * 1e3;
    rv[i] = dsp::so3_log(p.q) * kDeg;
    pv[i] = p.p * 1e3;
    rot_max = std::max(rot_max, rot[i]);
    trans_max = std::max(trans_max, trans[i]);
  }
  // A bar of kNoiseSigmas sigma keeps the distance between two noisy 3-D samples (the row and the
  // first row) below it: a logged robot pose's noise does not start the motion.
  constexpr double kShare = 0.02, kRotFloorDeg = 0.05, kTransFloorMm = 0.02, kNoiseSigmas = 8.0;
  const double rot_bar =
      std::max({kShare * rot_max, kRotFloorDeg, kNoiseSigmas * truth_noise_sigma(rv)});
  const double trans_bar =
      std::max({kShare * trans_max, kTransFloorMm, kNoiseSigmas * truth_noise_sigma(pv)});
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if ((rot_max >= rot_bar && rot[i] >= rot_bar) ||
        (trans_max >= trans_bar && trans[i] >= trans_bar)) {
      return truth[i].t_ns;
    }
  }
  return truth.front().t_ns;
}

namespace {

// The median frame period (ns) of the run's times; 0 with fewer than two frames.
std::int64_t median_period_ns(const std::vector<std::int64_t>& t_ns) {
  std::vector<std::int64_t> d;
  for (std::size_t i = 1; i < t_ns.size(); ++i) d.push_back(t_ns[i] - t_ns[i - 1]);
  if (d.empty()) return 0;
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return std::max<std::int64_t>(d[d.size() / 2], 0);
}

struct LagScore {
  double rms = 0.0, max = 0.0;
};

}  // namespace

TrackingError tracking_error(const std::vector<dsp::Pose>& estimate,
                             const std::vector<rec::TruthSample>& truth,
                             const std::vector<std::int64_t>& t_ns, double max_lag_s) {
  TrackingError e;
  const std::size_t n = std::min(estimate.size(), t_ns.size());
  if (n == 0 || truth.empty()) return e;
  e.start_ns = motion_start_ns(truth);
  std::size_t first = 0;
  while (first < n && t_ns[first] < e.start_ns) ++first;
  if (first == n) return e;
  e.valid = true;
  e.frames = n - first;
  const std::int64_t period = median_period_ns(t_ns);
  const int lags = period > 0 ? static_cast<int>(std::floor(max_lag_s * 1e9 / period + 1e-9)) : 0;
  for (int k = 0; k <= lags; ++k) {
    LagScore rot, trans;
    for (std::size_t i = first; i < n; ++i) {
      const dsp::Pose t = truth_pose_at(truth, t_ns[i] - k * period);
      const double r = rotation_error_deg(estimate[i].q, t.q);
      const double p = (estimate[i].p - t.p).norm() * 1e3;
      rot.rms += r * r;
      trans.rms += p * p;
      rot.max = std::max(rot.max, r);
      trans.max = std::max(trans.max, p);
    }
    rot.rms = std::sqrt(rot.rms / static_cast<double>(e.frames));
    trans.rms = std::sqrt(trans.rms / static_cast<double>(e.frames));
    const double lag_s = static_cast<double>(k * period) * 1e-9;
    if (k == 0 || rot.rms < e.rotation_rms_deg) {
      e.rotation_rms_deg = rot.rms;
      e.rotation_max_deg = rot.max;
      e.rotation_lag_s = lag_s;
    }
    if (k == 0 || trans.rms < e.translation_rms_mm) {
      e.translation_rms_mm = trans.rms;
      e.translation_max_mm = trans.max;
      e.translation_lag_s = lag_s;
    }
  }
  return e;
}

void SlipScore::add(bool detected, bool label) noexcept {
  if (detected && label) ++true_slip;
  if (!detected && !label) ++true_stick;
  if (detected && !label) ++false_slip;
  if (!detected && label) ++false_stick;
}

void SlipScore::merge(const SlipScore& o) noexcept {
  true_slip += o.true_slip;
  true_stick += o.true_stick;
  false_slip += o.false_slip;
  false_stick += o.false_stick;
}

}  // namespace tacse3::tools
