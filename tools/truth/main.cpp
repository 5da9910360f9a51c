// SPDX-License-Identifier: Apache-2.0
// tacse3-truth: truth.csv for a recording from robot pose logs (docs/truth.md).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "tacse3/config/board_file.hpp"
#include "tacse3/config/calibration_file.hpp"
#include "tacse3/fileio/file_io.hpp"
#include "tacse3/tools/cli.hpp"
#include "tacse3/tools/progress.hpp"
#include "tacse3/tools/replay.hpp"
#include "tacse3/tools/source.hpp"
#include "tacse3/tools/truth/clock_sync.hpp"
#include "tacse3/tools/truth/truth.hpp"

namespace {

namespace fs = std::filesystem;
namespace tt = tacse3::tools;
namespace tr = tacse3::tools::truth;

int fail(const std::string& msg) {
  std::fprintf(stderr, "tacse3-truth: error: %s\n", msg.c_str());
  return 1;
}

int usage(const std::string& msg) {
  std::fprintf(stderr, "tacse3-truth: %s\nRun with --help for more information.\n", msg.c_str());
  return 2;
}

// The relative orientation object-in-gripper at the gripper log's times inside the object log:
// what --clock-offset auto correlates when both move.
tr::PoseLog relative_log(const tr::PoseLog& gripper, const tr::PoseLog& object) {
  tr::PoseLog rel;
  rel.name = gripper.name + " and " + object.name;
  for (std::size_t i = 0; i < gripper.size(); ++i) {
    const std::int64_t t = gripper.t_ns[i];
    if (!object.covers(t, t)) continue;
    rel.t_ns.push_back(t);
    rel.pose.push_back(tr::inverse(gripper.pose[i]) * object.at(t));
  }
  return rel;
}

// The pipeline's angular speed per frame interval: |omega| of each frame's fused twist before
// the moving average (which would delay it by half its length), from the velocity proxy, which
// measures the motion between consecutive frames. Default calibration: only the shape is used.
std::string pipeline_speed(tt::RecordingSource& source, bool progress, std::vector<double>* speed) {
  tt::ProgressBar bar("tacse3-truth: replay",
                      static_cast<std::int64_t>(source.info().frame_count()), progress);
  tt::ReplaySinks sinks;
  sinks.progress = &bar;
  speed->clear();
  sinks.on_frame = [speed](std::size_t, const tt::FrameResult&, const tt::Replayer& engine) {
    speed->push_back(engine.result().fused.xi.head<3>().norm());
  };
  tt::ReplayOptions options;
  options.mode = tt::ProxyMode::kAuto;
  const tt::ReplayRun run = tt::run_replay(source, options, sinks);
  bar.finish();
  return run.error;
}

struct Options {
  std::string rec_dir, gripper_log, object_log, tcp_to_grasp, gripper_pose, clock_offset;
  std::string can_log, out, board;
  bool force = false, quiet = false;
};

// The clock offset by the method the options name; *how says which and how well it fits.
std::string sync_clock(const Options& o, tt::RecordingSource& source, const tr::PoseLog& log,
                       std::int64_t* offset_ns, std::string* how) {
  const std::vector<std::int64_t>& t = source.info().t_ns;
  char buf[512];
  if (!o.can_log.empty()) {
    tr::CanSync s;
    if (std::string e = tr::read_can_sync(o.can_log, t.front(), t.back(), &s); !e.empty()) return e;
    *offset_ns = s.offset_ns;
    std::snprintf(buf, sizeof(buf),
                  "from the CAN log %s: %zu cycles, arrival - SampleTime spread %.3f ms (robust "
                  "sigma), latency %.3f ms subtracted (%s)",
                  o.can_log.c_str(), s.cycles, s.spread_s * 1e3, s.latency_s * 1e3,
                  s.latency_reports > 0 ? "median LatencyP50 of the StatusTiming frames"
                                        : "none reported: assumed 0");
    *how = buf;
    return {};
  }
  if (o.clock_offset == "auto") {
    std::vector<double> speed;
    if (std::string e = pipeline_speed(source, !o.quiet && tt::stderr_is_tty(), &speed);
        !e.empty()) {
      return e;
    }
    tr::AutoSync a;
    if (std::string e = tr::sync_by_correlation(t, speed, log, &a); !e.empty()) return e;
    *offset_ns = a.offset_ns;
    std::snprintf(buf, sizeof(buf),
                  "auto: angular-speed correlation %.3f (next best peak %.3f at %.6f s), motion "
                  "%.0f times the speed noise",
                  a.correlation, a.runner_up, static_cast<double>(a.runner_up_ns) * 1e-9,
                  a.motion_snr);
    *how = buf;
    return {};
  }
  *offset_ns = std::llround(std::stod(o.clock_offset) * 1e9);
  *how = "given (--clock-offset)";
  return {};
}

// The option combinations and values CLI11 cannot check; "" or the usage error. Fills the rig's
// fixed poses.
std::string usage_problem(const Options& o, tr::Rig* rig) {
  if (o.gripper_log.empty() && o.object_log.empty()) {
    return "give --gripper-log FILE (the gripper moves) or --object-log FILE (the object moves), "
           "or both";
  }
  if (!o.can_log.empty() && !o.clock_offset.empty()) {
    return "--can-log and --clock-offset both set the clock offset; give one";
  }
  if (o.can_log.empty() && o.clock_offset.empty()) {
    return "no clock sync: give --clock-offset SECONDS (0 when the robot log has the recording's "
           "clock), --clock-offset auto, or --can-log FILE";
  }
  if (o.clock_offset != "auto" && !o.clock_offset.empty()) {
    std::size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(o.clock_offset, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != o.clock_offset.size() || !std::isfinite(v) || std::abs(v) > 9e9) {
      return "--clock-offset: expected seconds or auto, got \"" + o.clock_offset + "\"";
    }
  }
  if (!o.tcp_to_grasp.empty()) {
    if (std::string e = tr::parse_pose_text(o.tcp_to_grasp, &rig->tcp_to_grasp); !e.empty()) {
      return "--tcp-to-grasp: " + e;
    }
  }

  if (!o.gripper_pose.empty()) {
    if (!o.gripper_log.empty()) {
      return "--gripper-pose is the pose of a still gripper: give it or --gripper-log, not both";
    }
    if (std::string e = tr::parse_pose_text(o.gripper_pose, &rig->fixed_tcp); !e.empty()) {
      return "--gripper-pose: " + e;
    }
  }
  return {};
}

void print_summary(const fs::path& out, const std::vector<tacse3::recording::TruthSample>& rows,
                   std::int64_t offset_ns, const std::string& how) {
  double max_deg = 0.0, max_mm = 0.0;
  for (const auto& r : rows) {
    const double angle = tr::rotation_angle(Eigen::Quaterniond(r.qw, r.qx, r.qy, r.qz));
    max_deg = std::max(max_deg, angle * 180.0 / std::numbers::pi);
    max_mm = std::max(max_mm, Eigen::Vector3d(r.px, r.py, r.pz).norm() * 1e3);
  }
  std::printf("tacse3-truth: clock offset %.6f s, %s\n", static_cast<double>(offset_ns) * 1e-9,
              how.c_str());
  std::printf(
      "tacse3-truth: wrote %s: %zu rows, object rotation up to %.2f deg, translation up "
      "to %.2f mm\n",
      out.c_str(), rows.size(), max_deg, max_mm);
}

// The TCP-to-grasp pose from the board file's [rig] tcp_to_grasp when the command line gives none;
// *source says which was used. "" or the error naming the file and key.
std::string board_tcp_to_grasp(const Options& o, tr::Rig* rig, std::string* source) {
  if (!o.tcp_to_grasp.empty()) {
    *source = "--tcp-to-grasp";
    return {};
  }
  *source = "identity (no --tcp-to-grasp, no --board)";
  if (o.board.empty()) return {};
  namespace cfg = tacse3::config;
  std::string err;
  const fs::path file =
      cfg::resolve_board(o.board, cfg::executable_dir(), TACSE3_SOURCE_BOARDS_DIR, &err);
  if (file.empty()) return "--board: " + err;
  cfg::BoardConfig board;
  if (!cfg::load_board(file, &board, &err)) return err;
  if (!board.rig.has_tcp_to_grasp) {
    return file.string() +
           ": no key \"rig.tcp_to_grasp\"; add [rig] tcp_to_grasp = [x, y, z, "
           "qw, qx, qy, qz] or give --tcp-to-grasp";
  }
  const auto& v = board.rig.tcp_to_grasp;
  rig->tcp_to_grasp.p = Eigen::Vector3d(v[0], v[1], v[2]);
  rig->tcp_to_grasp.q = Eigen::Quaterniond(v[3], v[4], v[5], v[6]);
  *source = file.string() + " [rig] tcp_to_grasp";
  return {};
}

int execute(const Options& o) {
  tr::Rig rig;
  if (std::string e = usage_problem(o, &rig); !e.empty()) return usage(e);
  std::string tcp_source;
  if (std::string e = board_tcp_to_grasp(o, &rig, &tcp_source); !e.empty()) return fail(e);
  const fs::path out = o.out.empty() ? fs::path(o.rec_dir) / "truth.csv" : fs::path(o.out);
  std::string err;
  if (fs::exists(fs::symlink_status(out)) && !o.force) {
    return fail(out.string() + ": exists; give --force to replace it");
  }
  if (!tacse3::fileio::check_output_file(out, &err)) return fail(err);

  auto source = tt::RecordingSource::open(o.rec_dir, &err);
  if (!source) return fail(err);
  tr::PoseLog gripper, object;
  if (!o.gripper_log.empty()) {
    if (err = tr::read_pose_log(o.gripper_log, &gripper); !err.empty()) return fail(err);
    rig.gripper = &gripper;
  }
  if (!o.object_log.empty()) {
    if (err = tr::read_pose_log(o.object_log, &object); !err.empty()) return fail(err);
    rig.object = &object;
  }
  const tr::PoseLog sync_log = rig.gripper != nullptr && rig.object != nullptr
                                   ? relative_log(gripper, object)
                                   : (rig.gripper != nullptr ? gripper : object);
  std::int64_t offset_ns = 0;
  std::string how;
  if (err = sync_clock(o, *source, sync_log, &offset_ns, &how); !err.empty()) return fail(err);
  std::vector<tacse3::recording::TruthSample> rows;
  if (err = tr::make_truth(rig, source->info().t_ns, offset_ns, &rows); !err.empty()) {
    return fail(err);
  }
  if (!tacse3::fileio::write_file_atomically(out, tr::truth_csv(rows), &err)) return fail(err);
  if (!o.quiet) {
    std::printf("tacse3-truth: TCP to grasp from %s\n", tcp_source.c_str());
    print_summary(out, rows, offset_ns, how);
  }
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{
      "Writes truth.csv for a tacse3 recording from robot pose logs: the object's pose in the "
      "grasp frame G relative to the first frame (docs/truth.md)."};
  Options o;
  const CLI::Validator path = tt::non_empty_path();
  app.add_option("--recording", o.rec_dir, "recording directory (docs/recording-format.md)")
      ->required()
      ->check(path);
  app.add_option("--gripper-log", o.gripper_log,
                 "CSV: the robot TCP's pose in a fixed world frame over time (object fixed)")
      ->check(path);
  app.add_option("--object-log", o.object_log,
                 "CSV: the object's pose in the world over time (gripper fixed)")
      ->check(path);
  app.add_option("--tcp-to-grasp", o.tcp_to_grasp,
                 "\"x y z qw qx qy qz\": the grasp frame G in the TCP frame (default: --board's "
                 "[rig] tcp_to_grasp, else identity)");
  app.add_option("--board", o.board,
                 "board NAME|PATH whose [rig] tcp_to_grasp gives the pose when --tcp-to-grasp "
                 "is not given")
      ->check(path);
  app.add_option("--gripper-pose", o.gripper_pose,
                 "\"x y z qw qx qy qz\": the fixed TCP pose in the world when there is no "
                 "--gripper-log (default identity)");
  app.add_option("--clock-offset", o.clock_offset,
                 "SECONDS (robot-log time = recording time + SECONDS) or auto (cross-correlate "
                 "the angular speeds)");
  app.add_option("--can-log", o.can_log,
                 "candump -L log taken on the robot's clock during the recording: clock sync")
      ->check(path);
  app.add_option("--out", o.out, "output file (default REC_DIR/truth.csv)")->check(path);
  app.add_flag("--force", o.force, "replace an existing output file");
  app.add_flag("-q,--quiet", o.quiet, "no progress bar and no summary");
  if (const int rc = tt::parse_command_line(app, argc, argv); rc >= 0) return rc;
  return execute(o);
}

}  // namespace

int main(int argc, char** argv) {
  return tt::finish_stdout("tacse3-truth", run(argc, argv));
}
