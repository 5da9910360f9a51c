// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: shared value types of the tactile simulator (sensors, poses, twists, pad frames).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

namespace tacse3::sim {

// The two mirrored DM-Tac pads of the gripper (docs/recording-format.md, "Frames").
enum class Sensor : std::uint8_t { kLeft = 0, kRight = 1 };
inline constexpr int kSensorCount = 2;

constexpr const char* to_string(Sensor s) noexcept {
  return s == Sensor::kLeft ? "left" : "right";
}
constexpr int index_of(Sensor s) noexcept {
  return static_cast<int>(s);
}

// A rigid motion in the gripper frame G. It maps the G coordinates a point of the object had at
// the first frame to its G coordinates now: g = q * g0 + p. Millimetres inside the simulator;
// truth.csv stores metres.
struct Pose {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();

  Eigen::Vector3d apply(const Eigen::Vector3d& g0) const noexcept { return q * g0 + p; }
  Eigen::Vector3d apply_inverse(const Eigen::Vector3d& g) const noexcept {
    return q.conjugate() * (g - p);
  }
};

// Spatial twist in G: the object point currently at g moves with velocity w x g + v.
// w in rad/s, v in mm/s.
struct Twist {
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();

  Eigen::Vector3d velocity_at(const Eigen::Vector3d& g) const noexcept { return w.cross(g) + v; }
};

// Pad frame of a sensor: (u, v, n) with u = image x, v = image y and n the pad's outward normal
// (from the grasp centre into the gel). Left pad: identity. Right pad (mirrored): u = Gx,
// v = -Gy, n = -Gz, i.e. a rotation by pi about x, so both pad frames are right-handed.
// Returns the rotation taking G vectors to pad coordinates.
inline Eigen::Matrix3d pad_rotation(Sensor s) noexcept {
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  if (s == Sensor::kRight) {
    r(1, 1) = -1.0;
    r(2, 2) = -1.0;
  }
  return r;
}

// Camera geometry of one DM-Tac-like sensor. Pixel (i, j) is column i, row j; the pad point it
// sees lies at ((i - (width-1)/2) * P, (j - (height-1)/2) * P) mm in its pad frame.
struct RigSpec {
  double pixel_pitch_mm = 0.1;  // P: 320 x 240 px -> a 32 x 24 mm pad
  int width = 320;              // multiples of kCellPx
  int height = 240;
};

// Side of the simulator's physics grid cell in pixels: cell (i, j) is centred on pixel
// (4 i + 1.5, 4 j + 1.5), so the grid is symmetric about the image centre.
inline constexpr int kCellPx = 4;

// Result of the per-frame calls; they never throw and never allocate.
enum class SimStatus : std::uint8_t {
  kOk = 0,
  kBadBuffer,      // output span too small or channel count not 1 or 3
  kTimeBackwards,  // t earlier than the last step of that sensor (call reset() first)
  kCodecFailed,    // the MJPEG round trip of the frame failed
};

constexpr const char* to_string(SimStatus s) noexcept {
  switch (s) {
    case SimStatus::kOk:
      return "ok";
    case SimStatus::kBadBuffer:
      return "output buffer too small or unsupported channel count";
    case SimStatus::kTimeBackwards:
      return "time earlier than the previous step of this sensor; call reset() first";
    case SimStatus::kCodecFailed:
      return "the MJPEG round trip of the frame failed";
  }
  return "unknown status";
}

}  // namespace tacse3::sim
