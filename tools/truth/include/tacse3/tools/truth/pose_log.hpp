// SPDX-License-Identifier: Apache-2.0
// tacse3-truth: rigid poses, robot pose logs (CSV) and their interpolation (docs/truth.md).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace tacse3::tools::truth {

// A rigid transform T = (q, p): x' = q x + p. T_ab is frame b's pose in frame a.
struct Pose {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
};
Pose operator*(const Pose& a, const Pose& b) noexcept;
Pose inverse(const Pose& a) noexcept;

// The rotation of a rotation vector (axis times angle in rad, as a UR controller logs it).
Eigen::Quaterniond from_rotation_vector(const Eigen::Vector3d& r) noexcept;
// The angle of q in rad, in [0, pi].
double rotation_angle(const Eigen::Quaterniond& q) noexcept;

// A quaternion is accepted as unit when its norm is within this of 1, as in truth.csv
// (docs/recording-format.md); it is then normalised.
inline constexpr double kUnitTolerance = 1e-3;

// A pose log: CSV with a header naming a time column (`t` seconds or `t_ns` integer ns) and the
// pose (`x,y,z` m with `qw,qx,qy,qz` or with the rotation vector `rx,ry,rz`). Other columns are
// ignored. Rows strictly increasing in time, any spacing.
struct PoseLog {
  enum class Rotation { kQuaternion, kRotationVector };
  std::string name;  // the file, for messages
  Rotation rotation = Rotation::kQuaternion;
  std::vector<std::int64_t> t_ns;
  std::vector<Pose> pose;

  std::size_t size() const noexcept { return t_ns.size(); }
  // True when [a_ns, b_ns] lies within the log's first and last sample.
  bool covers(std::int64_t a_ns, std::int64_t b_ns) const noexcept;
  // The pose at t_ns (inside the log): slerp between the neighbouring orientations, linear
  // between the positions.
  Pose at(std::int64_t t_ns) const noexcept;
};

// Parses the text of a log; `name` goes into the messages. Returns "" or the error, naming the
// file and the line.
std::string parse_pose_log(std::string_view text, const std::string& name, PoseLog* out);
// Reads and parses a file (a regular file of at most kMaxLogBytes).
inline constexpr std::size_t kMaxLogBytes = std::size_t{1} << 30;
std::string read_pose_log(const std::filesystem::path& file, PoseLog* out);

// Parses "x y z qw qx qy qz" (m, unit quaternion) as given on the command line.
std::string parse_pose_text(std::string_view text, Pose* out);

}  // namespace tacse3::tools::truth
