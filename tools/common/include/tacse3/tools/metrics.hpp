// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: truth poses and twists, pose/rotation errors and slip-detector scores.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tacse3/dsp/se3.hpp"
#include "tacse3/recording/recording.hpp"

namespace tacse3::tools {

// A truth.csv row as a dsp pose (metres).
dsp::Pose to_pose(const recording::TruthSample& s) noexcept;

// Truth pose at t_ns: exact row, or interpolated between the two rows around it (slerp, linear
// position); clamped to the first/last row outside the table. Identity for an empty table.
dsp::Pose truth_pose_at(const std::vector<recording::TruthSample>& truth, std::int64_t t_ns);

// Spatial twist of the truth in G at each time of `t_ns` (rad/s, m/s): central difference
// ξ = log(T(t+) T(t−)⁻¹) / (t+ − t−) over the neighbouring frame times (one-sided at the ends).
// It is the quantity the pipeline's DualResult::twist estimates.
std::vector<dsp::Vector6d> truth_twists(const std::vector<recording::TruthSample>& truth,
                                        const std::vector<std::int64_t>& t_ns);

// Geodesic angle between two orientations, degrees, in [0, 180].
double rotation_error_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) noexcept;
// Rotation angle of q, degrees, in [0, 180].
double rotation_angle_deg(const Eigen::Quaterniond& q) noexcept;

// Errors of an estimated pose trajectory against the truth (same frame times).
struct PoseErrors {
  double final_rotation_error_deg = 0.0;    // geodesic angle at the last frame
  double max_rotation_error_deg = 0.0;      // largest geodesic angle over the run
  double final_translation_error_mm = 0.0;  // ‖p_est − p_true‖ at the last frame
  double max_translation_error_mm = 0.0;
  double true_rotation_deg = 0.0;       // truth rotation angle at the last frame
  double estimated_rotation_deg = 0.0;  // estimated rotation angle at the last frame
  double true_translation_mm = 0.0;
  double estimated_translation_mm = 0.0;
  Eigen::Vector3d final_rotation_vector_deg = Eigen::Vector3d::Zero();  // est, axis·angle
  Eigen::Vector3d true_rotation_vector_deg = Eigen::Vector3d::Zero();
};

PoseErrors pose_errors(const std::vector<dsp::Pose>& estimate,
                       const std::vector<recording::TruthSample>& truth,
                       const std::vector<std::int64_t>& t_ns);

// The per-frame tracking error a controller sees: for every frame from the motion's start to the
// end of the run, the geodesic angle between the estimated and true orientation (and the distance
// between the positions), with the truth delayed by the lag, in whole frame periods from 0 to
// max_lag_s, that gives the lowest RMS. Rotation and translation each pick their own lag.
struct TrackingError {
  bool valid = false;         // there were frames from the motion's start on
  std::size_t frames = 0;     // frames scored
  std::int64_t start_ns = 0;  // the motion's start (motion_start_ns)
  double rotation_rms_deg = 0.0;
  double rotation_max_deg = 0.0;
  double rotation_lag_s = 0.0;
  double translation_rms_mm = 0.0;
  double translation_max_mm = 0.0;
  double translation_lag_s = 0.0;
};

// When the truth starts to move: the first row whose rotation from the first row reaches 2 % of
// the largest over the table, or whose translation reaches 2 % of the largest; at least 0.05 deg
// and 0.02 mm, and at least 8 sigma of the truth's own noise (from its second differences), so
// a real rig's pose noise does not start it. The first row's time when the truth never moves
// that far.
std::int64_t motion_start_ns(const std::vector<recording::TruthSample>& truth);

TrackingError tracking_error(const std::vector<dsp::Pose>& estimate,
                             const std::vector<recording::TruthSample>& truth,
                             const std::vector<std::int64_t>& t_ns, double max_lag_s = 0.05);

// Confusion counts of a per-frame, per-sensor stick/slip detector against sim_labels.csv
// (only frames labelled in_contact are scored).
struct SlipScore {
  std::int64_t true_slip = 0, true_stick = 0, false_slip = 0, false_stick = 0;
  std::int64_t scored() const noexcept { return true_slip + true_stick + false_slip + false_stick; }
  double accuracy() const noexcept {
    return scored() ? static_cast<double>(true_slip + true_stick) / static_cast<double>(scored())
                    : 0.0;
  }
  void add(bool detected, bool label) noexcept;
  void merge(const SlipScore& o) noexcept;
};

}  // namespace tacse3::tools
