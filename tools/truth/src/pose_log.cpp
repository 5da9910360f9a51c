// SPDX-License-Identifier: Apache-2.0
// tacse3-truth: pose algebra, the pose-log CSV reader and slerp interpolation.
#include "tacse3/tools/truth/pose_log.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <optional>

#include "tacse3/fileio/file_io.hpp"

namespace tacse3::tools::truth {

Pose operator*(const Pose& a, const Pose& b) noexcept {
  Pose c;
  c.q = (a.q * b.q).normalized();
  c.p = a.q * b.p + a.p;
  return c;
}

Pose inverse(const Pose& a) noexcept {
  Pose c;
  c.q = a.q.conjugate();
  c.p = -(c.q * a.p);
  return c;
}

Eigen::Quaterniond from_rotation_vector(const Eigen::Vector3d& r) noexcept {
  const double angle = r.norm();
  // sin(a/2)/a -> 1/2 as a -> 0 (series to a^2: exact at double precision below 1e-4).
  const double k = angle < 1e-4 ? 0.5 - angle * angle / 48.0 : std::sin(0.5 * angle) / angle;
  return Eigen::Quaterniond(std::cos(0.5 * angle), k * r.x(), k * r.y(), k * r.z());
}

double rotation_angle(const Eigen::Quaterniond& q) noexcept {
  return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w()));
}

bool PoseLog::covers(std::int64_t a_ns, std::int64_t b_ns) const noexcept {
  return !t_ns.empty() && a_ns >= t_ns.front() && b_ns <= t_ns.back();
}

Pose PoseLog::at(std::int64_t t) const noexcept {
  if (t <= t_ns.front()) return pose.front();
  if (t >= t_ns.back()) return pose.back();
  const auto it = std::upper_bound(t_ns.begin(), t_ns.end(), t);
  const std::size_t b = static_cast<std::size_t>(it - t_ns.begin());
  const std::size_t a = b - 1;
  const double u = static_cast<double>(t - t_ns[a]) / static_cast<double>(t_ns[b] - t_ns[a]);
  Pose r;
  r.q = pose[a].q.slerp(u, pose[b].q).normalized();  // Eigen's slerp takes the shorter arc
  r.p = (1.0 - u) * pose[a].p + u * pose[b].p;
  return r;
}

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> f;
  for (;;) {
    const std::size_t c = line.find(',');
    f.push_back(trim(line.substr(0, c)));
    if (c == std::string_view::npos) return f;
    line.remove_prefix(c + 1);
  }
}

bool to_double(std::string_view s, double* out) {
  const auto r = std::from_chars(s.data(), s.data() + s.size(), *out);
  return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(*out);
}

bool to_int64(std::string_view s, std::int64_t* out) {
  const auto r = std::from_chars(s.data(), s.data() + s.size(), *out);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

// Column indices of the fields the log needs, found by header name.
struct Columns {
  bool seconds = false;  // `t` (s) rather than `t_ns`
  std::size_t time = 0;
  std::array<std::size_t, 3> xyz{};
  std::array<std::size_t, 4> rot{};  // qw qx qy qz, or rx ry rz (3 used)
  std::size_t count = 0;             // fields per row
};

std::optional<std::size_t> find(const std::vector<std::string_view>& h, std::string_view name) {
  const auto it = std::find(h.begin(), h.end(), name);
  if (it == h.end()) return std::nullopt;
  return static_cast<std::size_t>(it - h.begin());
}

std::string parse_header(std::string_view line, const std::string& name, Columns* c,
                         PoseLog::Rotation* rotation) {
  const std::vector<std::string_view> h = split(line);
  const std::string where = name + " line 1 (header): ";
  c->count = h.size();
  const auto t = find(h, "t"), t_ns = find(h, "t_ns");
  if (t.has_value() == t_ns.has_value()) {
    return where + "needs exactly one time column, `t` (seconds) or `t_ns` (integer ns)";
  }
  c->seconds = t.has_value();
  c->time = t ? *t : *t_ns;
  const char* xyz[3] = {"x", "y", "z"};
  for (std::size_t i = 0; i < 3; ++i) {
    const auto k = find(h, xyz[i]);
    if (!k) return where + "no column `" + xyz[i] + "` (the position x,y,z in metres)";
    c->xyz[i] = *k;
  }
  const char* quat[4] = {"qw", "qx", "qy", "qz"};
  const char* rvec[3] = {"rx", "ry", "rz"};
  std::array<std::optional<std::size_t>, 4> q{}, r{};
  int nq = 0, nr = 0;
  for (std::size_t i = 0; i < 4; ++i) nq += (q[i] = find(h, quat[i])).has_value() ? 1 : 0;
  for (std::size_t i = 0; i < 3; ++i) nr += (r[i] = find(h, rvec[i])).has_value() ? 1 : 0;
  if (nq == 4 && nr == 0) {
    *rotation = PoseLog::Rotation::kQuaternion;
    for (std::size_t i = 0; i < 4; ++i) c->rot[i] = *q[i];
  } else if (nr == 3 && nq == 0) {
    *rotation = PoseLog::Rotation::kRotationVector;
    for (std::size_t i = 0; i < 3; ++i) c->rot[i] = *r[i];
  } else {
    return where + "needs the orientation as `qw,qx,qy,qz` (unit quaternion) or as `rx,ry,rz` " +
           "(rotation vector), exactly one of the two";
  }
  return {};
}

std::string parse_row(const std::vector<std::string_view>& f, const Columns& c,
                      PoseLog::Rotation rotation, const std::string& where, std::int64_t* t,
                      Pose* pose) {
  if (f.size() != c.count) {
    return where + std::to_string(f.size()) + " fields, the header has " + std::to_string(c.count);
  }
  if (c.seconds) {
    double s = 0.0;
    if (!to_double(f[c.time], &s) || std::abs(s) > 9e9) {
      return where + "`t` must be a finite number of seconds, got \"" + std::string(f[c.time]) +
             "\"";
    }
    *t = std::llround(s * 1e9);
  } else if (!to_int64(f[c.time], t)) {
    return where + "`t_ns` must be an integer, got \"" + std::string(f[c.time]) + "\"";
  }
  const int nrot = rotation == PoseLog::Rotation::kQuaternion ? 4 : 3;
  double v[7];
  for (int i = 0; i < 3 + nrot; ++i) {
    const std::size_t k =
        i < 3 ? c.xyz[static_cast<std::size_t>(i)] : c.rot[static_cast<std::size_t>(i - 3)];
    if (!to_double(f[k], &v[i])) {
      return where + "field " + std::to_string(k + 1) + " must be a finite number, got \"" +
             std::string(f[k]) + "\"";
    }
  }
  pose->p = Eigen::Vector3d(v[0], v[1], v[2]);
  if (rotation == PoseLog::Rotation::kRotationVector) {
    pose->q = from_rotation_vector(Eigen::Vector3d(v[3], v[4], v[5]));
    return {};
  }
  const Eigen::Quaterniond q(v[3], v[4], v[5], v[6]);
  if (std::abs(q.norm() - 1.0) > kUnitTolerance) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.6f", q.norm());
    return where + "quaternion is not unit (norm " + buf + ")";
  }
  pose->q = q.normalized();
  return {};
}

}  // namespace

