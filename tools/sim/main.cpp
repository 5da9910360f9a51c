// SPDX-License-Identifier: Apache-2.0
// tacse3-sim: render a simulated dual DM-Tac grasp-and-move recording with exact ground truth.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "options.hpp"
#include "tacse3/recording/recording.hpp"
#include "tacse3/sim/profile.hpp"
#include "tacse3/sim/simulator.hpp"
#include "tacse3/tools/cli.hpp"
#include "tacse3/tools/progress.hpp"
#include "tacse3/tools/sim_source.hpp"

namespace {

using tacse3::tools::Options;
using tacse3::tools::parse_options;
namespace rec = tacse3::recording;
namespace sim = tacse3::sim;

int fail(const std::string& msg) {
  std::fprintf(stderr, "tacse3-sim: error: %s\n", msg.c_str());
  return 1;
}

int usage_error(const std::string& msg) {
  std::fprintf(stderr, "tacse3-sim: error: %s\n", msg.c_str());
  return 2;
}

// --profile list: every profile's name and values (the random one's for this --seed).
int list_profiles(std::uint64_t seed) {
  for (const char* name :
       {"reference", "soft-thick", "stiff-thin", "coulomb-rim", "halfspace-mjpeg", "random"}) {
    sim::SensorProfile p;
    if (!sim::make_profile(name, seed, &p, nullptr)) return fail(std::string("no profile ") + name);
    std::printf("%s\n", name);
    for (const auto& [key, value] : sim::profile_values(p)) {
      std::printf("  %s = %s\n", key.c_str(), value.c_str());
    }
  }
  return 0;
}

// The profile's values for recording.json: numbers as numbers, model names as strings.
nlohmann::ordered_json profile_json(const sim::SensorProfile& p) {
  nlohmann::ordered_json values = nlohmann::ordered_json::object();
  for (const auto& [key, value] : sim::profile_values(p)) {
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (value == "true" || value == "false") {
      values[key] = value == "true";
    } else if (end && *end == '\0' && end != value.c_str()) {
      if (v == std::floor(v) && std::abs(v) < 1e15) {
        values[key] = static_cast<std::int64_t>(v);
      } else {
        values[key] = v;
      }
    } else {
      values[key] = value;
    }
  }
  return values;
}

std::string command_line(int argc, char** argv) {
  std::string s;
  for (int i = 0; i < argc; ++i) {
    if (i) s += ' ';
    s += argv[i];
  }
  return s;
}

int run(int argc, char** argv) {
  Options o;
  if (const int rc = parse_options(argc, argv, &o); rc >= 0) return rc;
  if (o.profile == "list") return list_profiles(o.seed);

  sim::SimConfig cfg;
  cfg.seed = o.seed;
  cfg.scenario.object.seed = o.seed;
  if (!sim::object_preset(o.object, &cfg.scenario.object)) {
    return fail("unknown --object \"" + o.object + "\" (one of: " + sim::object_preset_names() +
                ")");
  }
  if (!sim::parse_axis(o.motion, &cfg.scenario.axis)) {
    return fail("unknown --motion \"" + o.motion + "\" (rx, ry, rz, tx or ty)");
  }
  if (!sim::parse_regime(o.regime, &cfg.scenario.regime)) {
    return fail("unknown --regime \"" + o.regime + "\" (stick, slide or auto)");
  }
  const bool rotation = sim::is_rotation(cfg.scenario.axis);
  cfg.scenario.magnitude = std::isnan(o.magnitude) ? (rotation ? 30.0 : 10.0) : o.magnitude;
  // The profile first (it sets the motion duration from the magnitude), then the options the
  // user gave explicitly.
  sim::SensorProfile profile;
  std::string profile_error;
  if (!sim::make_profile(o.profile, o.seed, &profile, &profile_error)) {
    return usage_error("--profile: " + profile_error);
  }
  if (std::string e = sim::validate(profile); !e.empty()) {
    return fail("--profile " + o.profile + ": " + e);
  }
  if (o.out.empty()) return usage_error("--out is required");
  sim::apply_profile(profile, &cfg);
  cfg.scenario.approach_s = o.approach_s;
  cfg.scenario.grasp_s = o.grasp_s;
  cfg.scenario.settle_s = o.settle_s;
  if (o.motion_s > 0.0) cfg.scenario.motion_s = o.motion_s;
  cfg.scenario.hold_s = o.hold_s;
  cfg.scenario.release_s = o.release_s;
  cfg.scenario.fps = o.fps;
  if (!std::isnan(o.indentation)) cfg.scenario.indentation_mm = o.indentation;
  if (!std::isnan(o.radius)) cfg.scenario.object.size_mm = o.radius;
  if (!std::isnan(o.friction)) cfg.scenario.object.friction = o.friction;
  if (o.offset.size() == 2) cfg.scenario.object.offset_mm = {o.offset[0], o.offset[1]};
  if (!std::isnan(o.pitch)) cfg.rig.pixel_pitch_mm = o.pitch;
  if (!std::isnan(o.noise)) cfg.camera.noise = o.noise;
  if (!std::isnan(o.flicker)) cfg.camera.flicker = o.flicker;
  std::vector<sim::Sensor> sensors;
  if (o.sensors == "both") {
    sensors = {sim::Sensor::kLeft, sim::Sensor::kRight};
  } else if (o.sensors == "left") {
    sensors = {sim::Sensor::kLeft};
  } else if (o.sensors == "right") {
    sensors = {sim::Sensor::kRight};
  } else {
    return fail("unknown --sensors \"" + o.sensors + "\" (both, left or right)");
  }
  cfg.sensors = {false, false};
  for (auto s : sensors) cfg.sensors[static_cast<std::size_t>(s)] = true;
  int channels = 3;
  if (o.colour == "grey" || o.colour == "gray") {
    channels = 1;
  } else if (o.colour != "rgb") {
    return fail("unknown --colour \"" + o.colour + "\" (rgb or grey)");
  }
  if (o.jobs < 1) return fail("--jobs must be at least 1");

  std::string error;
  if (!std::isnan(o.separation) && !sim::fit_object_to_separation(&cfg, o.separation, &error)) {
    return fail(error);
  }
  auto simulator = sim::Simulator::create(cfg, &error);
  if (!simulator) return fail(error);
  const sim::Scenario& scn = simulator->scenario();
  const int frames = scn.frame_count();

  rec::RecordingInfo info;
  info.width = cfg.rig.width;
  info.height = cfg.rig.height;
  info.fps = cfg.scenario.fps;
  info.sensors.clear();
  for (auto s : sensors) info.sensors.push_back(static_cast<rec::SensorId>(s));
  info.rig.pixel_pitch_mm = cfg.rig.pixel_pitch_mm;
  info.rig.finger_separation_mm = simulator->finger_separation_mm();
  const auto& obj = scn.object();
  nlohmann::ordered_json meta;
  meta["sim"] = {{"generator", "tacse3-sim"},
                 {"command", command_line(argc, argv)},
                 {"object", o.object},
                 {"shape", sim::to_string(obj.shape)},
                 {"size_mm", obj.size_mm},
                 {"friction", obj.friction},
                 {"offset_mm", {obj.offset_mm.x(), obj.offset_mm.y()}},
                 {"motion",
                  {{"axis", sim::to_string(cfg.scenario.axis)},
                   {"magnitude", cfg.scenario.magnitude},
                   {"unit", rotation ? "deg" : "mm"}}},
                 {"regime", scn.sliding() ? "slide" : "stick"},
                 {"regime_requested", sim::to_string(cfg.scenario.regime)},
                 {"indentation_mm", cfg.scenario.indentation_mm},
                 {"seed", o.seed},
                 {"profile", {{"name", profile.name}, {"values", profile_json(profile)}}},
                 {"noise", cfg.camera.noise},
                 {"flicker", cfg.camera.flicker},
                 {"grasp_end_ns", std::llround(scn.grasp_end_s() * 1e9)},
                 {"motion_start_ns", std::llround(scn.motion_start_s() * 1e9)},
                 {"motion_end_ns", std::llround(scn.motion_end_s() * 1e9)},
                 {"gel",
                  {{"spread_length_mm", cfg.gel.spread_length_mm},
                   {"bulge_gain_mm", cfg.gel.bulge_gain_mm},
                   {"bulge_sigma_mm", cfg.gel.bulge_sigma_mm},
                   {"drag_time_s", cfg.gel.drag_time_s},
                   {"lag_time_s", cfg.gel.lag_time_s},
                   {"shear_compliance", cfg.gel.shear_compliance}}},
                 {"mjpeg_quality", cfg.camera.mjpeg_quality}};
  info.extra_json = meta.dump();

  rec::WriterOptions wopt;
  wopt.png_compression = o.png_level;
  wopt.overwrite = o.overwrite;
  wopt.overwrite_option = "--overwrite";
  auto opened = rec::RecordingWriter::open(o.out, info, wopt);
  if (!opened) return fail(opened.status().message());
  const std::unique_ptr<rec::RecordingWriter> writer_ptr = std::move(opened).value();
  if (!writer_ptr) return fail("cannot open the recording writer");
  rec::RecordingWriter& writer = *writer_ptr;

  const auto start = std::chrono::steady_clock::now();
  const std::size_t nsens = sensors.size();
  std::vector<rec::SimLabel> labels(nsens * static_cast<std::size_t>(frames));
  std::atomic<std::int64_t> done{0};
  std::atomic<bool> abort{false};
  std::vector<std::string> errors(nsens);

  // Each sensor is simulated in order of time by one worker; sensors are independent.
  auto run_sensor = [&](std::size_t slot) {
    const sim::Sensor s = sensors[slot];
    std::vector<std::uint8_t> buf(simulator->frame_bytes(channels));
    for (int i = 0; i < frames && !abort.load(); ++i) {
      const std::int64_t t = scn.frame_time_ns(i);
      const sim::SimStatus st = simulator->render(s, t, buf, channels);
      if (st != sim::SimStatus::kOk) {
        errors[slot] = std::string("render failed: ") + sim::to_string(st);
        abort = true;
        return;
      }
      const rec::ImageView im{buf.data(), cfg.rig.width, cfg.rig.height, channels};
      if (rec::Status ws = writer.write_image(slot, i, im); !ws) {
        errors[slot] = ws.message();
        abort = true;
        return;
      }
      labels[slot * static_cast<std::size_t>(frames) + static_cast<std::size_t>(i)] =
          tacse3::tools::sim_label(*simulator, s, i, t);
      ++done;
    }
  };

  tacse3::tools::ProgressBar bar(
      "tacse3-sim", static_cast<std::int64_t>(frames) * static_cast<std::int64_t>(nsens),
      !o.quiet && tacse3::tools::stderr_is_tty());
  const std::int64_t total = static_cast<std::int64_t>(frames) * static_cast<std::int64_t>(nsens);
  const bool parallel = o.jobs >= 2 && nsens == 2;
  std::thread first([&] {
    for (std::size_t slot = 0; slot < (parallel ? 1 : nsens); ++slot) run_sensor(slot);
  });
  std::thread second;
  if (parallel) second = std::thread([&] { run_sensor(1); });
  while (done.load() < total && !abort.load()) {
    bar.update(done.load());
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  first.join();
  if (second.joinable()) second.join();
  for (const auto& e : errors) {
    if (!e.empty()) return fail(e);
  }
  bar.finish();

  for (int i = 0; i < frames; ++i) {
    const std::int64_t t = scn.frame_time_ns(i);
    if (rec::Status s = writer.append_frame_time(i, t); !s) return fail(s.message());
    const sim::Pose p = simulator->truth(t);
    rec::TruthSample ts;
    ts.t_ns = t;
    ts.qw = p.q.w();
    ts.qx = p.q.x();
    ts.qy = p.q.y();
    ts.qz = p.q.z();
    ts.px = p.p.x() * 1e-3;
    ts.py = p.p.y() * 1e-3;
    ts.pz = p.p.z() * 1e-3;
    if (rec::Status s = writer.append_truth(ts); !s) return fail(s.message());
    for (std::size_t slot = 0; slot < nsens; ++slot) {
      const auto& l = labels[slot * static_cast<std::size_t>(frames) + static_cast<std::size_t>(i)];
      if (rec::Status s = writer.append_sim_label(l); !s) return fail(s.message());
    }
  }
  if (rec::Status s = writer.finish(); !s) return fail(s.message());
  const double secs =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!o.quiet) {
    std::printf(
        "tacse3-sim: wrote %s: %d frames x %zu sensor(s), %.2f s of %s %s %.4g %s (%s), finger "
        "separation %.3f mm, in %.2f s (%.0f sensor-frames/s)\n",
        o.out.c_str(), frames, nsens, scn.duration_s(), o.object.c_str(), o.motion.c_str(),
        cfg.scenario.magnitude, rotation ? "deg" : "mm", scn.sliding() ? "slide" : "stick",
        simulator->finger_separation_mm(), secs, frames * static_cast<double>(nsens) / secs);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Every path out of run() goes through here: the summary is on stdout.
  return tacse3::tools::finish_stdout("tacse3-sim", run(argc, argv));
}
