// SPDX-License-Identifier: Apache-2.0
// tacse3-truth: the offset between the robot log's clock and the recording's (docs/truth.md).
// Convention: robot-log time = recording time + offset.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "tacse3/tools/truth/pose_log.hpp"

namespace tacse3::tools::truth {

// From a `candump -L` log taken on the robot's clock: each complete cycle of node 1 (11-bit
// identifiers) pairs its Timestamp frame's SampleTime (the board's clock, the recording's clock)
// with that frame's arrival stamp (the cycle's first frame). arrival = sample + latency +
// offset, where latency is the firmware's sample-to-CAN-driver latency, taken as the median of
// the LatencyP50 values the StatusTiming frames report (0 when none reports one). The frame's
// own bus time (0.13 ms at 1 Mbit/s, 0.26 ms at 500 kbit/s) is not modelled.
struct CanSync {
  std::int64_t offset_ns = 0;
  std::size_t cycles = 0;           // complete cycles used
  std::size_t latency_reports = 0;  // StatusTiming frames with a LatencyP50
  double latency_s = 0.0;           // latency subtracted
  double spread_s = 0.0;            // robust sigma (1.4826 MAD) of arrival - sample
};
// `first_ns`, `last_ns`: the recording's span; cycles outside it are ignored, and a log with
// none inside is refused (it is not this recording's log).
std::string sync_by_can_log(std::string_view text, const std::string& name, std::int64_t first_ns,
                            std::int64_t last_ns, CanSync* out);
inline constexpr std::size_t kMaxCanLogBytes = std::size_t{1} << 30;
std::string read_can_sync(const std::filesystem::path& file, std::int64_t first_ns,
                          std::int64_t last_ns, CanSync* out);

// Angular speed (rad/s) over each frame interval: angle(q[i-1]^-1 q[i]) / (t[i] - t[i-1]) at
// element i; element 0 is 0.
std::vector<double> interval_speed(const std::vector<std::int64_t>& t_ns,
                                   const std::vector<Eigen::Quaterniond>& q);

// Noise of a speed series, from its successive differences: 1.4826 MAD(diff) / sqrt(2). A
// smooth motion barely changes between frames, so this sees the noise, not the motion.
double difference_noise(const std::vector<double>& s);

// From the shape of the angular speed. `speed[i]` is the recording's angular speed over the
// frame interval (t_ns[i-1], t_ns[i]] as the pipeline measures it (its scale does not matter;
// speed[0] is unused). The Pearson correlation between it and the log's speed over the same
// intervals read at t + offset is maximised over every offset at which the log covers the
// recording: first on a grid of one frame period, then by golden-section search within one period
// of the best grid point.
struct AutoSync {
  std::int64_t offset_ns = 0;
  double correlation = 0.0;       // at the offset
  double runner_up = 0.0;         // best correlation outside the main peak (-1: none)
  std::int64_t runner_up_ns = 0;  // its offset
  double motion_snr = 0.0;        // smaller of the two series' range / difference_noise
};
// Less correlation than this is refused: the speeds share less than a quarter of their variance.
inline constexpr double kMinCorrelation = 0.5;
// A second peak this close to the best is refused: the motion repeats and the offset is
// ambiguous.
inline constexpr double kMaxRunnerUpRatio = 0.9;
// A series whose range is less than this many noise sigmas has too little motion to sync on.
inline constexpr double kMinMotionSnr = 10.0;
std::string sync_by_correlation(const std::vector<std::int64_t>& t_ns,
                                const std::vector<double>& speed, const PoseLog& log,
                                AutoSync* out);

}  // namespace tacse3::tools::truth
