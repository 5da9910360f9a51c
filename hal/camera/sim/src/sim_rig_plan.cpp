// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: the simulated rig's plan mode: one plan motion per recording, the robot's log.
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <system_error>

#include "tacse3/fileio/file_io.hpp"
#include "tacse3/hal/camera/clock.hpp"
#include "tacse3/hal/camera/sim_camera.hpp"
#include "tacse3/sim/arm_log.hpp"
#include "tacse3/sim/plan.hpp"
#include "tacse3/sim/simulator.hpp"

namespace tacse3::hal {

namespace {

// A plan file is a few lines; this bounds what is read.
constexpr std::size_t kMaxPlanBytes = 1 << 20;
// The robot logs from this long before the motion starts until this long after the pads open.
constexpr std::int64_t kLogBeforeNs = 1'000'000'000;
constexpr std::int64_t kLogAfterNs = 200'000'000;

std::int64_t realtime_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// CLOCK_REALTIME - CLOCK_MONOTONIC, from the reading taken between the closest two monotonic ones.
std::int64_t realtime_minus_monotonic() noexcept {
  std::int64_t best_gap = INT64_MAX, offset = 0;
  for (int i = 0; i < 5; ++i) {
    const std::int64_t a = monotonic_ns();
    const std::int64_t r = realtime_ns();
    const std::int64_t b = monotonic_ns();
    if (b - a < best_gap) {
      best_gap = b - a;
      offset = r - (a + (b - a) / 2);
    }
  }
  return offset;
}

sim::RigidPose to_rigid(const sim::Pose& mm) {
  return {mm.q, mm.p * 1e-3};
}

}  // namespace

bool SimRig::load_plan(const sim::SimConfig& base, std::string* error) {
  const std::string& file = config_.scene.plan;
  std::string text;
  const fileio::ReadResult rr = fileio::read_regular_file(file, kMaxPlanBytes, &text);
  if (!rr.ok()) {
    *error = "[sim] plan " + file + ": " +
             (rr.error == fileio::ReadError::kNotFound ? std::string("no such file")
              : rr.error == fileio::ReadError::kNotRegular
                  ? std::string("is ") + rr.kind + ", not a file"
              : rr.error == fileio::ReadError::kTooLarge
                  ? "larger than " + fileio::size_text(kMaxPlanBytes) + ": not a plan"
                  : "cannot be read" + fileio::os_error(rr.os_errno)) +
             "; write it with tacse3-calibrate --plan --format csv";
    return false;
  }
  std::vector<sim::PlanMotion> plan;
  std::string e;
  if (!sim::parse_plan(text, "[sim] plan " + file, &plan, &e)) {
    *error = e;
    return false;
  }
  // Every motion on the same gel, object and camera (the same seed): one sensor, many grasps.
  for (const sim::PlanMotion& m : plan) {
    sim::SimConfig c = base;
    c.scenario = sim::plan_scenario(m, base.scenario);
    std::unique_ptr<sim::Simulator> s = sim::Simulator::create(c, &e);
    if (!s) {
      *error =
          "[sim] plan " + file + ": motion " + std::to_string(plan_sims_.size() + 1) + ": " + e;
      plan_sims_.clear();
      return false;
    }
    plan_sims_.push_back(std::move(s));
  }
  plan_file_ = file;
  // A start and a stop per motion, after the first rest.
  segment_capacity_ = 2 * plan_sims_.size() + 1;
  segments_ = std::make_unique<Segment[]>(segment_capacity_);
  segments_[0] = Segment{-1, 0, 0};
  segment_count_.store(1, std::memory_order_release);
  for (auto& r : rendered_) r.store(-1, std::memory_order_relaxed);
  const std::array<double, 7>& g = config_.tcp_to_grasp;
  sim::RigidPose tcp_g;
  tcp_g.p = Eigen::Vector3d(g[0], g[1], g[2]);
  tcp_g.q = Eigen::Quaterniond(g[3], g[4], g[5], g[6]).normalized();
  arm_ = std::make_unique<sim::ArmLog>(config_.scene.seed, tcp_g);
  return true;
}

std::size_t SimRig::segment_at(std::int64_t k) const noexcept {
  std::size_t j = segment_count_.load(std::memory_order_acquire);
  while (j > 1 && segments_[j - 1].start_grid > k) --j;
  return j - 1;
}

sim::Pose SimRig::motion_truth(int motion, std::int64_t start_grid,
                               std::int64_t t_sim) const noexcept {
  const std::int64_t t = t_sim - grid_time_ns(start_grid);
  if (motion < 0 || t < 0) return {};
  return plan_sims_[static_cast<std::size_t>(motion)]->truth(t);
}

void SimRig::restart_pad(sim::Sensor s) noexcept {
  sim_->reset(s);
  play_[static_cast<std::size_t>(s)] = PadPlay{};
}

sim::SimStatus SimRig::render(sim::Sensor s, std::int64_t k, std::span<std::uint8_t> out,
                              int channels) noexcept {
  if (!has_plan()) return sim_->render(s, grid_time_ns(k), out, channels);
  const auto i = static_cast<std::size_t>(s);
  rendered_[i].store(k, std::memory_order_release);
  const std::size_t j = segment_at(k);
  const Segment seg = segments_[j];
  sim::Simulator& sm = *plan_sims_[static_cast<std::size_t>(seg.scene)];
  std::int64_t t = grid_time_ns(k) - grid_time_ns(seg.start_grid);
  if (seg.motion < 0) {
    // At rest: the scene's approach (pads open) over and over, so the camera noise goes on.
    const auto open_ns = static_cast<std::int64_t>(sm.scenario().spec().approach_s * 1e9);
    t = open_ns > 0 ? t % open_ns : 0;
  }
  PadPlay& p = play_[i];
  if (p.segment != j || t < p.t_ns) sm.reset(s);  // a fresh grasp, or the rest starting over
  p.segment = j;
  p.t_ns = t;
  return sm.render(s, t, out, channels);
}

// The first grid frame neither pad has rendered: after anything either pad has rendered and, in
// real time, two periods from now (a pad renders at most one frame ahead of its time).
bool SimRig::append_segment(int motion) {
  const std::size_t n = segment_count_.load(std::memory_order_relaxed);
  if (n >= segment_capacity_) return false;
  std::int64_t k = segments_[n - 1].start_grid + 1;
  if (const std::int64_t t0 = t0_ns(); t0 != 0 && config_.scene.realtime) {
    const double now_k = std::ceil(static_cast<double>(monotonic_ns() - t0) * config_.fps * 1e-9);
    k = std::max(k, static_cast<std::int64_t>(now_k) + 2);
  }
  for (const auto& r : rendered_) k = std::max(k, r.load(std::memory_order_acquire) + 1);
  // At rest the pads are open where the next motion grasps (a translation starts off centre).
  const int scene =
      motion >= 0 ? motion : static_cast<int>(std::min(next_motion_, plan_sims_.size() - 1));
  segments_[n] = Segment{motion, scene, k};
  segment_count_.store(n + 1, std::memory_order_release);
  return true;
}

std::string SimRig::next_motion_problem() const {
  if (!has_plan()) return "the sim rig has no [sim] plan";
  if (next_motion_ < plan_sims_.size()) return {};
  return "every motion of the sim plan " + plan_file_ + " was recorded (" +
         std::to_string(plan_sims_.size()) + "); restart tacse3d to play it again";
}

void SimRig::start_motion(const std::filesystem::path& dir) {
  if (!next_motion_problem().empty()) return;
  if (!append_segment(static_cast<int>(next_motion_))) return;
  ++next_motion_;
  motion_dir_ = dir;
}

std::string SimRig::stop_motion() {
  const std::size_t n = segment_count_.load(std::memory_order_relaxed);
  const Segment motion = segments_[n - 1];
  if (!has_plan() || motion.motion < 0) return "no motion is playing";
  if (!append_segment(-1)) return "the sim plan's rest could not start";
  const Segment rest = segments_[n];
  const std::int64_t t0 = t0_ns();
  const std::int64_t start_ns = t0 + grid_time_ns(motion.start_grid);
  const std::int64_t end_ns = t0 + grid_time_ns(rest.start_grid);
  // The held pose until the end of the log: the robot logs a moment after the pads open.
  auto truth = [&](std::int64_t board_ns) {
    return to_rigid(motion_truth(motion.motion, motion.start_grid, board_ns - t0));
  };
  const std::string log =
      arm_->gripper_log(truth, start_ns - kLogBeforeNs, end_ns + kLogAfterNs,
                        realtime_minus_monotonic(), sim::ArmLogFormat::kQuaternionNs);
  std::string sim_truth = "t_ns,qw,qx,qy,qz,px,py,pz\n";
  char buf[256];
  for (std::int64_t k = std::max<std::int64_t>(0, motion.start_grid - config_.fps);
       k < rest.start_grid; ++k) {
    const std::int64_t t = t0 + grid_time_ns(k);
    const sim::RigidPose m = truth(t);
    std::snprintf(buf, sizeof buf, "%lld,%.12f,%.12f,%.12f,%.12f,%.12f,%.12f,%.12f\n",
                  static_cast<long long>(t), m.q.w(), m.q.x(), m.q.y(), m.q.z(), m.p.x(), m.p.y(),
                  m.p.z());
    sim_truth += buf;
  }
  const std::filesystem::path robot = motion_dir_ / "robot";
  std::error_code ec;
  std::filesystem::create_directory(robot, ec);
  if (ec) return robot.string() + ": cannot be created (" + ec.message() + ")";
  std::string e;
  if (!fileio::write_file_atomically(robot / "gripper.csv", log, &e) ||
      !fileio::write_file_atomically(robot / "sim-truth.csv", sim_truth, &e)) {
    return e;
  }
  return {};
}

}  // namespace tacse3::hal
