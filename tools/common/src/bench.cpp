// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: simulated accuracy cases rendered in memory and evaluated through the replay
// engine (and, on request, the double-precision reference pipeline in lock step).
#include "tacse3/tools/bench.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "tacse3/dsp_ref/pipeline_ref.hpp"
#include "tacse3/sim/profile.hpp"
#include "tacse3/tools/locked_reference.hpp"
#include "tacse3/tools/sim_source.hpp"

namespace tacse3::tools {

std::string SimCase::label() const {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "%s %s %g", object.c_str(), motion.c_str(), magnitude);
  return buf;
}

std::string SimCase::sim_arguments() const {
  char buf[256];
  std::snprintf(buf, sizeof(buf), "--object %s --motion %s --magnitude %g --seed %llu",
                object.c_str(), motion.c_str(), magnitude, static_cast<unsigned long long>(seed));
  std::string s = buf;
  double nominal_indentation = 1.0;
  if (profile != "reference") {
    s.append(" --profile ").append(profile);
    sim::SensorProfile p;
    std::string e;
    if (sim::make_profile(profile, seed, &p, &e)) nominal_indentation = p.indentation_mm;
  }
  if (radius_mm > 0.0) {
    std::snprintf(buf, sizeof(buf), " --radius %g", radius_mm);
    s += buf;
  }
  if (indentation_mm != 1.0) {
    std::snprintf(buf, sizeof(buf), " --indentation %g", indentation_mm * nominal_indentation);
    s += buf;
  }
  if (friction > 0.0) {
    std::snprintf(buf, sizeof(buf), " --friction %g", friction);
    s += buf;
  }
  if (hold_s != 0.4 || approach_s != 0.1 || grasp_s != 0.4 || settle_s != 0.1) {
    std::snprintf(buf, sizeof(buf), " --approach-s %g --grasp-s %g --settle-s %g --hold-s %g",
                  approach_s, grasp_s, settle_s, hold_s);
    s += buf;
  }
  if (release_s > 0.0) {
    std::snprintf(buf, sizeof(buf), " --release-s %g", release_s);
    s += buf;
  }
  return s;
}

std::string parse_profile_list(const std::string& text, std::vector<std::string>* out) {
  const std::string names = sim::profile_names();
  out->clear();
  if (text == "all") {
    // The named profiles and three sensors of the random profile. Each is one physics in every
    // recording, as a calibration is of one sensor; "random" itself, another sensor in each
    // recording, is run when asked for by name.
    for (std::size_t start = 0; start < names.size();) {
      const std::size_t end = std::min(names.find(", ", start), names.size());
      if (names.compare(start, end - start, "random") != 0) {
        out->push_back(names.substr(start, end - start));
      }
      start = end + 2;
    }
    for (const char* sensor : {"random:1", "random:2", "random:3"}) out->push_back(sensor);
    return {};
  }
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    const std::string name = text.substr(start, end - start);
    sim::SensorProfile p;
    if (!sim::make_profile(name, 0, &p, nullptr)) {
      std::string e = "unknown profile \"";
      e.append(name).append("\" (one of: ").append(names).append(", random:N, or all)");
      return e;
    }
    out->push_back(name);
    start = end + 1;
  }
  return {};
}

bool shear_carries_speed(const SimCase& c) {
  sim::SimConfig cfg;
  if (!make_sim_config(c, &cfg).empty()) return false;
  // Only an in-plane rotation drags the deepest contact point across the gel; a torsion's
  // deepest point stays put and a translation is read from the mask centroid, not the shear.
  if (cfg.scenario.axis != sim::MotionAxis::kRx && cfg.scenario.axis != sim::MotionAxis::kRy) {
    return true;
  }
  // Peak surface speed at the deepest point: the minimum-jerk profile's peak rate, 15/8 of the
  // mean, on the lever of the object's surface on the grasp axis (its size). The slide law holds
  // the shear at the cap mu kappa d, which reads as a speed of mu kappa d / c
  // (docs/simulator.md, tangential response; tools/analysis/friction_cap_bound.py).
  const sim::Scenario scn(cfg.scenario);
  const double angle = std::abs(cfg.scenario.magnitude) * M_PI / 180.0;
  const double peak = 1.875 * angle / scn.motion_duration_s() * cfg.scenario.object.size_mm;
  const double cap = cfg.scenario.object.friction * cfg.gel.shear_compliance *
                     cfg.scenario.indentation_mm / cfg.gel.drag_time_s;
  return peak <= cap;
}

