// SPDX-License-Identifier: Apache-2.0
// tacse3-replay: run the firmware's fixed-point pipeline over a recording (docs/replay.md).
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>

#include "replay_view.hpp"
#include "tacse3/config/calibration_file.hpp"
#include "tacse3/config/listen_address.hpp"
#include "tacse3/fileio/file_io.hpp"
#include "tacse3/tools/can_log.hpp"
#include "tacse3/tools/cli.hpp"
#include "tacse3/tools/field_dump.hpp"
#include "tacse3/tools/plot_layout.hpp"
#include "tacse3/tools/progress.hpp"
#include "tacse3/tools/replay.hpp"
#include "tacse3/tools/replay_plot.hpp"
#include "tacse3/tools/source.hpp"
#if TACSE3_HAVE_PLOT
#include "tacse3/tools/plot_render.hpp"
#endif

namespace {

namespace tt = tacse3::tools;

int fail(const std::string& msg) {
  std::fprintf(stderr, "tacse3-replay: error: %s\n", msg.c_str());
  return 1;
}

std::string axis_text(const Eigen::Vector3d& v) {
  const double n = v.norm();
  if (n < 1e-9) return "";
  char buf[96];
  std::snprintf(buf, sizeof(buf), " about (%.2f, %.2f, %.2f)", v.x() / n, v.y() / n, v.z() / n);
  return buf;
}

// Where the calibration came from, for the warning and the summary.
std::string calibration_text(const std::string& file, bool is_default, bool fitted) {
  if (file.empty()) return "built-in defaults";
  std::string t = file;
  if (is_default) t += " (the simulator's, the default for a simulator recording)";
  if (!fitted) t += " (sets no sensor keys)";
  return t;
}

// The per-frame tracking error, which a controller reading every cycle lives by.
void print_tracking(std::FILE* report, const tt::TrackingError& t) {
  if (!t.valid) {
    std::fprintf(report, "  tracking: no frame after the truth's motion starts\n");
    return;
  }
  std::fprintf(report,
               "  tracking (%zu frames from the motion's start): rotation RMS %.2f deg, max %.2f "
               "deg (truth lag %.0f ms); translation RMS %.2f mm, max %.2f mm (lag %.0f ms)\n",
               t.frames, t.rotation_rms_deg, t.rotation_max_deg, t.rotation_lag_s * 1e3,
               t.translation_rms_mm, t.translation_max_mm, t.translation_lag_s * 1e3);
}

// "--plot MSG" (built up in place: GCC 12 -O3 warns -Wrestrict on "literal" + std::string).
std::string plot_error(const std::string& msg) {
  std::string s = "--plot ";
  s += msg;
  return s;
}

// --plot FILE: refused before the replay runs when it cannot be written (no cairo, no such
// folder, a directory or device); written atomically after it, so a failure leaves no part.
std::string plot_check(const std::string& file) {
#if TACSE3_HAVE_PLOT
  std::string err;
  if (!tacse3::fileio::check_output_file(file, &err)) return plot_error(err);
  return "";
#else
  return plot_error(file +
                    ": this tacse3-replay was built without plotting (a host build with "
                    "libcairo2-dev draws it; docs/replay.md)");
#endif
}

// The figure's title: recording, method and mode, calibration file (or UNCALIBRATED).
std::string plot_title(const std::string& rec_dir, const tt::ReplayOptions& opt,
                       const std::string& mode, const std::string& cal_file) {
  namespace fs = std::filesystem;
  fs::path rec = fs::path(rec_dir).lexically_normal();
  if (rec.filename().empty()) rec = rec.parent_path();
  std::string t = rec.filename().string();
  t += ": method ";
  t += tt::method_name(opt.method);
  t += ", mode ";
  t += mode;
  t += ", ";
  t += opt.calibration.fitted ? fs::path(cal_file).filename().string() : "UNCALIBRATED";
  return t;
}

std::string write_plot(const std::string& file, const tt::SourceInfo& info,
                       const std::vector<tt::FrameResult>& frames, const tt::RunSummary& sum,
                       std::string title) {
  tt::plot::PlotData d = tt::plot::replay_plot_data(info, frames, sum.tracking);
  d.title = std::move(title);
#if TACSE3_HAVE_PLOT
  std::string bytes, err;
  const bool drawn = tt::plot::render(d, *tt::plot::format_from_path(file), &bytes, &err);
  tt::plot::release_static_data();
  if (!drawn) return plot_error(file + ": " + err);
  if (!tacse3::fileio::write_file_atomically(file, bytes, &err)) return plot_error(err);
  return "";
#else
  return plot_check(file);
#endif
}

// An output file that run() created is removed unless the run completed: a recording that fails
// half way (a corrupt PNG, a full disk) leaves no partial CSV behind.
struct RemoveUnlessKept {
  explicit RemoveUnlessKept(std::string p) : path(std::move(p)) {}
  ~RemoveUnlessKept() {
    if (!keep && !path.empty()) std::remove(path.c_str());
  }
  RemoveUnlessKept(const RemoveUnlessKept&) = delete;
  RemoveUnlessKept& operator=(const RemoveUnlessKept&) = delete;
  std::string path;
  bool keep = false;
};

int run(int argc, char** argv) {
  CLI::App app{
      "Replays a tacse3 recording through the firmware's fixed-point pipeline (dsp::DualPipeline) "
      "and writes the estimated twist and pose per frame (docs/replay.md)."};
  std::string rec_dir, cal_file, out_file, method = "joint", mode = "auto", sensors = "both";
  std::string dump_dir, can_log, slip_log, plot_file;
  bool quiet = false;
  const CLI::Validator path = tt::non_empty_path();
  app.add_option("REC_DIR", rec_dir, "recording directory (docs/recording-format.md)")
      ->required()
      ->check(path);
  app.add_option("--calibration", cal_file,
                 "calibration file (docs/calibration.md); default: the simulator's "
                 "sim-calibration.toml for a simulator recording, else the built-in defaults "
                 "(reported as UNCALIBRATED)")
      ->check(path);
  app.add_option("--out", out_file, "output CSV, one row per frame ('-' = standard output)")
      ->required()
      ->check(path);
  app.add_option("--method", method, "dual-sensor fusion: joint (default) or paper")
      ->check(CLI::IsMember({"paper", "joint"}));
  app.add_option("--mode", mode, "velocity proxy: auto (default), velocity or displacement")
      ->check(CLI::IsMember({"auto", "velocity", "displacement"}));
  app.add_option("--sensors", sensors, "sensors to use: both (default), left or right")
      ->check(CLI::IsMember({"both", "left", "right"}));
  app.add_option("--dump-fields", dump_dir, "write per-frame fields as .npy files into DIR")
      ->check(path);
  app.add_option("--can-log", can_log, "write the firmware's CAN frames as a candump -L log")
      ->check(path);
  app.add_option("--slip-log", slip_log,
                 "write the stick/slip detector's per-frame decision and features as CSV")
      ->check(path);
  app.add_option("--plot", plot_file,
                 "write a figure of the estimate against the truth and the tracking error over "
                 "time; the extension picks SVG or PNG")
      ->check(path)
      ->check(CLI::Validator(
          [](std::string& f) {
            std::string e;
            if (!tt::plot::format_from_path(f)) {
              e = f;
              e += ": the name must end in .svg or .png (the extension picks the format)";
            }
            return e;
          },
          "FILE.svg|FILE.png"));
  app.add_flag("-q,--quiet", quiet, "no progress bar and no summary");
  std::string view;
  tacse3::config::ListenAddress view_at;
  app.add_option("--view", view,
                 "then serve the recording's web view on [ADDR:]PORT until Ctrl-C (docs/viewer.md)")
      ->check(CLI::Validator(
          [&view_at](std::string& text) {
            std::string e;
            return tacse3::config::parse_listen_address(text, &view_at, &e) ? std::string() : e;
          },
          "[ADDR:]PORT"));
  if (const int rc = tt::parse_command_line(app, argc, argv); rc >= 0) return rc;

  tt::ReplayOptions opt;
  (void)tt::parse_method(method, &opt.method);
  (void)tt::parse_mode(mode, &opt.mode);
  (void)tt::parse_sensors(sensors, &opt.sensors);
  std::string err;
  if (!plot_file.empty()) {
    if (err = plot_check(plot_file); !err.empty()) return fail(err);
  }
  auto source = tt::RecordingSource::open(rec_dir, &err);
  if (!source) return fail(err);
  const tt::SourceInfo& info = source->info();

  const bool cal_default = cal_file.empty() && tt::is_simulator_recording(info);
  if (cal_default) {
    cal_file = tacse3::config::find_sim_calibration(tacse3::config::executable_dir(),
                                                    TACSE3_SOURCE_SIM_CALIBRATION)
                   .string();
  }
  if (!cal_file.empty()) {
    if (auto s = tacse3::config::load_calibration(cal_file, &opt.calibration); !s) {
      return fail(s.message());
    }
  }
  const std::string cal_text = calibration_text(cal_file, cal_default, opt.calibration.fitted);
  if (!opt.calibration.fitted) {
    std::fprintf(stderr,
                 "tacse3-replay: UNCALIBRATED: calibration %s; the estimates are not to scale. "
                 "Give --calibration FILE from tacse3-calibrate (docs/calibration.md)\n",
                 cal_text.c_str());
  }

  tt::EngineSetup setup;
  if (err = tt::make_setup(info, opt, &setup); !err.empty()) return fail(err);

  const bool to_stdout = out_file == "-";
  std::FILE* csv = to_stdout ? stdout : std::fopen(out_file.c_str(), "w");
  if (csv == nullptr) return fail(out_file + ": cannot open for writing");
  RemoveUnlessKept csv_guard(to_stdout ? "" : out_file);
  std::FILE* report = to_stdout ? stderr : stdout;

  tt::FieldDumper dumper;
  tt::CanLogger can;
  tt::ReplaySinks sinks;
  sinks.csv = csv;
  if (!dump_dir.empty()) {
    if (err = dumper.open(dump_dir, static_cast<std::int64_t>(info.frame_count()), setup.use,
                          info.pixel_pitch_mm);
        !err.empty()) {
      return fail(err);
    }
    sinks.dump = &dumper;
  }
  if (!can_log.empty()) {
    if (err = can.open(can_log, opt.method, opt.mode); !err.empty()) return fail(err);
    sinks.can = &can;
  }
  std::FILE* slip = nullptr;
  RemoveUnlessKept slip_guard("");
  if (!slip_log.empty()) {
    slip = std::fopen(slip_log.c_str(), "w");
    if (slip == nullptr) return fail(slip_log + ": cannot open for writing");
    slip_guard.path = slip_log;
    std::fprintf(slip,
                 "t_ns,sensor,contact,slipping,onset,stick_confirmed,relax_rate_per_s,shift_m,"
                 "rate_m_s,load_drop_per_s,releasing,anchor_set,velocity_anchored,points,"
                 "velocity_points,anchor_overlap_points\n");
    sinks.on_frame = [slip](std::size_t, const tt::FrameResult& r, const tt::Replayer& engine) {
      const auto& res = engine.result();
      for (int k = 0; k < 2; ++k) {
        const auto& sr = res.sensors[static_cast<std::size_t>(k)];
        if (!res.present[static_cast<std::size_t>(k)]) continue;
        const auto& m = sr.motion;
        std::fprintf(slip, "%lld,%s,%d,%d,%d,%d,%.6g,%.6g,%.6g,%.6g,%d,%d,%d,%d,%d,%d\n",
                     static_cast<long long>(r.t_ns), k == 0 ? "left" : "right", m.contact ? 1 : 0,
                     sr.slipping ? 1 : 0, m.slip_onset ? 1 : 0, m.stick_confirmed ? 1 : 0,
                     m.slip_relax_rate, m.shear_shift_m, m.shear_rate_m_s, m.load_drop_rate,
                     m.releasing ? 1 : 0, m.anchor_set ? 1 : 0, m.velocity_anchored ? 1 : 0,
                     m.points, m.velocity_points, m.anchor_overlap_points);
      }
    };
  }
  tt::ProgressBar bar("tacse3-replay", static_cast<std::int64_t>(info.frame_count()),
                      !quiet && tt::stderr_is_tty());
  sinks.progress = &bar;
  std::unique_ptr<tt::ReplayView> viewer;
  if (!view.empty()) {
    if (const char* why = tt::ReplayView::unavailable())
      return fail(std::string("--view: ").append(why));
    viewer = std::make_unique<tt::ReplayView>(info, opt.calibration.fitted);
    sinks.on_frame = [viewer = viewer.get(), log = sinks.on_frame](
                         std::size_t i, const tt::FrameResult& r, const tt::Replayer& engine) {
      if (log) log(i, r, engine);
      viewer->add(i, r, engine);
    };
  }
  // After the run and its summary: --view serves until Ctrl-C.
  const auto finish = [&] {
    if (!viewer) return 0;
    std::fflush(stdout);
    const std::string e = viewer->serve(view_at, cal_text);
    return e.empty() ? 0 : fail(std::string("--view ").append(view).append(": ").append(e));
  };

  const tt::ReplayRun run = tt::run_replay(*source, opt, sinks);
  bar.finish();
  if (!to_stdout && std::fclose(csv) != 0) return fail(out_file + ": write error");
  if (slip != nullptr && std::fclose(slip) != 0) return fail(slip_log + ": write error");
  if (!run.error.empty()) return fail(run.error);
  if (sinks.dump != nullptr) {
    if (err = dumper.close(); !err.empty()) return fail(err);
  }
  if (sinks.can != nullptr) {
    if (err = can.close(); !err.empty()) return fail(err);
  }
  const tt::RunSummary sum = tt::summarize(info, run.frames, opt.sensors);
  if (!plot_file.empty()) {
    if (err =
            write_plot(plot_file, info, run.frames, sum, plot_title(rec_dir, opt, mode, cal_file));
        !err.empty()) {
      return fail(err);
    }
  }
  csv_guard.keep = true;
  slip_guard.keep = true;
  if (quiet) return finish();

  const char* used =
      setup.use[0] && setup.use[1] ? "left+right" : (setup.use[0] ? "left" : "right");
  std::fprintf(report, "tacse3-replay: %s: %zu frames (%s), method %s, mode %s%s, calibration %s\n",
               rec_dir.c_str(), run.frames.size(), used, tt::method_name(opt.method), mode.c_str(),
               opt.mode == tt::ProxyMode::kAuto && !tt::pipeline_has_auto()
                   ? " (runs the velocity proxy: the pipeline has no auto switch yet)"
                   : "",
               (cal_text + (opt.calibration.fitted ? "" : ": UNCALIBRATED")).c_str());
  std::fprintf(report, "  estimate valid in %.0f%% of frames; wrote %s\n",
               100.0 * sum.valid_fraction, to_stdout ? "standard output" : out_file.c_str());
  if (sum.valid_fraction <= 0.0 && !run.frames.empty()) {
    // An all-invalid run is almost always a setup problem, not a still object: say what to check.
    const double tau = opt.calibration.sensor[0].contact_tau_on;
    std::fprintf(report,
                 "  warning: no frame gave a valid estimate, so no pad saw a contact it could "
                 "read. Check that the pads touch the object; that the calibration is this "
                 "sensor's (its contact_tau_on %.4g may be above this sensor's f^z: "
                 "docs/calibration.md); and that the object's face does not cover the pad's "
                 "whole view (docs/accuracy.md, \"Other known limits\")\n",
                 tau);
  }
  std::fprintf(report, "  confidence >= %.1f in %.0f%% of frames (median %.2f where valid)\n",
               tacse3::dsp::kConfidenceThreshold, 100.0 * sum.confident_fraction,
               sum.confidence_median);
  if (sum.has_truth) {
    const auto& e = sum.errors;
    std::fprintf(report,
                 "  rotation:    estimated %7.2f deg%s, truth %7.2f deg%s -> error %.2f deg\n",
                 e.estimated_rotation_deg, axis_text(e.final_rotation_vector_deg).c_str(),
                 e.true_rotation_deg, axis_text(e.true_rotation_vector_deg).c_str(),
                 e.final_rotation_error_deg);
    std::fprintf(report, "  translation: estimated %7.2f mm, truth %7.2f mm -> error %.2f mm\n",
                 e.estimated_translation_mm, e.true_translation_mm, e.final_translation_error_mm);
    print_tracking(report, sum.tracking);
    if (sum.truth_ends_early) {
      std::fprintf(report,
                   "  warning: %s/truth.csv ends at t = %.3f s, before the last frame (%.3f s): "
                   "the frames after it are compared with its last pose\n",
                   rec_dir.c_str(), static_cast<double>(sum.truth_end_ns) * 1e-9,
                   static_cast<double>(sum.last_frame_ns) * 1e-9);
    }
  }
  if (sum.has_slip_score) {
    const auto& s = sum.slip;
    std::fprintf(
        report,
        "  slip detector vs sim_labels.csv: %.1f%% of %lld in-contact sensor-frames "
        "(slip found %lld/%lld, stick found %lld/%lld)\n",
        100.0 * s.accuracy(), static_cast<long long>(s.scored()),
        static_cast<long long>(s.true_slip), static_cast<long long>(s.true_slip + s.false_stick),
        static_cast<long long>(s.true_stick), static_cast<long long>(s.true_stick + s.false_slip));
  } else if (!info.labels.empty()) {
    std::fprintf(report,
                 "  slip detector: not scored (the pipeline reports no per-frame stick/slip "
                 "decision yet)\n");
  }
  return finish();
}

}  // namespace

int main(int argc, char** argv) {
  // Every path out of run() goes through here: the CSV (--out -) or the summary is on stdout.
  return tt::finish_stdout("tacse3-replay", run(argc, argv));
}
