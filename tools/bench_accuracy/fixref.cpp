// SPDX-License-Identifier: Apache-2.0
// tacse3-fixref: the fixed-point pipeline (dsp::DualPipeline through the replay engine) against
// the double-precision reference (dsp_ref::DualPipelineRef) on ONE simulated recording, per
// velocity-proxy mode, with per-stage and per-frame differences (docs/dsp/reference.md).
#include <CLI/CLI.hpp>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "tacse3/config/calibration_file.hpp"
#include "tacse3/dsp_ref/density_ref.hpp"
#include "tacse3/dsp_ref/nhhd_ref.hpp"
#include "tacse3/dsp_ref/pipeline_ref.hpp"
#include "tacse3/dsp_ref/smoothing_ref.hpp"
#include "tacse3/tools/bench.hpp"
#include "tacse3/tools/cli.hpp"
#include "tacse3/tools/locked_reference.hpp"
#include "tacse3/tools/replay.hpp"
#include "tacse3/tools/sim_source.hpp"

namespace {

namespace tt = tacse3::tools;
namespace dsp = tacse3::dsp;
namespace ref = tacse3::dsp_ref;

constexpr double kQ16 = 1.0 / 65536.0;

// RMS difference of a Q16 vector field against a double one over the points valid in both.
struct FieldDiff {
  double sum2 = 0.0, sig2 = 0.0, big2 = 0.0;  // big2: from differences above 0.02
  long n = 0, big = 0;
  void add(double a, double b) {
    if (std::abs(a - b) > 0.02) {
      big2 += (a - b) * (a - b);
      ++big;
    }
    sum2 += (a - b) * (a - b);
    sig2 += b * b;
    ++n;
  }
  double rms() const { return n ? std::sqrt(sum2 / static_cast<double>(n)) : 0.0; }
  double snr_db() const { return sum2 > 0.0 ? 10.0 * std::log10(sig2 / sum2) : 999.0; }
};

void diff_vector(const dsp::VectorField& f, const ref::GridVectorD& r, const dsp::GridMask& mf,
                 const std::vector<std::uint8_t>* mr, FieldDiff* d) {
  for (std::size_t i = 0; i < static_cast<std::size_t>(dsp::kGridCount); ++i) {
    if (mf.v[i] == 0 || (mr != nullptr && (*mr)[i] == 0)) continue;
    d->add(f.x.v[i] * kQ16, r.x[i]);
    d->add(f.y.v[i] * kQ16, r.y[i]);
  }
}

// What each decision-locked reference follows: the stick/slip decision only, plus the block
// flow's validity and keyframe switches, plus the contact mask (all of them).
const std::array<std::pair<const char*, tt::DecisionFollower::Levels>, 3> kLockLevels = {{
    {"slip", {true, false, false}},
    {"slip+flow", {true, true, false}},
    {"all", {true, true, true}},
}};

struct Runner {
  tt::ProxyMode mode;
  tt::Replayer engine;
  std::unique_ptr<ref::DualPipelineRef> ref;
  std::vector<dsp::Pose> poses, ref_poses;
  // Decision-locked references, one per lock level (kLockLevels).
  std::array<std::unique_ptr<ref::DualPipelineRef>, 3> locked;
  std::array<tt::DecisionFollower, 3> followers;
  std::array<std::vector<dsp::Pose>, 3> locked_poses;
  // The fully locked chain's own stage differences (what the decisions do not explain).
  FieldDiff locked_flow, locked_shear;
  std::array<long, 2> locked_switches{}, fixed_switches{};
  // Accumulated diagnostics.
  long slip_mismatch = 0, frames_contact = 0, mask_mismatch_cells = 0, mask_cells = 0;
  // The region choices of dsp/src/motion.cpp (docs/dsp/motion.md): which sensor-frames set
  // the displacement proxy's anchor, and which read the velocity proxy over Ω ∩ anchor.
  long anchor_set_mismatch = 0, velocity_anchored_mismatch = 0;
  FieldDiff flow, smoothed, d, r, k, shear, shear_in_contact, fz, density;
  long flow_valid_mismatch = 0, smoothed_valid_mismatch = 0, cells = 0;
  // Stages in isolation: the double stage fed with the fixed stage's own input.
  std::array<std::unique_ptr<ref::NhhdRef>, 2> iso_nhhd;
  FieldDiff iso_smoothed, iso_density, iso_d, iso_r, iso_k;
  double omega_diff_int_deg = 0.0;  // ∫ |ω̄_fixed − ω̄_ref| dt (deg)
  std::FILE* csv = nullptr;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Fixed-point pipeline vs double reference on one simulated recording (in memory, grey): "
      "final fixed−ref angle per proxy mode, per-stage differences and per-frame logs."};
  tt::SimCase c;
  std::string cal_in, csv_prefix;
  std::vector<std::string> modes = {"auto", "velocity", "displacement"};
  std::string method = "joint";
  app.add_option("--profile", c.profile, "sensor profile (tacse3-sim --profile)");
  app.add_option("--object", c.object, "simulator object preset");
  app.add_option("--motion", c.motion, "rx, ry, rz, tx, ty");
  app.add_option("--magnitude", c.magnitude, "deg or mm");
  app.add_option("--seed", c.seed, "simulator seed (the test set uses 1)");
  app.add_option("--calibration", cal_in, "calibration file (default: documented defaults)");
  app.add_option("--mode", modes, "proxy modes to run (auto, velocity, displacement)");
  app.add_option("--method", method, "fusion method (joint, paper)");
  app.add_option("--csv", csv_prefix, "write PREFIX-MODE.csv with per-frame differences");
  bool fixed_sampling = false;
  app.add_flag("--ref-fixed-sampling", fixed_sampling,
               "reference block flow on the fixed path's 1/32 px sampling grid (diagnostic)");
  if (const int rc = tacse3::tools::parse_command_line(app, argc, argv); rc >= 0) return rc;
  tacse3::dsp_ref::ReferenceOptions ro;
  ro.fixed_point_sampling = fixed_sampling;