std::string make_sim_config(const SimCase& c, sim::SimConfig* out) {
  sim::SimConfig cfg;
  cfg.seed = c.seed;
  cfg.scenario.object.seed = c.seed;
  if (!sim::object_preset(c.object, &cfg.scenario.object)) {
    return "unknown object \"" + c.object + "\"";
  }
  if (!sim::parse_axis(c.motion, &cfg.scenario.axis)) return "unknown motion \"" + c.motion + "\"";
  cfg.scenario.magnitude = c.magnitude;
  sim::SensorProfile profile;
  if (std::string e; !sim::make_profile(c.profile, c.seed, &profile, &e)) return e;
  sim::apply_profile(profile, &cfg);
  cfg.scenario.indentation_mm = c.indentation_mm * profile.indentation_mm;
  cfg.scenario.approach_s = c.approach_s;
  cfg.scenario.grasp_s = c.grasp_s;
  cfg.scenario.settle_s = c.settle_s;
  cfg.scenario.hold_s = c.hold_s;
  cfg.scenario.release_s = c.release_s;
  if (c.radius_mm > 0.0) cfg.scenario.object.size_mm = c.radius_mm;
  if (c.friction > 0.0) cfg.scenario.object.friction = c.friction;
  if (std::string e = sim::validate(cfg); !e.empty()) return c.label() + ": " + e;
  *out = cfg;
  return {};
}

std::int64_t case_frames(const SimCase& c) {
  sim::SimConfig cfg;
  if (!make_sim_config(c, &cfg).empty()) return 0;
  return sim::Scenario(cfg.scenario).frame_count();
}

std::string evaluate_case(const SimCase& c, const config::CalibrationSet& cal,
                          const std::vector<EvalConfig>& configs, std::vector<EvalResult>* out,
                          std::atomic<std::int64_t>* frames_done) {
  sim::SimConfig cfg;
  if (std::string e = make_sim_config(c, &cfg); !e.empty()) return e;
  std::string err;
  auto src = SimSource::create(cfg, c.label(), 1, &err);
  if (!src) return err;
  const SourceInfo& info = src->info();
  struct Runner {
    Replayer engine;
    std::unique_ptr<dsp_ref::DualPipelineRef> ref, locked;
    std::vector<dsp::Pose> poses;
    std::vector<dsp::Pose> ref_poses, locked_poses;
    std::vector<FrameResult> rows;
    DecisionFollower follower;
  };
  std::vector<std::unique_ptr<Runner>> runners;
  for (const auto& ec : configs) {
    auto r = std::make_unique<Runner>();
    ReplayOptions o;
    o.calibration = cal;
    o.method = ec.method;
    o.mode = ec.mode;
    o.sensors = ec.sensors;
    if (std::string e = r->engine.init(info, o); !e.empty()) return e;
    if (ec.reference) {
      r->ref =
          std::make_unique<dsp_ref::DualPipelineRef>(r->engine.setup().dual, r->engine.setup().cal);
      r->locked =
          std::make_unique<dsp_ref::DualPipelineRef>(r->engine.setup().dual, r->engine.setup().cal);
    }
    runners.push_back(std::move(r));
  }
  FrameResult row;
  dsp_ref::DualResultRef ref_out;
  for (std::size_t i = 0; i < info.frame_count(); ++i) {
    std::array<const dsp::FrameView*, 2> views{};
    if (std::string e = src->read(i, &views); !e.empty()) return e;
    for (auto& r : runners) {
      if (std::string e = r->engine.step_views(views, info.t_ns[i], i, &row); !e.empty()) return e;
      r->poses.push_back(row.pose);
      r->rows.push_back(row);
      if (r->ref) {
        const auto& use = r->engine.setup().use;
        r->ref->process(use[0] ? views[0] : nullptr, use[1] ? views[1] : nullptr, info.t_ns[i],
                        ref_out);
        r->ref_poses.push_back(ref_out.pose);
      }
      if (r->locked) {
        const auto& use = r->engine.setup().use;
        const auto& follow = r->follower.take(r->engine.pipeline(), r->engine.result());
        r->locked->process(use[0] ? views[0] : nullptr, use[1] ? views[1] : nullptr, info.t_ns[i],
                           ref_out, &follow);
        r->locked_poses.push_back(ref_out.pose);
      }
    }
    if (frames_done != nullptr) ++*frames_done;
  }
  out->assign(configs.size(), EvalResult{});
  for (std::size_t k = 0; k < runners.size(); ++k) {
    Runner& r = *runners[k];
    EvalResult& e = (*out)[k];
    e.errors = pose_errors(r.poses, info.truth, info.t_ns);
    e.tracking = tracking_error(r.poses, info.truth, info.t_ns);
    if (r.ref) {
      const PoseErrors re = pose_errors(r.ref_poses, info.truth, info.t_ns);
      e.reference_error_deg = re.final_rotation_error_deg;
      e.reference_translation_error_mm = re.final_translation_error_mm;
      e.fixed_vs_reference_deg = rotation_error_deg(r.poses.back().q, r.ref_poses.back().q);
    }
    if (r.locked) {
      e.fixed_vs_locked_reference_deg =
          rotation_error_deg(r.poses.back().q, r.locked_poses.back().q);
    }
    const RunSummary s = summarize(info, r.rows, configs[k].sensors);
    e.slip = s.slip;
    e.slip_scored = s.has_slip_score;
  }
  return {};
}