std::string parse_pose_log(std::string_view text, const std::string& name, PoseLog* out) {
  PoseLog log;
  log.name = name;
  Columns c;
  std::size_t line_no = 0;
  bool header = true, blank = false;
  while (!text.empty()) {
    const std::size_t nl = text.find('\n');
    std::string_view line = text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    ++line_no;
    if (trim(line).empty()) {
      blank = true;  // allowed only at the end
      continue;
    }
    const std::string where = name + " line " + std::to_string(line_no) + ": ";
    if (blank) return name + " line " + std::to_string(line_no - 1) + ": blank line inside the log";
    if (header) {
      if (std::string e = parse_header(line, name, &c, &log.rotation); !e.empty()) return e;
      header = false;
      continue;
    }
    std::int64_t t = 0;
    Pose p;
    if (std::string e = parse_row(split(line), c, log.rotation, where, &t, &p); !e.empty()) {
      return e;
    }
    if (!log.t_ns.empty() && t <= log.t_ns.back()) {
      return where + "time " + std::to_string(t) + " ns is not after the previous row's " +
             std::to_string(log.t_ns.back()) + " ns: the log must be strictly increasing in time";
    }
    log.t_ns.push_back(t);
    log.pose.push_back(p);
  }
  if (header) return name + ": empty; a pose log starts with a header line";
  if (log.size() < 2) return name + ": fewer than two poses; nothing to interpolate";
  *out = std::move(log);
  return {};
}

std::string read_pose_log(const std::filesystem::path& file, PoseLog* out) {
  std::string text;
  const fileio::ReadResult r = fileio::read_regular_file(file, kMaxLogBytes, &text);
  if (!r.ok()) {
    switch (r.error) {
      case fileio::ReadError::kNotFound:
        return file.string() + ": no such file";
      case fileio::ReadError::kNotRegular:
        return file.string() + ": is " + r.kind + ", not a regular file";
      case fileio::ReadError::kTooLarge:
        return file.string() + ": larger than " + fileio::size_text(kMaxLogBytes);
      default:
        return file.string() + ": cannot read" + fileio::os_error(r.os_errno);
    }
  }
  return parse_pose_log(text, file.string(), out);
}

std::string parse_pose_text(std::string_view text, Pose* out) {
  std::array<double, 7> v{};
  std::size_t n = 0;
  while (true) {
    while (!text.empty() && (text.front() == ' ' || text.front() == ',')) text.remove_prefix(1);
    if (text.empty()) break;
    std::size_t end = text.find_first_of(" ,");
    if (end == std::string_view::npos) end = text.size();
    if (n == v.size() || !to_double(text.substr(0, end), &v[n])) {
      return "expected seven numbers \"x y z qw qx qy qz\" (m, unit quaternion)";
    }
    ++n;
    text.remove_prefix(end);
  }
  if (n != v.size()) return "expected seven numbers \"x y z qw qx qy qz\" (m, unit quaternion)";
  const Eigen::Quaterniond q(v[3], v[4], v[5], v[6]);
  if (std::abs(q.norm() - 1.0) > kUnitTolerance) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "quaternion is not unit (norm %.6f)", q.norm());
    return buf;
  }
  out->q = q.normalized();
  out->p = Eigen::Vector3d(v[0], v[1], v[2]);
  return {};
}

}  // namespace tacse3::tools::truth