  tacse3::config::CalibrationSet cal;
  if (!cal_in.empty()) {
    if (auto s = tacse3::config::load_calibration(cal_in, &cal); !s) {
      std::fprintf(stderr, "tacse3-fixref: error: %s\n", s.message().c_str());
      return 1;
    }
  }
  dsp::FusionMethod fm{};
  if (!tt::parse_method(method, &fm)) {
    std::fprintf(stderr, "tacse3-fixref: error: bad --method\n");
    return 1;
  }
  tacse3::sim::SimConfig cfg;
  if (std::string e = tt::make_sim_config(c, &cfg); !e.empty()) {
    std::fprintf(stderr, "tacse3-fixref: error: %s\n", e.c_str());
    return 1;
  }
  std::string err;
  auto src = tt::SimSource::create(cfg, c.label(), 1, &err);
  if (!src) {
    std::fprintf(stderr, "tacse3-fixref: error: %s\n", err.c_str());
    return 1;
  }
  const tt::SourceInfo& info = src->info();
  std::vector<std::unique_ptr<Runner>> runners;
  for (const auto& m : modes) {
    auto r = std::make_unique<Runner>();
    if (!tt::parse_mode(m, &r->mode)) {
      std::fprintf(stderr, "tacse3-fixref: error: bad --mode %s\n", m.c_str());
      return 1;
    }
    tt::ReplayOptions o;
    o.calibration = cal;
    o.method = fm;
    o.mode = r->mode;
    if (std::string e = r->engine.init(info, o); !e.empty()) {
      std::fprintf(stderr, "tacse3-fixref: error: %s\n", e.c_str());
      return 1;
    }
    r->ref =
        std::make_unique<ref::DualPipelineRef>(r->engine.setup().dual, r->engine.setup().cal, ro);
    for (std::size_t l = 0; l < kLockLevels.size(); ++l) {
      r->locked[l] =
          std::make_unique<ref::DualPipelineRef>(r->engine.setup().dual, r->engine.setup().cal, ro);
      r->followers[l] = tt::DecisionFollower(kLockLevels[l].second);
    }
    if (!csv_prefix.empty()) {
      const std::string path = csv_prefix + "-" + m + ".csv";
      r->csv = std::fopen(path.c_str(), "w");
      if (r->csv == nullptr) {
        std::fprintf(stderr, "tacse3-fixref: error: cannot write %s\n", path.c_str());
        return 1;
      }
      std::fprintf(r->csv,
                   "frame,angle_diff_deg,wfx,wfy,wfz,wrx,wry,wrz,slip_f0,slip_r0,slip_f1,slip_r1,"
                   "pts_f0,pts_r0,pts_f1,pts_r1,mask_mismatch,shear_rms_px,flow_rms_px,"
                   "rho_f0,rho_r0,shift_f0,shift_r0,ksw_f0,ksw_r0,valid_mismatch0,flow_max0,flow_"
                   "argmax0,valid_f0,valid_r0\n");
    }
    runners.push_back(std::move(r));
  }