std::string write_case_recording(const SimCase& c, const std::filesystem::path& dir, int channels,
                                 SensorChoice sensors) {
  namespace rec = tacse3::recording;
  sim::SimConfig cfg;
  if (std::string e = make_sim_config(c, &cfg); !e.empty()) return e;
  cfg.sensors = {sensors != SensorChoice::kRight, sensors != SensorChoice::kLeft};
  std::string err;
  auto src = SimSource::create(cfg, c.label(), channels, &err);
  if (!src) return err;
  const SourceInfo& info = src->info();
  rec::RecordingInfo ri;
  ri.sensors.clear();
  for (std::size_t k = 0; k < 2; ++k) {
    if (cfg.sensors[k]) ri.sensors.push_back(static_cast<rec::SensorId>(k));
  }
  ri.fps = cfg.scenario.fps;
  ri.rig.pixel_pitch_mm = info.pixel_pitch_mm;
  ri.rig.finger_separation_mm = info.finger_separation_mm;
  ri.extra_json = info.extra_json;
  rec::WriterOptions wo;
  wo.overwrite = true;
  auto w = rec::RecordingWriter::open(dir, ri, wo);
  if (!w) return w.status().message();
  rec::RecordingWriter& writer = *w.value();
  for (std::size_t i = 0; i < info.frame_count(); ++i) {
    std::array<const dsp::FrameView*, 2> views{};
    if (std::string e = src->read(i, &views); !e.empty()) return e;
    std::vector<rec::ImageView> ims;
    for (std::size_t k = 0; k < 2; ++k) {
      if (views[k] != nullptr) {
        ims.push_back({views[k]->data, views[k]->width, views[k]->height, channels});
      }
    }
    if (rec::Status s = writer.write_frame(info.t_ns[i], ims); !s) return s.message();
    if (rec::Status s = writer.append_truth(info.truth[i]); !s) return s.message();
  }
  for (const auto& l : info.labels) {
    if (rec::Status s = writer.append_sim_label(l); !s) return s.message();
  }
  if (rec::Status s = writer.finish(); !s) return s.message();
  return {};
}

std::string calibrate_cases(const std::vector<SimCase>& cases, const CalibrateOptions& options,
                            CalibrateReport* report) {
  std::vector<std::unique_ptr<SimSource>> owned;
  std::vector<FrameSource*> sources;
  for (const auto& c : cases) {
    sim::SimConfig cfg;
    if (std::string e = make_sim_config(c, &cfg); !e.empty()) return e;
    std::string err;
    auto s = SimSource::create(cfg, c.label(), 1, &err);
    if (!s) return err;
    sources.push_back(s.get());
    owned.push_back(std::move(s));
  }
  if (std::string e = calibrate(sources, options, report); !e.empty()) return e;
  // The sources live in memory: record how to re-create them.
  auto& meta = report->calibration.meta;
  meta.recordings.clear();
  for (const auto& c : cases) meta.recordings.push_back("tacse3-sim " + c.sim_arguments());
  meta.note =
      "fitted on simulated recordings rendered in memory (grey); recreate each with the "
      "tacse3-sim options listed in recordings";
  return {};
}

}  // namespace tacse3::tools
