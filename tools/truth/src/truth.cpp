// SPDX-License-Identifier: Apache-2.0
// tacse3-truth: composes the logged poses into the object's motion in G, writes truth.csv rows.
#include "tacse3/tools/truth/truth.hpp"

#include <cstdio>

namespace tacse3::tools::truth {

namespace {

std::string coverage_error(const PoseLog& log, std::int64_t a_ns, std::int64_t b_ns) {
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                ": covers log time %.6f .. %.6f s, but the recording needs %.6f .. %.6f s "
                "(frame times + clock offset); record the robot for the whole recording or "
                "check the clock offset",
                static_cast<double>(log.t_ns.front()) * 1e-9,
                static_cast<double>(log.t_ns.back()) * 1e-9, static_cast<double>(a_ns) * 1e-9,
                static_cast<double>(b_ns) * 1e-9);
  return log.name + buf;
}

}  // namespace

std::string make_truth(const Rig& rig, const std::vector<std::int64_t>& frame_t_ns,
                       std::int64_t offset_ns, std::vector<recording::TruthSample>* out) {
  if (frame_t_ns.empty()) return "the recording has no frame";
  const std::int64_t a = frame_t_ns.front() + offset_ns, b = frame_t_ns.back() + offset_ns;
  for (const PoseLog* log : {rig.gripper, rig.object}) {
    if (log != nullptr && !log->covers(a, b)) return coverage_error(*log, a, b);
  }
  auto grasp = [&](std::int64_t t) {
    const Pose tcp = rig.gripper != nullptr ? rig.gripper->at(t) : rig.fixed_tcp;
    return tcp * rig.tcp_to_grasp;
  };
  auto object = [&](std::int64_t t) { return rig.object != nullptr ? rig.object->at(t) : Pose{}; };
  // Constant right factor T_wo(t0)^-1 T_wg(t0).
  const Pose first = inverse(object(a)) * grasp(a);
  std::vector<recording::TruthSample> rows;
  rows.reserve(frame_t_ns.size());
  Eigen::Quaterniond prev = Eigen::Quaterniond::Identity();
  for (const std::int64_t t : frame_t_ns) {
    const std::int64_t tl = t + offset_ns;
    Pose m = inverse(grasp(tl)) * object(tl) * first;
    if (m.q.coeffs().dot(prev.coeffs()) < 0.0) m.q.coeffs() = -m.q.coeffs();
    prev = m.q;
    rows.push_back({t, m.q.w(), m.q.x(), m.q.y(), m.q.z(), m.p.x(), m.p.y(), m.p.z()});
  }
  *out = std::move(rows);
  return {};
}

std::string truth_csv(const std::vector<recording::TruthSample>& rows) {
  std::string s = "t_ns,qw,qx,qy,qz,px,py,pz\n";
  char buf[256];
  for (const auto& r : rows) {
    std::snprintf(buf, sizeof(buf), "%lld,%.12f,%.12f,%.12f,%.12f,%.12f,%.12f,%.12f\n",
                  static_cast<long long>(r.t_ns), r.qw, r.qx, r.qy, r.qz, r.px, r.py, r.pz);
    s += buf;
  }
  return s;
}

}  // namespace tacse3::tools::truth