  tt::FrameResult row;
  ref::DualResultRef ref_out;
  for (std::size_t i = 0; i < info.frame_count(); ++i) {
    std::array<const dsp::FrameView*, 2> views{};
    if (std::string e = src->read(i, &views); !e.empty()) {
      std::fprintf(stderr, "tacse3-fixref: error: %s\n", e.c_str());
      return 1;
    }
    for (auto& rp : runners) {
      Runner& r = *rp;
      if (std::string e = r.engine.step_views(views, info.t_ns[i], i, &row); !e.empty()) {
        std::fprintf(stderr, "tacse3-fixref: error: %s\n", e.c_str());
        return 1;
      }
      const auto& use = r.engine.setup().use;
      r.ref->process(use[0] ? views[0] : nullptr, use[1] ? views[1] : nullptr, info.t_ns[i],
                     ref_out);
      r.poses.push_back(row.pose);
      r.ref_poses.push_back(ref_out.pose);
      const dsp::DualResult& fres = r.engine.result();
      for (std::size_t l = 0; l < kLockLevels.size(); ++l) {
        const auto& follow = r.followers[l].take(r.engine.pipeline(), fres);
        ref::DualResultRef lo;
        r.locked[l]->process(use[0] ? views[0] : nullptr, use[1] ? views[1] : nullptr, info.t_ns[i],
                             lo, &follow);
        r.locked_poses[l].push_back(lo.pose);
      }
      for (int s = 0; s < 2; ++s) {
        if (!use[static_cast<std::size_t>(s)]) continue;
        const auto& lf = r.engine.pipeline().sensor(static_cast<dsp::SensorSlot>(s)).fields();
        const auto& ls = r.locked.back()->sensor(s);
        diff_vector(lf.flow, ls.flow(), lf.flow_valid, nullptr, &r.locked_flow);
        ref::GridVectorD lsh;
        lsh.x = ls.shear_x();
        lsh.y = ls.shear_y();
        diff_vector(lf.shear, lsh, lf.contact.mask, nullptr, &r.locked_shear);
        if (!fres.sensors[static_cast<std::size_t>(s)].processed) continue;
        r.locked_switches[static_cast<std::size_t>(s)] = ls.flow_stage().keyframe_switches();
        r.fixed_switches[static_cast<std::size_t>(s)] =
            fres.sensors[static_cast<std::size_t>(s)].keyframe_switches;
      }
      const Eigen::Vector3d wf = fres.twist.head<3>(), wr = ref_out.twist.head<3>();
      r.omega_diff_int_deg += (wf - wr).norm() * fres.dt_s * 180.0 / M_PI;
      long frame_mask_mismatch = 0;
      FieldDiff frame_shear, frame_flow;
      int slip[2][2] = {{0, 0}, {0, 0}}, pts[2][2] = {{0, 0}, {0, 0}};
      double rho[2] = {0, 0}, shift[2] = {0, 0};
      long ksw[2] = {0, 0}, valid_mismatch = 0;
      double flow_max = 0.0;
      long flow_argmax = -1, nvalid[2] = {0, 0};
      for (int s = 0; s < 2; ++s) {
        if (!use[static_cast<std::size_t>(s)]) continue;
        const auto& fs = r.engine.pipeline().sensor(static_cast<dsp::SensorSlot>(s));
        const auto& rs = r.ref->sensor(s);
        const dsp::SensorFields& f = fs.fields();
        const auto* fv = &rs.flow_valid();
        const auto* sv = &rs.smoothed_valid();
        diff_vector(f.flow, rs.flow(), f.flow_valid, fv, &r.flow);
        diff_vector(f.flow, rs.flow(), f.flow_valid, fv, &frame_flow);
        diff_vector(f.smoothed, rs.smoothed(), f.smoothed_valid, sv, &r.smoothed);
        diff_vector(f.d, rs.d(), f.smoothed_valid, sv, &r.d);
        diff_vector(f.r, rs.r(), f.smoothed_valid, sv, &r.r);
        diff_vector(f.k, rs.k(), f.smoothed_valid, sv, &r.k);
        ref::GridVectorD sh;
        sh.x = rs.shear_x();
        sh.y = rs.shear_y();
        diff_vector(f.shear, sh, f.smoothed_valid, sv, &r.shear);
        {
          const ref::GridVectorD fin = ref::grid_vector_from_q16(f.flow);
          const ref::GridMaskD fval = ref::grid_mask_from(f.flow_valid);
          ref::GridVectorD so;
          ref::GridMaskD sov;
          ref::smooth_ref(fin, fval, fs.config().smoothing, so, sov);
          diff_vector(f.smoothed, so, f.smoothed_valid, &sov, &r.iso_smoothed);
          const ref::GridVectorD sin = ref::grid_vector_from_q16(f.smoothed);
          const ref::GridMaskD sval = ref::grid_mask_from(f.smoothed_valid);
          const ref::GridScalarD g = ref::gaussian_density_ref(sin, sval, fs.config().density);
          for (std::size_t j = 0; j < static_cast<std::size_t>(dsp::kGridCount); ++j) {
            if (sval[j] != 0) r.iso_density.add(f.density.v[j] * kQ16, g[j]);
          }
          auto& nh = r.iso_nhhd[static_cast<std::size_t>(s)];
          if (!nh) nh = std::make_unique<ref::NhhdRef>(fs.config().nhhd);
          ref::GridVectorD dd, rr, kk;
          nh->decompose(sin, sval, dd, rr, kk);
          diff_vector(f.d, dd, f.smoothed_valid, nullptr, &r.iso_d);
          diff_vector(f.r, rr, f.smoothed_valid, nullptr, &r.iso_r);
          diff_vector(f.k, kk, f.smoothed_valid, nullptr, &r.iso_k);
        }
        const auto& rc = rs.contact();
        const auto& fr = fres.sensors[static_cast<std::size_t>(s)];
        if (!rc.mask.empty()) {
          diff_vector(f.shear, sh, f.contact.mask, &rc.mask, &r.shear_in_contact);
          diff_vector(f.shear, sh, f.contact.mask, &rc.mask, &frame_shear);
          for (std::size_t j = 0; j < static_cast<std::size_t>(dsp::kGridCount); ++j) {
            const bool a = f.contact.mask.v[j] != 0, b = rc.mask[j] != 0;
            r.mask_cells += (a || b) ? 1 : 0;
            if (a != b) {
              ++r.mask_mismatch_cells;
              ++frame_mask_mismatch;
            }
            if (f.smoothed_valid.v[j] != 0 && (*sv)[j] != 0) r.fz.add(f.fz.v[j] * kQ16, rs.fz()[j]);
            if (f.smoothed_valid.v[j] != 0 && (*sv)[j] != 0) {
              r.density.add(f.density.v[j] * kQ16, rs.density()[j]);
            }
            if (f.flow_valid.v[j] != (*fv)[j]) ++r.flow_valid_mismatch;
            if (f.smoothed_valid.v[j] != (*sv)[j]) ++r.smoothed_valid_mismatch;
            ++r.cells;
          }
        }
        const auto& rm = rs.motion();
        slip[s][0] = fr.motion.slipping ? 1 : 0;
        slip[s][1] = rm.slipping ? 1 : 0;
        pts[s][0] = fr.motion.points;
        pts[s][1] = rm.points;
        if (s == 0) {
          ksw[0] = fr.keyframe_switches;
          ksw[1] = rs.flow_stage().keyframe_switches();
          for (std::size_t j = 0; j < static_cast<std::size_t>(dsp::kGridCount); ++j) {
            const bool a = f.flow_valid.v[j] != 0, b = rs.flow_valid()[j] != 0;
            if (a != b) ++valid_mismatch;
            nvalid[0] += a ? 1 : 0;
            nvalid[1] += b ? 1 : 0;
            if (a && b) {
              const double e = std::hypot(f.flow.x.v[j] * kQ16 - rs.flow().x[j],
                                          f.flow.y.v[j] * kQ16 - rs.flow().y[j]);
              if (e > 0.02 && std::getenv("FIXREF_OUTLIERS") != nullptr) {
                const int gx = static_cast<int>(j) % dsp::kGridWidth;
                const int gy = static_cast<int>(j) / dsp::kGridWidth;
                int nm = 0;
                for (int oy = -1; oy <= 1; ++oy) {
                  for (int ox = -1; ox <= 1; ++ox) {
                    const int x = gx + ox, y = gy + oy;
                    if (x < 0 || y < 0 || x >= dsp::kGridWidth || y >= dsp::kGridHeight) continue;
                    const auto q = static_cast<std::size_t>(y * dsp::kGridWidth + x);
                    nm += (f.flow_valid.v[q] != 0) != (rs.flow_valid()[q] != 0) ? 1 : 0;
                  }
                }
                std::fprintf(stderr,
                             "outlier %s frame %zu point (%d,%d) fixed (%.4f,%.4f) ref (%.4f,%.4f) "
                             "ksw %u/%d neighbour-validity-mismatch %d\n",
                             tt::to_string(r.mode), i, gx, gy, f.flow.x.v[j] * kQ16,
                             f.flow.y.v[j] * kQ16, rs.flow().x[j], rs.flow().y[j],
                             fr.keyframe_switches, rs.flow_stage().keyframe_switches(), nm);
              }
              if (e > flow_max) {
                flow_max = e;
                flow_argmax = static_cast<long>(j);
              }
            }
          }
          rho[0] = fr.motion.slip_relax_rate;
          rho[1] = rm.slip_relax_rate;
          shift[0] = fr.motion.shear_shift_m;
          shift[1] = rm.shear_shift_m;
        }
        if (fr.motion.contact || rm.contact) {
          ++r.frames_contact;
          if (fr.motion.slipping != rm.slipping) ++r.slip_mismatch;
          if (fr.motion.anchor_set != rm.anchor_set) ++r.anchor_set_mismatch;
          if (fr.motion.velocity_anchored != rm.velocity_anchored) {
            ++r.velocity_anchored_mismatch;
          }
        }
      }
      if (r.csv != nullptr) {
        std::fprintf(r.csv,
                     "%zu,%.6f,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%d,%d,%d,%d,%d,%d,%d,%ld,%.6g,%.6g,"
                     "%.5g,%.5g,%.5g,%.5g,%ld,%ld,%ld,%.5g,%ld,%ld,%ld\n",
                     i, tt::rotation_error_deg(row.pose.q, ref_out.pose.q), wf.x(), wf.y(), wf.z(),
                     wr.x(), wr.y(), wr.z(), slip[0][0], slip[0][1], slip[1][0], slip[1][1],
                     pts[0][0], pts[0][1], pts[1][0], pts[1][1], frame_mask_mismatch,
                     frame_shear.rms(), frame_flow.rms(), rho[0], rho[1], shift[0], shift[1],
                     ksw[0], ksw[1], valid_mismatch, flow_max, flow_argmax, nvalid[0], nvalid[1]);
      }
    }
  }
  std::printf("%s (%zu frames), method %s\n", c.label().c_str(), info.frame_count(),
              method.c_str());
  std::printf(
      "mode          fixed-ref(deg)  fixed err  ref err  int|dw|(deg)  slip-mismatch  "
      "mask-mismatch  flow rms px/SNR  smooth  d  r  k  shear(all)  shear(contact)  fz\n");
  for (auto& rp : runners) {
    Runner& r = *rp;
    const tt::PoseErrors fe = tt::pose_errors(r.poses, info.truth, info.t_ns);
    const tt::PoseErrors re = tt::pose_errors(r.ref_poses, info.truth, info.t_ns);
    std::printf(
        "%-12s  %14.4f  %9.3f  %7.3f  %12.4f  %6ld/%-6ld  %6ld/%-7ld  %.2e/%.1f  %.1f  %.1f  %.1f  "
        "%.1f  %.1f  %.2e/%.1f  %.1f dB\n",
        tt::to_string(r.mode), tt::rotation_error_deg(r.poses.back().q, r.ref_poses.back().q),
        fe.final_rotation_error_deg, re.final_rotation_error_deg, r.omega_diff_int_deg,
        r.slip_mismatch, r.frames_contact, r.mask_mismatch_cells, r.mask_cells, r.flow.rms(),
        r.flow.snr_db(), r.smoothed.snr_db(), r.d.snr_db(), r.r.snr_db(), r.k.snr_db(),
        r.shear.snr_db(), r.shear_in_contact.rms(), r.shear_in_contact.snr_db(), r.fz.snr_db());
    std::printf(
        "              region choices differing (sensor-frames in contact): anchor set %ld, "
        "velocity proxy over the anchored patch %ld\n",
        r.anchor_set_mismatch, r.velocity_anchored_mismatch);
    std::printf(
        "              stage SNR over points valid in both: flow %.1f dB, smoothed %.1f, "
        "density %.1f, d %.1f, r %.1f, k %.1f, shear %.1f, fz %.1f; validity mismatches: "
        "flow %ld, smoothed %ld of %ld\n",
        r.flow.snr_db(), r.smoothed.snr_db(), r.density.snr_db(), r.d.snr_db(), r.r.snr_db(),
        r.k.snr_db(), r.shear.snr_db(), r.fz.snr_db(), r.flow_valid_mismatch,
        r.smoothed_valid_mismatch, r.cells);
    std::printf(
        "              flow: %ld of %ld components differ by > 0.02 px and carry %.1f %% of "
        "the difference energy; SNR without them %.1f dB\n",
        r.flow.big, r.flow.n, r.flow.sum2 > 0 ? 100.0 * r.flow.big2 / r.flow.sum2 : 0.0,
        10.0 * std::log10(r.flow.sig2 / std::max(1e-300, r.flow.sum2 - r.flow.big2)));
    std::printf(
        "              stages in isolation (double stage on the fixed stage's input): "
        "smoothed %.1f dB, density %.1f, d %.1f, r %.1f, k %.1f\n",
        r.iso_smoothed.snr_db(), r.iso_density.snr_db(), r.iso_d.snr_db(), r.iso_r.snr_db(),
        r.iso_k.snr_db());
    std::printf(
        "  locked all: flow SNR %.1f dB (%ld of %ld components > 0.02 px), shear in Ω SNR "
        "%.1f dB; keyframe switches fixed %ld/%ld, reference %ld/%ld\n",
        r.locked_flow.snr_db(), r.locked_flow.big, r.locked_flow.n, r.locked_shear.snr_db(),
        r.fixed_switches[0], r.fixed_switches[1], r.locked_switches[0], r.locked_switches[1]);
    for (std::size_t l = 0; l < kLockLevels.size(); ++l) {
      std::printf(
          "  locked %-10s %10.4f  (reference following the fixed pipeline's %s decisions; "
          "ref err %.3f)\n",
          kLockLevels[l].first,
          tt::rotation_error_deg(r.poses.back().q, r.locked_poses[l].back().q),
          kLockLevels[l].first,
          tt::pose_errors(r.locked_poses[l], info.truth, info.t_ns).final_rotation_error_deg);
    }
    if (r.csv != nullptr) std::fclose(r.csv);
  }
  return 0;
}
