// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: calibration fit: τ from the f^z noise, gains and scales by least squares on
// integrated rotations against the truth, all from runs of the real fixed-point pipeline.
#include "tacse3/tools/calibrate.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <iterator>
#include <limits>
#include <mutex>
#include <numbers>
#include <thread>

#include "tacse3/dsp/calibration_fields.hpp"
#include "tacse3/tools/calibration_check.hpp"
#include "tacse3/tools/contact_area.hpp"
#include "tacse3/tools/contact_noise.hpp"
#include "tacse3/tools/progress.hpp"
#include "tacse3/tools/rest_persistence.hpp"

namespace tacse3::tools {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;
constexpr double kQ16 = 1.0 / 65536.0;
constexpr int kModes = 2;       // 0 = velocity proxy, 1 = displacement proxy
constexpr int kComponents = 3;  // shear from d, r, k
// Rotations below this count as "no rotation" in the relative weights (a translation or a tiny
// stick motion still has its drift weighed, against 3 degrees).
constexpr double kWeightFloorRad = 3.0 / kDeg;
// A recording whose truth rotates this much or more about an axis excites that axis: its per-axis
// scales are fitted. The truth is exact, so this only keeps out recordings that do not rotate
// about the axis (a translation, or another axis's motion); a stick motion of 1-2 deg is read with
// the displacement proxy closely and does excite it. (At 3 deg, the weight floor, an axis with
// only 2 deg stick recordings would leave the displacement proxy's scale unfitted: it would take
// the velocity proxy's, and a small stick about that axis would read well over.)
constexpr double kExciteFloorRad = 1.0 / kDeg;
// Sanity bounds of the joint fusion's per-axis rotation scales: that fusion is in rad/s with the
// physical lever arm, so a scale far from 1 would only fit noise.
constexpr double kJointScaleMin = 0.5, kJointScaleMax = 2.0;
// After this many iterations the proxy assignment is frozen (the alternation may otherwise cycle
// between two assignments); the gains then converge for that assignment.
constexpr int kFreezeAssignmentAfter = 20;
// The alternation stops when no gain moves by kFitConverged (relative for the proxy factors, which
// enter as logarithms) in an iteration, or after kMaxFitIterations (the report then says how far
// from converged: the file keeps four significant digits).
constexpr int kMaxFitIterations = 200;
constexpr double kFitConverged = 1e-9;
// A recording is explained by the velocity proxy if less than this share of its velocity-proxy
// rate persists at rest (rest_persistence).
constexpr double kRestPersistenceMax = 0.5;
// Ridge weight pulling the shear gains towards the starting ones, relative to the data term's
// mean curvature (the three gains are nearly collinear on few recordings).
constexpr double kShearRidge = 0.1;
// Relative cost difference below which two slip-detector candidates are a tie (stage 2b).
constexpr double kDetectorCostTie = 0.01;

ProxyMode mode_of(int m) {
  return m == 0 ? ProxyMode::kVelocity : ProxyMode::kDisplacement;
}

// ---- one pass: K engines in lock step over one source ----------------------------------------
struct RunOutput {
  Eigen::Vector3d rot_integral = Eigen::Vector3d::Zero();  // Σ ω̄ Δt, rad (what is integrated)
  dsp::Pose final_pose{};
  std::vector<Eigen::Vector3d> omega;  // per-frame ω̄ (kept when asked for)
};

// Each pad's filter(f^z) of the engine's last frame, NaN where not valid.
void add_fz_grids(const Replayer& engine, const std::array<const dsp::FrameView*, 2>& views,
                  PreMotionFz* pre) {
  for (std::size_t s = 0; s < 2; ++s) {
    const dsp::SensorFields& f = engine.pipeline().sensor(static_cast<dsp::SensorSlot>(s)).fields();
    FzGrid g;
    for (std::size_t i = 0; i < g.size(); ++i) {
      g[i] = views[s] != nullptr && f.smoothed_valid.v[i] != 0
                 ? static_cast<float>(f.contact.fz_filtered.v[i] * kQ16)
                 : std::numeric_limits<float>::quiet_NaN();
    }
    pre->add(s, g);
  }
}

// `pre`, when given, receives both pads' f^z of the frames before `pre_frames`.
std::string run_pass(FrameSource& src, const std::vector<ReplayOptions>& configs,
                     std::atomic<std::int64_t>* done, PreContactNoise* noise,
                     std::vector<RunOutput>* out, bool keep_omega = false,
                     PreMotionFz* pre = nullptr, std::size_t pre_frames = 0) {
  const SourceInfo& info = src.info();
  std::vector<std::unique_ptr<Replayer>> engines;
  for (const auto& c : configs) {
    engines.push_back(std::make_unique<Replayer>());
    if (std::string e = engines.back()->init(info, c); !e.empty()) return e;
  }
  out->assign(configs.size(), RunOutput{});
  FrameResult r;
  std::vector<double> fz;
  for (std::size_t i = 0; i < info.frame_count(); ++i) {
    std::array<const dsp::FrameView*, 2> views{};
    if (std::string e = src.read(i, &views); !e.empty()) return e;
    for (std::size_t k = 0; k < engines.size(); ++k) {
      if (std::string e = engines[k]->step_views(views, info.t_ns[i], i, &r); !e.empty()) return e;
      (*out)[k].rot_integral += r.twist.head<3>() * r.dt_s;
      (*out)[k].final_pose = r.pose;
      if (keep_omega) (*out)[k].omega.push_back(r.twist.head<3>());
    }
    if (noise != nullptr && !noise->onset_found()) {
      fz.clear();
      for (std::size_t s = 0; s < 2; ++s) {
        if (views[s] == nullptr) continue;
        const dsp::SensorFields& f =
            engines[0]->pipeline().sensor(static_cast<dsp::SensorSlot>(s)).fields();
        for (std::size_t g = 0; g < static_cast<std::size_t>(dsp::kGridCount); ++g) {
          if (f.smoothed_valid.v[g] != 0) fz.push_back(f.contact.fz_filtered.v[g] * kQ16);
        }
      }
      noise->add_frame(i, fz);
    }
    if (pre != nullptr && i < pre_frames) add_fz_grids(*engines[0], views, pre);
    if (done != nullptr) ++*done;
  }
  return {};
}

// ---- the least-squares model ------------------------------------------------------------------
// est_r = diag(a) · k_m · Σ_c s_c · I_r[m][c]: integrated rotation of recording r under proxy m
// with shear gains s, proxy gain factor k_m and per-axis rotation scales a, against θ_r.
struct FitData {
  Eigen::Vector3d theta = Eigen::Vector3d::Zero();
  std::array<std::array<Eigen::Vector3d, kComponents>, kModes> I{};
  double w = 1.0;
  // Proxy whose per-frame rate follows the truth's rate best (scale-free), or -1 when the
  // recording does not rotate enough to tell; such recordings go to the proxy with less drift.
  int preferred = -1;
};

struct FitParams {
  std::array<double, kComponents> s{0.0, 1.0, 1.0};
  std::array<double, kModes> k{1.0, 1.0};
  // Per-axis rotation scales per proxy (the file stores the velocity proxy's as rotation_scale
  // and the displacement proxy's as displacement_rotation_ratio = a[1] / a[0]).
  std::array<Eigen::Vector3d, kModes> a{Eigen::Vector3d::Ones(), Eigen::Vector3d::Ones()};
  std::vector<int> mode;
};

Eigen::Vector3d combine(const FitData& d, const std::array<double, kComponents>& s, int m) {
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int c = 0; c < kComponents; ++c)
    v += s[static_cast<std::size_t>(c)] *
         d.I[static_cast<std::size_t>(m)][static_cast<std::size_t>(c)];
  return v;
}

Eigen::Vector3d predict(const FitData& d, const FitParams& p, int m) {
  return p.a[static_cast<std::size_t>(m)].cwiseProduct(combine(d, p.s, m)) *
         p.k[static_cast<std::size_t>(m)];
}

double cost(const FitData& d, const FitParams& p, int m) {
  return d.w * (predict(d, p, m) - d.theta).squaredNorm();
}

// min over s ≥ 0 of sᵀMs − 2bᵀs by enumerating the active sets (3 unknowns).
std::array<double, 3> nnls3(const Eigen::Matrix3d& M, const Eigen::Vector3d& b,
                            const std::array<double, 3>& fallback) {
  double best = std::numeric_limits<double>::infinity();
  std::array<double, 3> out = fallback;
  for (int mask = 1; mask < 8; ++mask) {
    std::vector<int> idx;
    for (int i = 0; i < 3; ++i) {
      if (mask & (1 << i)) idx.push_back(i);
    }
    const auto n = static_cast<Eigen::Index>(idx.size());
    Eigen::MatrixXd Ms(n, n);
    Eigen::VectorXd bs(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      bs(i) = b(idx[static_cast<std::size_t>(i)]);
      for (Eigen::Index j = 0; j < n; ++j)
        Ms(i, j) = M(idx[static_cast<std::size_t>(i)], idx[static_cast<std::size_t>(j)]);
    }
    const double tr = Ms.trace();
    if (!(tr > 0.0)) continue;
    Ms += 1e-12 * tr * Eigen::MatrixXd::Identity(n, n);
    const Eigen::VectorXd x = Ms.ldlt().solve(bs);
    if (!x.allFinite() || (x.array() < 0.0).any()) continue;
    Eigen::Vector3d full = Eigen::Vector3d::Zero();
    for (Eigen::Index i = 0; i < n; ++i) full(idx[static_cast<std::size_t>(i)]) = x(i);
    const double f = full.dot(M * full) - 2.0 * b.dot(full);
    if (f < best) {
      best = f;
      out = {full(0), full(1), full(2)};
    }
  }
  return out;
}

struct FitResult {
  FitParams p;
  int iterations = 0;
  bool converged = false;    // the last iteration changed no gain by kFitConverged or more
  double last_change = 0.0;  // largest change of a gain in the last iteration
  std::vector<std::string> notes;
  // Per proxy and axis: the scale was fitted on that proxy's recordings (false: the axis is
  // excited by the other proxy's recordings only and takes that proxy's scale).
  std::array<std::array<bool, 3>, kModes> own_axis{};
  std::array<bool, 3> excited{};
  // The last iteration's least-squares scale per proxy and axis, and whether the sanity bound
  // kJointScaleMin .. kJointScaleMax stopped it.
  std::array<Eigen::Vector3d, kModes> raw_a{Eigen::Vector3d::Ones(), Eigen::Vector3d::Ones()};
  std::array<std::array<bool, 3>, kModes> clamped{};
};

FitResult fit_model(const std::vector<FitData>& data, const FitParams& start) {
  FitResult res;
  FitParams p = start;
  const std::size_t n = data.size();
  p.mode.assign(n, 0);
  // Initial assignment: the proxy whose best single-gain fit explains the recording best
  // (scale-free); recordings without a rotation worth the name: the proxy with less drift at the
  // starting gains.
  for (std::size_t r = 0; r < n; ++r) {
    const FitData& d = data[r];
    if (d.preferred >= 0) {
      p.mode[r] = d.preferred;
      continue;
    }
    double best = std::numeric_limits<double>::infinity();
    for (int m = 0; m < kModes; ++m) {
      const Eigen::Vector3d e = combine(d, p.s, m);
      double c = 0.0;
      if (d.theta.norm() >= kWeightFloorRad && e.squaredNorm() > 0.0) {
        const double g = std::max(0.0, e.dot(d.theta) / e.squaredNorm());
        c = (g * e - d.theta).squaredNorm() / d.theta.squaredNorm();
      } else {
        c = (e - d.theta).squaredNorm();
      }
      if (c < best) {
        best = c;
        p.mode[r] = m;
      }
    }
  }
  std::array<bool, 3> excited{false, false, false};
  for (const auto& d : data) {
    for (int ax = 0; ax < 3; ++ax)
      excited[static_cast<std::size_t>(ax)] =
          excited[static_cast<std::size_t>(ax)] || std::abs(d.theta(ax)) >= kExciteFloorRad;
  }
  for (int it = 0; it < kMaxFitIterations; ++it) {
    res.iterations = it + 1;
    const FitParams before = p;
    // (1) proxy gain factor per mode.
    for (int m = 0; m < kModes; ++m) {
      double num = 0.0, den = 0.0;
      for (std::size_t r = 0; r < n; ++r) {
        if (p.mode[r] != m) continue;
        const Eigen::Vector3d e =
            p.a[static_cast<std::size_t>(m)].cwiseProduct(combine(data[r], p.s, m));
        num += data[r].w * e.dot(data[r].theta);
        den += data[r].w * e.squaredNorm();
      }
      if (den > 0.0 && num > 0.0) p.k[static_cast<std::size_t>(m)] = num / den;
    }
    // (2) shear gains (non-negative), all recordings with their proxy.
    {
      Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
      Eigen::Vector3d b = Eigen::Vector3d::Zero();
      for (std::size_t r = 0; r < n; ++r) {
        const int m = p.mode[r];
        std::array<Eigen::Vector3d, 3> u;
        for (int c = 0; c < kComponents; ++c) {
          u[static_cast<std::size_t>(c)] =
              p.k[static_cast<std::size_t>(m)] *
              p.a[static_cast<std::size_t>(m)].cwiseProduct(
                  data[r].I[static_cast<std::size_t>(m)][static_cast<std::size_t>(c)]);
        }
        for (int i = 0; i < 3; ++i) {
          b(i) += data[r].w * u[static_cast<std::size_t>(i)].dot(data[r].theta);
          for (int j = 0; j < 3; ++j)
            M(i, j) +=
                data[r].w * u[static_cast<std::size_t>(i)].dot(u[static_cast<std::size_t>(j)]);
        }
      }
      const double ridge = kShearRidge * M.trace() / 3.0;
      for (int i = 0; i < 3; ++i) {
        M(i, i) += ridge;
        b(i) += ridge * start.s[static_cast<std::size_t>(i)];
      }
      std::array<double, 3> s = nnls3(M, b, p.s);
      const double mx = std::max({s[0], s[1], s[2]});
      if (mx > 0.0) {
        for (auto& v : s) v /= mx;
        for (auto& k : p.k) k *= mx;
        p.s = s;
      }
    }
    // (3) per-axis rotation scales per proxy, on the axes its recordings excite; an axis no
    // recording of a proxy excites takes the other proxy's scale (ratio 1).
    for (int m = 0; m < kModes; ++m) {
      const auto mi = static_cast<std::size_t>(m);
      std::array<bool, 3> own{false, false, false};
      res.clamped[mi] = {false, false, false};
      for (int ax = 0; ax < 3; ++ax) {
        if (!excited[static_cast<std::size_t>(ax)]) continue;
        double num = 0.0, den = 0.0, excite = 0.0;
        for (std::size_t r = 0; r < n; ++r) {
          if (p.mode[r] != m) continue;
          const double e = p.k[mi] * combine(data[r], p.s, m)(ax);
          num += data[r].w * e * data[r].theta(ax);
          den += data[r].w * e * e;
          excite = std::max(excite, std::abs(data[r].theta(ax)));
        }
        if (excite >= kExciteFloorRad && den > 0.0 && num > 0.0) {
          const double raw = num / den;
          res.raw_a[mi](ax) = raw;
          res.clamped[mi][static_cast<std::size_t>(ax)] =
              raw < kJointScaleMin || raw > kJointScaleMax;
          p.a[mi](ax) = std::clamp(raw, kJointScaleMin, kJointScaleMax);
          own[static_cast<std::size_t>(ax)] = true;
        }
      }
      // Scale freedom between a[m] and k[m]: geometric mean of its fitted axes' scales = 1.
      double lg = 0.0;
      int cnt = 0;
      for (int ax = 0; ax < 3; ++ax) {
        if (own[static_cast<std::size_t>(ax)]) {
          lg += std::log(p.a[mi](ax));
          ++cnt;
        }
      }
      if (cnt > 0) {
        const double g = std::exp(lg / cnt);
        for (int ax = 0; ax < 3; ++ax) {
          if (own[static_cast<std::size_t>(ax)]) p.a[mi](ax) /= g;
        }
        p.k[mi] *= g;
      }
      for (int ax = 0; ax < 3; ++ax) {
        if (!own[static_cast<std::size_t>(ax)]) p.a[mi](ax) = p.a[1 - mi](ax);
      }
      res.own_axis[mi] = own;
    }
    // (4) reassign every recording to the proxy that explains it best.
    bool changed = false;
    for (std::size_t r = 0; r < n && it < kFreezeAssignmentAfter; ++r) {
      if (data[r].preferred >= 0) continue;
      const int other = 1 - p.mode[r];
      if (cost(data[r], p, other) < cost(data[r], p, p.mode[r])) {
        p.mode[r] = other;
        changed = true;
      }
    }
    double delta = std::max((p.a[0] - before.a[0]).cwiseAbs().maxCoeff(),
                            (p.a[1] - before.a[1]).cwiseAbs().maxCoeff());
    for (int m = 0; m < kModes; ++m)
      delta = std::max(delta, std::abs(std::log(p.k[static_cast<std::size_t>(m)] /
                                                before.k[static_cast<std::size_t>(m)])));
    for (int c = 0; c < kComponents; ++c)
      delta = std::max(delta, std::abs(p.s[static_cast<std::size_t>(c)] -
                                       before.s[static_cast<std::size_t>(c)]));
    res.last_change = delta;
    if (!changed && delta < kFitConverged) {
      res.converged = true;
      break;
    }
  }
  res.p = p;
  res.excited = excited;
  return res;
}

std::string sim_regime(const std::string& json) {
  const auto at = json.find("\"regime\"");
  if (at == std::string::npos) return {};
  const auto q1 = json.find('"', json.find(':', at) + 1);
  if (q1 == std::string::npos) return {};
  const auto q2 = json.find('"', q1 + 1);
  if (q2 == std::string::npos) return {};
  return json.substr(q1 + 1, q2 - q1 - 1);
}

double geodesic_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return rotation_error_deg(dsp::so3_exp(a), dsp::so3_exp(b));
}

std::string now_utc() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

double round_sig(double v, int digits) {
  if (v == 0.0 || !std::isfinite(v)) return v;
  const double e =
      std::pow(10.0, digits - 1 - static_cast<int>(std::floor(std::log10(std::abs(v)))));
  return std::round(v * e) / e;
}

// A recording that drove a fitted value, with the value it alone would give.
struct Driver {
  std::string name;
  double value;
};

// A fitted value stopped at a bound: an error naming the field, the value the data asked for and
// the recordings that pushed it there (most extreme first, at most five).
std::string bound_problem(const std::string& field, double wanted, double lo, double hi,
                          std::vector<Driver> drivers) {
  const bool high = wanted > hi;
  std::sort(drivers.begin(), drivers.end(), [&](const Driver& a, const Driver& b) {
    return high ? a.value > b.value : a.value < b.value;
  });
  char b[256];
  std::snprintf(b, sizeof b, "%s: the fit asks for %.4g, outside its bound %.4g .. %.4g",
                field.c_str(), wanted, lo, hi);
  std::string o = b;
  if (!drivers.empty()) o += "; driven by";
  for (std::size_t k = 0; k < drivers.size() && k < 5; ++k) {
    std::snprintf(b, sizeof b, "%s %s (alone %.3g)", k ? "," : "", drivers[k].name.c_str(),
                  drivers[k].value);
    o += b;
  }
  if (drivers.size() > 5) o += ", ...";
  o += std::string(". The pipeline reads these recordings' motion ") +
       (high ? "far smaller" : "far larger") +
       " than their truth: check that the check table shows valid frames for them and that "
       "their truth.csv is in G and in metres; drop or re-record them";
  return o;
}

// The first frame at or after the truth's motion start.
std::size_t motion_frame(const SourceInfo& in) {
  const std::int64_t start_ns = motion_start_ns(in.truth);
  std::size_t i = 0;
  while (i < in.frame_count() && in.t_ns[i] < start_ns) ++i;
  return i;
}

// Stage 1, the area: at tau_on the noise still makes small components now and then (f^z is
// smoothed, so its excursions span several grid points, and its tails are heavier than a
// Gaussian's). contact_min_area_cells is set one above the largest component in any recording's
// frames before the grasp (never below the starting value), so none of them would start a
// contact. A pad whose contact at the motion start is no larger cannot be told from its noise:
// that is a problem, named per recording.
void fit_contact_area(const std::vector<FrameSource*>& sources, const std::vector<PreMotionFz>& pre,
                      int start_area, CalibrateReport* rep) {
  int largest = 0;
  std::size_t quiet = 0;
  std::vector<NoiseComponents> nc(sources.size());
  for (std::size_t r = 0; r < sources.size(); ++r) {
    nc[r] = noise_components(pre[r], rep->contact_tau_on);
    largest = std::max(largest, nc[r].largest);
    quiet += nc[r].quiet_frames;
  }
  rep->noise_largest_component = largest;
  rep->noise_component_frames = quiet;
  rep->contact_min_area_cells = std::max(start_area, largest + 1);
  for (std::size_t r = 0; r < sources.size(); ++r) {
    for (std::size_t p = 0; p < 2; ++p) {
      const int cells = nc[r].contact_cells[p];
      if (cells == 0 || cells >= rep->contact_min_area_cells) continue;
      char b[320];
      std::snprintf(b, sizeof b,
                    "%s: the %s pad's contact at the motion start covers %d grid point(s), fewer "
                    "than contact_min_area_cells %d (the noise before contact made components of "
                    "%d): grasp harder or with a larger object, or check the pad's lighting",
                    sources[r]->info().name.c_str(), p == 0 ? "left" : "right", cells,
                    rep->contact_min_area_cells, largest);
      rep->problems.push_back(b);
    }
  }
}

// Stage 1: one run with the starting calibration feeds every recording's filter(f^z) to a
// PreContactNoise. A recording gives a noise estimate when its contact onset comes before the
// truth starts to move (the grasp closes on a still object); one whose first frames are already
// in contact shows no onset before the motion (its reference frame holds the contact). The σ is
// the median over the recordings that give one; contact_tau_on = kOnsetSigma·σ (the onset's
// bar: about 1e-9 for one cell of Gaussian noise, and contact_min_area_cells drops single cells),
// contact_tau_off = half of it.
std::string fit_contact_threshold(const std::vector<FrameSource*>& sources,
                                  const CalibrateOptions& opt, const config::CalibrationSet& base,
                                  CalibrateReport* rep) {
  const std::size_t n = sources.size();
  std::vector<PreContactNoise> noise(n);
  std::vector<PreMotionFz> pre(n);
  std::vector<std::size_t> motion_frames(n);
  for (std::size_t r = 0; r < n; ++r) motion_frames[r] = motion_frame(sources[r]->info());
  std::string err =
      run_stage(sources, opt.jobs, opt.progress, "calibrate 1/4", [&](std::size_t r, auto* done) {
        std::vector<ReplayOptions> cfg(1);
        cfg[0].calibration = base;
        std::vector<RunOutput> out;
        return run_pass(*sources[r], cfg, done, &noise[r], &out, false, &pre[r], motion_frames[r]);
      });
  if (!err.empty()) return err;
  std::vector<double> sigmas;
  std::string mid_contact;
  for (std::size_t r = 0; r < n; ++r) {
    const SourceInfo& in = sources[r]->info();
    RecordingFit& f = rep->recordings[r];
    const std::size_t motion_frame = motion_frames[r];
    const PreContactNoise& z = noise[r];
    f.quiet_frames = z.quiet_frames();
    if (z.onset_found()) f.contact_onset_frame = static_cast<std::int64_t>(z.onset_frame());
    if (z.onset_found() && z.onset_frame() < motion_frame) {
      f.noise_sigma = z.sigma();
      sigmas.push_back(z.sigma());
    } else {
      char b[256];
      std::snprintf(b, sizeof b,
                    "%s: no contact forms before the motion starts (frame %zu): the recording "
                    "starts mid-contact (or the pads never touch); record frames with the pads "
                    "open first",
                    in.name.c_str(), motion_frame);
      mid_contact += std::string(mid_contact.empty() ? "" : "\n") + b;
    }
  }
  if (sigmas.empty()) {
    return "no recording gives the f^z noise before contact, so contact_tau_on cannot be set:\n" +
           mid_contact;
  }
  if (!mid_contact.empty()) {
    rep->notes.push_back("left out of the noise estimate (the others give it):\n" + mid_contact);
  }
  std::nth_element(sigmas.begin(), sigmas.begin() + static_cast<std::ptrdiff_t>(sigmas.size() / 2),
                   sigmas.end());
  const double sigma = sigmas[sigmas.size() / 2];
  rep->fz_noise_sigma = sigma;
  if (!(sigma > 0.0)) {
    return "the f^z before contact has no noise at all (sigma 0), so contact_tau_on cannot be "
           "set from it: are the frames before contact identical copies?";
  }
  rep->contact_tau_on = round_sig(PreContactNoise::kOnsetSigma * sigma, 3);
  rep->contact_tau_off = round_sig(0.5 * PreContactNoise::kOnsetSigma * sigma, 3);
  fit_contact_area(sources, pre, base.sensor[0].contact_min_area_cells, rep);
  return {};
}

}  // namespace

std::string check_calibration_recording(const SourceInfo& info) {
  if (!info.has_truth()) {
    return info.name + ": has no truth.csv; calibration needs recordings with truth";
  }
  if (info.frame_count() < kMinCalibrationFrames) {
    return info.name + ": " + std::to_string(info.frame_count()) +
           " frame(s); calibration needs at least " + std::to_string(kMinCalibrationFrames) +
           " per recording (a grasp, a motion and a rest)";
  }
  return {};
}

namespace {

// One fit with the working-image filter that opt.start names.
std::string calibrate_with_filter(const std::vector<FrameSource*>& sources,
                                  const CalibrateOptions& opt, CalibrateReport* report) {
  if (sources.empty()) return "no recordings given";
  for (auto* s : sources) {
    if (std::string e = check_calibration_recording(s->info()); !e.empty()) return e;
  }
  auto log = [&](const std::string& m) {
    if (opt.log) opt.log(m);
  };
  CalibrateReport rep;
  const std::size_t n = sources.size();
  rep.recordings.resize(n);
  std::vector<FitData> data(n);
  std::vector<Eigen::Vector3d> truth_p(n);
  for (std::size_t r = 0; r < n; ++r) {
    const SourceInfo& in = sources[r]->info();
    const dsp::Pose tp = truth_pose_at(in.truth, in.t_ns.back());
    data[r].theta = dsp::so3_log(tp.q);
    data[r].w = 1.0 / std::pow(std::max(data[r].theta.norm(), kWeightFloorRad), 2.0);
    truth_p[r] = tp.p;
    rep.recordings[r].name = in.name;
    rep.recordings[r].truth_rotation_deg = data[r].theta * kDeg;
    rep.recordings[r].truth_translation_mm = tp.p.norm() * 1e3;
    rep.recordings[r].sim_regime = sim_regime(in.extra_json);
  }
  // The file's pixel pitch is the calibration rig's (the replay rescales the proxy gains for a
  // rig with another pitch).
  const double rig_pitch_m = sources[0]->info().pixel_pitch_mm * 1e-3;
  for (auto* s : sources) {
    if (std::abs(s->info().pixel_pitch_mm * 1e-3 - rig_pitch_m) > 1e-12) {
      rep.notes.push_back("recordings have different pixel pitches; the file uses " +
                          sources[0]->info().name + "'s");
      break;
    }
  }
  config::CalibrationSet base = opt.start;
  for (auto& c : base.sensor) {
    const double ratio = rig_pitch_m / c.pixel_pitch_m;
    c.pixel_pitch_m = rig_pitch_m;
    c.c_velocity *= ratio;
    c.c_displacement *= ratio;
  }

  // ---- stage 1: the contact threshold from the f^z noise before contact ------------------
  log("stage 1/4: contact threshold from the f^z noise before contact");
  if (std::string e = fit_contact_threshold(sources, opt, base, &rep); !e.empty()) return e;
  for (auto& c : base.sensor) {
    c.contact_tau_on = rep.contact_tau_on;
    c.contact_tau_off = rep.contact_tau_off;
    c.contact_min_area_cells = rep.contact_min_area_cells;
  }

  // ---- stage 1: one run per proxy and shear component -------------------------------------
  log("stage 2/4: the starting gains and one run per proxy and shear component (d, r, k)");
  std::vector<std::vector<RunOutput>> out1(n), out0(n);
  std::string err =
      run_stage(sources, opt.jobs, opt.progress, "calibrate 2/4", [&](std::size_t r, auto* done) {
        // The starting gains with the fitted threshold, in both proxies (which proxy explains the
        // recording, and the report's "before"), then the six component runs.
        std::vector<ReplayOptions> cfg(kModes);
        for (int m = 0; m < kModes; ++m) {
          cfg[static_cast<std::size_t>(m)].calibration = base;
          cfg[static_cast<std::size_t>(m)].mode = mode_of(m);
        }
        for (int m = 0; m < kModes; ++m) {
          for (int c = 0; c < kComponents; ++c) {
            ReplayOptions o;
            o.calibration = base;
            o.mode = mode_of(m);
            for (auto& s : o.calibration.sensor) {
              s.shear_gain_d = c == 0 ? 1.0 : 0.0;
              s.shear_gain_r = c == 1 ? 1.0 : 0.0;
              s.shear_gain_k = c == 2 ? 1.0 : 0.0;
              s.rotation_scale = {1.0, 1.0, 1.0};
              s.displacement_rotation_ratio = {1.0, 1.0, 1.0};
            }
            cfg.push_back(o);
          }
        }
        std::vector<RunOutput> all;
        if (std::string e = run_pass(*sources[r], cfg, done, nullptr, &all, true); !e.empty())
          return e;
        out0[r].assign(all.begin(), all.begin() + kModes);
        out1[r].assign(all.begin() + kModes, all.end());
        for (auto& o : out1[r]) o.omega.clear();
        return std::string{};
      });
  if (!err.empty()) return err;
  for (std::size_t r = 0; r < n; ++r) {
    for (int m = 0; m < kModes; ++m) {
      for (int c = 0; c < kComponents; ++c) {
        data[r].I[static_cast<std::size_t>(m)][static_cast<std::size_t>(c)] =
            out1[r][static_cast<std::size_t>(m * kComponents + c)].rot_integral;
      }
    }
  }
  // Which proxy explains each recording (label-free): a rotating recording by how much of the
  // velocity-proxy rate persists at rest; a recording without rotation by the smaller combined
  // rotation-drift and translation error of the two proxies at the starting gains.
  for (std::size_t r = 0; r < n; ++r) {
    const SourceInfo& in = sources[r]->info();
    if (data[r].theta.norm() >= kWeightFloorRad) {
      std::vector<Eigen::Quaterniond> tq;
      for (const std::int64_t t : in.t_ns) tq.push_back(truth_pose_at(in.truth, t).q);
      const double persist = rest_persistence(out0[r][0].omega, tq);
      rep.recordings[r].rest_persistence = persist;
      if (persist >= 0.0) data[r].preferred = persist < kRestPersistenceMax ? 0 : 1;
    }
    if (data[r].preferred < 0) {
      double best = std::numeric_limits<double>::infinity();
      for (int m = 0; m < kModes; ++m) {
        const dsp::Pose& e = out0[r][static_cast<std::size_t>(m)].final_pose;
        const double rot = rotation_error_deg(e.q, dsp::so3_exp(data[r].theta)) / kDeg /
                           std::max(data[r].theta.norm(), kWeightFloorRad);
        const double tr = (e.p - truth_p[r]).norm() / std::max(truth_p[r].norm(), 1e-3);
        const double c = rot * rot + tr * tr;
        if (c < best) {
          best = c;
          data[r].preferred = m;
        }
      }
    }
    out0[r][0].omega.clear();
    out0[r][1].omega.clear();
  }
  FitParams start;
  {
    const dsp::Calibration& c0 = base.sensor[0];
    start.s = {c0.shear_gain_d, c0.shear_gain_r, c0.shear_gain_k};
    const double mx = std::max({start.s[0], start.s[1], start.s[2]});
    if (mx > 0.0) {
      for (auto& v : start.s) v /= mx;
    } else {
      start.s = {0.0, 1.0, 1.0};
    }
  }
  const FitResult fit = fit_model(data, start);
  rep.iterations = fit.iterations;
  if (!fit.converged) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "the gain fit stopped at its %d-iteration cap; the last iteration still moved a "
                  "gain by %.2g",
                  kMaxFitIterations, fit.last_change);
    rep.notes.push_back(text);
  }
  rep.shear_gains = fit.p.s;
  config::CalibrationSet fitted = base;
  for (int m = 0; m < kModes; ++m) {
    rep.recordings_per_mode[static_cast<std::size_t>(m)] =
        static_cast<int>(std::count(fit.p.mode.begin(), fit.p.mode.end(), m));
  }
  // Recordings of proxy m, each with the gain factor it alone would give.
  auto mode_drivers = [&](int m) {
    std::vector<Driver> d;
    for (std::size_t r = 0; r < n; ++r) {
      if (fit.p.mode[r] != m) continue;
      const Eigen::Vector3d e =
          fit.p.a[static_cast<std::size_t>(m)].cwiseProduct(combine(data[r], fit.p.s, m));
      if (e.squaredNorm() > 0.0)
        d.push_back({sources[r]->info().name, e.dot(data[r].theta) / e.squaredNorm()});
    }
    return d;
  };
  std::array<double, kModes> gain{base.sensor[0].c_velocity, base.sensor[0].c_displacement};
  for (int m = 0; m < kModes; ++m) {
    const auto mi = static_cast<std::size_t>(m);
    const char* key = m == 0 ? "c_velocity" : "c_displacement";
    if (rep.recordings_per_mode[mi] == 0) {
      rep.notes.push_back(std::string("no recording is explained by the ") + to_string(mode_of(m)) +
                          " proxy: " + key + " is kept at the start value");
      continue;
    }
    // The proxy gain may move by kGainRange either way from the start: further only fits noise.
    constexpr double kGainRange = 50.0;
    const double k = fit.p.k[mi];
    const dsp::CalibrationField* f = dsp::find_calibration_field(key);
    const double schema_hi = f != nullptr ? f->hi : HUGE_VAL;
    const double lo = gain[mi] / kGainRange, hi = std::min(gain[mi] * kGainRange, schema_hi);
    const double wanted = gain[mi] * k;
    if (!(wanted >= lo && wanted <= hi)) {
      std::vector<Driver> d = mode_drivers(m);
      for (auto& x : d) x.value *= gain[mi];
      rep.problems.push_back(bound_problem(key, wanted, lo, hi, d));
    }
    gain[mi] = round_sig(std::clamp(wanted, lo, hi), 4);
  }
  for (int m = 0; m < kModes; ++m) {
    for (int ax = 0; ax < 3; ++ax) {
      if (!fit.clamped[static_cast<std::size_t>(m)][static_cast<std::size_t>(ax)]) continue;
      std::vector<Driver> d;
      for (std::size_t r = 0; r < n; ++r) {
        const double e = fit.p.k[static_cast<std::size_t>(m)] * combine(data[r], fit.p.s, m)(ax);
        if (fit.p.mode[r] == m && std::abs(data[r].theta(ax)) >= kExciteFloorRad && e != 0.0)
          d.push_back({sources[r]->info().name, data[r].theta(ax) / e});
      }
      rep.problems.push_back(bound_problem(
          std::string(m == 0 ? "rotation_scale " : "displacement proxy scale ") + "xyz"[ax],
          fit.raw_a[static_cast<std::size_t>(m)](ax), kJointScaleMin, kJointScaleMax, d));
    }
  }
  for (auto& c : fitted.sensor) {
    c.shear_gain_d = round_sig(fit.p.s[0], 4);
    c.shear_gain_r = round_sig(fit.p.s[1], 4);
    c.shear_gain_k = round_sig(fit.p.s[2], 4);
    c.c_velocity = gain[0];
    c.c_displacement = gain[1];
    for (int ax = 0; ax < 3; ++ax)
      c.rotation_scale[static_cast<std::size_t>(ax)] = round_sig(fit.p.a[0](ax), 4);
    for (int ax = 0; ax < 3; ++ax)
      c.displacement_rotation_ratio[static_cast<std::size_t>(ax)] =
          round_sig(fit.p.a[1](ax) / fit.p.a[0](ax), 4);
  }
  for (int m = 0; m < kModes; ++m) {
    if (rep.recordings_per_mode[static_cast<std::size_t>(m)] == 0) continue;
    for (int ax = 0; ax < 3; ++ax) {
      const auto a = static_cast<std::size_t>(ax);
      if (!fit.excited[a] || fit.own_axis[static_cast<std::size_t>(m)][a]) continue;
      char floor[16];
      std::snprintf(floor, sizeof(floor), "%.0f", kExciteFloorRad * kDeg);
      rep.notes.push_back(std::string("the ") + to_string(mode_of(m)) + " proxy's " + "xyz"[ax] +
                          " scale is the other proxy's: none of its recordings rotates about " +
                          "xyz"[ax] + " by " + floor +
                          " deg or more, or their readings there do not fit one");
    }
  }
  for (std::size_t r = 0; r < n; ++r) {
    rep.recordings[r].explained_by = mode_of(fit.p.mode[r]);
    rep.recordings[r].before_deg = rotation_error_deg(
        out0[r][static_cast<std::size_t>(fit.p.mode[r])].final_pose.q, dsp::so3_exp(data[r].theta));
  }
  // ---- stick/slip detector thresholds (label-free) -------------------------------------------
  // kAuto runs with the fitted gains over every recording, once per candidate onset threshold
  // (ρ_on, frames); the candidate with the smallest summed final-pose error (the same relative
  // rotation and translation cost that chose each recording's proxy above) wins. Only truth
  // poses are used, never a regime label.
  log("stage 2b/4: stick/slip detector thresholds (kAuto, one run per candidate)");
  // The minimum shift is a candidate too: the grasp itself leaves a small planar shear content
  // (the bulge is not exactly curl- and translation-free once d enters the shear), and a
  // torsion that starts from it reads as that content relaxing. That content can exceed the
  // default minimum shift at the start of a small stick torsion and pass as a slip onset, whose
  // payback then costs far more than the motion.
  struct DetectorCandidate {
    double relax_rate_on;
    int on_frames;
    double min_shift_m;
  };
  static constexpr std::array<double, 4> kRates{1.5, 2.5, 4.0, 6.0};
  static constexpr std::array<int, 2> kFrames{3, 6};
  static constexpr std::array<double, 3> kShifts{20e-6, 40e-6, 80e-6};
  constexpr std::size_t kCandidateCount = kRates.size() * kFrames.size() * kShifts.size();
  static constexpr auto kCandidates = [] {
    std::array<DetectorCandidate, kCandidateCount> c{};
    std::size_t k = 0;
    for (const double shift : kShifts) {
      for (const double rate : kRates) {
        for (const int frames : kFrames) c[k++] = DetectorCandidate{rate, frames, shift};
      }
    }
    return c;
  }();
  std::vector<std::vector<RunOutput>> outd(n);
  err =
      run_stage(sources, opt.jobs, opt.progress, "calibrate 2b/4", [&](std::size_t r, auto* done) {
        std::vector<ReplayOptions> cfg;
        for (const auto& cand : kCandidates) {
          ReplayOptions o;
          o.calibration = fitted;
          for (auto& c : o.calibration.sensor) {
            c.slip_relax_rate_on = cand.relax_rate_on;
            c.slip_on_frames = cand.on_frames;
            c.slip_min_shift_m = cand.min_shift_m;
          }
          o.method = dsp::FusionMethod::kJoint;
          o.mode = ProxyMode::kAuto;
          for (auto& p : o.calibration.paper) p = config::PaperScales{};
          cfg.push_back(o);
        }
        return run_pass(*sources[r], cfg, done, nullptr, &outd[r]);
      });
  if (!err.empty()) return err;
  {
    std::array<double, kCandidateCount> cost{};
    for (std::size_t k = 0; k < kCandidateCount; ++k) {
      for (std::size_t r = 0; r < n; ++r) {
        const dsp::Pose& e = outd[r][k].final_pose;
        const double rot = rotation_error_deg(e.q, dsp::so3_exp(data[r].theta)) / kDeg /
                           std::max(data[r].theta.norm(), kWeightFloorRad);
        const double tr = (e.p - truth_p[r]).norm() / std::max(truth_p[r].norm(), 1e-3);
        cost[k] += rot * rot + tr * tr;
      }
    }
    // Costs within kDetectorCostTie of the smallest are a tie: candidates often agree to the
    // third digit, and the last digits would pick between them by accident. A tie goes to the
    // first candidate in the list, the most sensitive detector (smallest shift, lowest rate,
    // fewest frames).
    const double lowest = *std::min_element(cost.begin(), cost.end());
    std::size_t best = 0;
    while (cost[best] > lowest * (1.0 + kDetectorCostTie)) ++best;
    for (auto& c : fitted.sensor) {
      c.slip_relax_rate_on = kCandidates[best].relax_rate_on;
      c.slip_on_frames = kCandidates[best].on_frames;
      c.slip_min_shift_m = kCandidates[best].min_shift_m;
    }
    char line[160];
    std::string text =
        "slip detector (kAuto) onset thresholds: cost per candidate (rho_on/s, frames, min "
        "shift um):";
    for (std::size_t k = 0; k < kCandidateCount; ++k) {
      std::snprintf(line, sizeof(line), " %.1f/%d/%.0f=%.3f", kCandidates[k].relax_rate_on,
                    kCandidates[k].on_frames, kCandidates[k].min_shift_m * 1e6, cost[k]);
      text += line;
    }
    std::snprintf(line, sizeof(line),
                  " -> slip_relax_rate_on %.1f, slip_on_frames %d, slip_min_shift_m %.0f um",
                  kCandidates[best].relax_rate_on, kCandidates[best].on_frames,
                  kCandidates[best].min_shift_m * 1e6);
    rep.notes.push_back(text + line);
    rep.detector_cost.assign(cost.begin(), cost.end());
  }

  // ---- stage 2: validation runs; paper-fusion and translation scales -----------------------
  log("stage 3/4: validation runs (joint, paper) with the fitted gains");
  std::vector<std::vector<RunOutput>> out2(n);
  err = run_stage(sources, opt.jobs, opt.progress, "calibrate 3/4", [&](std::size_t r, auto* done) {
    std::vector<ReplayOptions> cfg;
    for (auto method : {dsp::FusionMethod::kJoint, dsp::FusionMethod::kPaper}) {
      for (int m = 0; m < kModes; ++m) {
        ReplayOptions o;
        o.calibration = fitted;
        o.method = method;
        o.mode = mode_of(m);
        for (auto& p : o.calibration.paper) p = config::PaperScales{};
        cfg.push_back(o);
      }
    }
    return run_pass(*sources[r], cfg, done, nullptr, &out2[r]);
  });
  if (!err.empty()) return err;
  auto run_of = [&](std::size_t r, bool paper) -> const RunOutput& {
    return out2[r][static_cast<std::size_t>((paper ? 2 : 0) + fit.p.mode[r])];
  };
  // Paper fusion: per-axis rotation scales (ω_x, ω_y are lever-scaled there).
  Eigen::Vector3d ap = Eigen::Vector3d::Ones();
  for (int ax = 0; ax < 3; ++ax) {
    double num = 0.0, den = 0.0, excite = 0.0;
    for (std::size_t r = 0; r < n; ++r) {
      const double e = run_of(r, true).rot_integral(ax);
      num += data[r].w * e * data[r].theta(ax);
      den += data[r].w * e * e;
      excite = std::max(excite, std::abs(data[r].theta(ax)));
    }
    if (excite >= kExciteFloorRad && den > 0.0) {
      // The schema's upper bound; the lower one keeps the scale a scale (a sign flip or a
      // thousandfold shrink only fits noise).
      constexpr double kLo = 1e-3, kHi = 100.0;
      const double wanted = num / den;
      if (!(wanted >= kLo && wanted <= kHi)) {
        std::vector<Driver> d;
        for (std::size_t r = 0; r < n; ++r) {
          const double e = run_of(r, true).rot_integral(ax);
          if (std::abs(data[r].theta(ax)) >= kExciteFloorRad && e != 0.0)
            d.push_back({sources[r]->info().name, data[r].theta(ax) / e});
        }
        rep.problems.push_back(
            bound_problem(std::string("paper rotation_scale ") + "xyz"[ax], wanted, kLo, kHi, d));
      }
      ap(ax) = round_sig(std::clamp(wanted, kLo, kHi), 4);
    } else {
      rep.notes.push_back(std::string("paper fusion: no rotation about ") + "xyz"[ax] +
                          " in the recordings; its scale stays 1");
    }
  }
  // The proxy whose translation is closer to the truth (the two proxies measure translation
  // differently: contact centroid vs common material points). The translation scales are fitted
  // on it and the report's translation error is read from it.
  auto translation_run = [&](std::size_t r, bool paper) -> const RunOutput& {
    const std::size_t base_idx = paper ? 2 : 0;
    const RunOutput& ra = out2[r][base_idx];
    const RunOutput& rb = out2[r][base_idx + 1];
    const bool use_b =
        (rb.final_pose.p - truth_p[r]).norm() < (ra.final_pose.p - truth_p[r]).norm();
    return use_b ? rb : ra;
  };
  // Translation scales (x, y; t_z = 0) from recordings that translate.
  auto fit_translation = [&](bool paper, const char* what) {
    std::array<double, 3> st{1.0, 1.0, 1.0};
    for (int ax = 0; ax < 2; ++ax) {
      double num = 0.0, den = 0.0;
      for (std::size_t r = 0; r < n; ++r) {
        if (std::abs(truth_p[r](ax)) < 1e-3) continue;
        const double e = translation_run(r, paper).final_pose.p(ax);
        num += e * truth_p[r](ax);
        den += e * e;
      }
      if (den > 0.0) {
        // A translation scale far from 1 only fits noise: the pipeline reads translation in
        // metres from the pixel pitch.
        constexpr double kLo = 0.2, kHi = 5.0;
        const double v = num / den;
        st[static_cast<std::size_t>(ax)] = round_sig(std::clamp(v, kLo, kHi), 4);
        if (!(v >= kLo && v <= kHi)) {
          std::vector<Driver> d;
          for (std::size_t r = 0; r < n; ++r) {
            const double e = translation_run(r, paper).final_pose.p(ax);
            if (std::abs(truth_p[r](ax)) >= 1e-3 && e != 0.0)
              d.push_back({sources[r]->info().name, truth_p[r](ax) / e});
          }
          rep.problems.push_back(bound_problem(std::string(what) + " " + "xy"[ax], v, kLo, kHi, d));
        }
      } else {
        rep.notes.push_back(std::string(what) + ": no translation along " + "xy"[ax] +
                            " in the recordings; its translation scale stays 1");
      }
    }
    return st;
  };
  const auto st_joint = fit_translation(false, "translation_scale");
  const auto st_paper = fit_translation(true, "paper translation_scale");
  for (std::size_t k = 0; k < 2; ++k) {
    fitted.sensor[k].translation_scale = st_joint;
    fitted.paper[k].rotation_scale = {ap(0), ap(1), ap(2)};
    fitted.paper[k].translation_scale = st_paper;
  }
  for (std::size_t r = 0; r < n; ++r) {
    RecordingFit& f = rep.recordings[r];
    const dsp::Pose tp{dsp::so3_exp(data[r].theta), truth_p[r]};
    f.after_deg = rotation_error_deg(run_of(r, false).final_pose.q, tp.q);
    f.after_other_deg =
        rotation_error_deg(out2[r][static_cast<std::size_t>(1 - fit.p.mode[r])].final_pose.q, tp.q);
    f.after_paper_deg = geodesic_deg(ap.cwiseProduct(run_of(r, true).rot_integral), data[r].theta);
    const Eigen::Vector3d pe = translation_run(r, false).final_pose.p.cwiseProduct(
        Eigen::Vector3d(st_joint[0], st_joint[1], st_joint[2]));
    f.translation_after_mm = (pe - truth_p[r]).norm() * 1e3;
  }

  fitted.meta.generator = "tacse3-calibrate";
  fitted.meta.created = now_utc();
  fitted.meta.recordings.clear();
  for (auto* s : sources) fitted.meta.recordings.push_back(s->info().name);
  fitted.meta.note = "fitted from " + std::to_string(n) + " recording(s); see docs/calibration.md";
  if (config::Status s = config::validate(fitted, "fitted calibration"); !s) {
    return "internal error: " + s.message();
  }
  rep.calibration = fitted;
  // Coverage: the axes from the truth, the regime from the proxy that explains the recording.
  rep.motions.resize(n);
  for (std::size_t r = 0; r < n; ++r) {
    rep.motions[r] = motion_from_truth(sources[r]->info());
    rep.motions[r].set(fit.p.mode[r] == 0 ? Motion::kSlide : Motion::kStick);
    if (rep.recordings[r].noise_sigma >= 0.0) rep.motions[r].set(Motion::kPadsOpen);
  }
  if (std::string m = coverage_message(missing_motions(rep.motions, true, opt.pitch_given));
      !m.empty()) {
    rep.problems.push_back(m);
  }
  log("stage 4/4: self-check: the fitted calibration replayed as tacse3-replay would");
  if (std::string e = check_calibration(sources, fitted, opt.jobs, opt.progress, &rep.check);
      !e.empty()) {
    return e;
  }
  for (const auto& c : rep.check.recordings) {
    if (!c.passed()) rep.problems.push_back("not explained: " + c.name + ": " + c.reason());
  }
  *report = std::move(rep);
  return {};
}

}  // namespace

// The 2x2 box first: it keeps the sharpest image. A pattern finer than the working grid
// resolves folds into it as a moire that the flow tracks (dsp/luma.hpp); such a sensor's fit
// fails its own check, so a failing fit is repeated with the binomial low-pass, and the binomial
// is kept when its fit has fewer problems.
std::string calibrate(const std::vector<FrameSource*>& sources, const CalibrateOptions& opt,
                      CalibrateReport* report) {
  const bool start_binomial = opt.start.sensor[0].antialias_filter != 0;
  if (std::string e = calibrate_with_filter(sources, opt, report); !e.empty()) return e;
  if (report->problems.empty() || start_binomial) return {};
  if (opt.log) {
    opt.log("the fit with the 2x2 box working image has " +
            std::to_string(report->problems.size()) +
            " problem(s): fitting again with the 4x4 binomial (antialias_filter = 1)");
  }
  CalibrateOptions binomial = opt;
  for (auto& c : binomial.start.sensor) c.antialias_filter = 1;
  CalibrateReport alt;
  if (std::string e = calibrate_with_filter(sources, binomial, &alt); !e.empty()) return e;
  const std::size_t box_problems = report->problems.size();
  if (alt.problems.size() < box_problems) {
    *report = std::move(alt);
    report->notes.push_back("antialias_filter 1: the 2x2 box's fit had " +
                            std::to_string(box_problems) + " problem(s), the binomial's " +
                            std::to_string(report->problems.size()));
  } else {
    report->notes.push_back("antialias_filter 0: the binomial's fit had " +
                            std::to_string(alt.problems.size()) + " problem(s), no fewer");
  }
  return {};
}

std::string format_report(const CalibrateReport& rep) {
  std::string o;
  char line[512];
  const dsp::Calibration& c = rep.calibration.sensor[0];
  int noisy = 0;
  for (const auto& r : rep.recordings) noisy += r.noise_sigma >= 0.0 ? 1 : 0;
  std::snprintf(line, sizeof(line),
                "contact threshold: f^z noise sigma %.4g before contact (median of %d "
                "recording(s)) -> contact_tau_on %.4g, contact_tau_off %.4g\n",
                rep.fz_noise_sigma, noisy, c.contact_tau_on, c.contact_tau_off);
  o += line;
  std::snprintf(line, sizeof(line),
                "contact area: the noise's largest component over tau_on before contact %d grid "
                "point(s) (%zu quiet frame(s)) -> contact_min_area_cells %d\n",
                rep.noise_largest_component, rep.noise_component_frames, c.contact_min_area_cells);
  o += line;
  std::snprintf(line, sizeof(line),
                "shear gains (d, r, k) = (%.4g, %.4g, %.4g); c_velocity %.4g m/s per unit "
                "(%d recording(s)), c_displacement %.4g m per unit (%d recording(s)); %d "
                "iteration(s)\n",
                c.shear_gain_d, c.shear_gain_r, c.shear_gain_k, c.c_velocity,
                rep.recordings_per_mode[0], c.c_displacement, rep.recordings_per_mode[1],
                rep.iterations);
  o += line;
  o += c.antialias_filter != 0 ? "working image: 4x4 binomial (antialias_filter 1)\n"
                               : "working image: 2x2 box (antialias_filter 0)\n";
  const auto& p = rep.calibration.paper[0];
  std::snprintf(line, sizeof(line),
                "rotation scales: joint (%.4g, %.4g, %.4g), displacement proxy ratio "
                "(%.4g, %.4g, %.4g), "
                "paper (%.4g, %.4g, %.4g); "
                "translation scales: joint (%.4g, %.4g), paper (%.4g, %.4g)\n",
                c.rotation_scale[0], c.rotation_scale[1], c.rotation_scale[2],
                c.displacement_rotation_ratio[0], c.displacement_rotation_ratio[1],
                c.displacement_rotation_ratio[2], p.rotation_scale[0], p.rotation_scale[1],
                p.rotation_scale[2], c.translation_scale[0], c.translation_scale[1],
                p.translation_scale[0], p.translation_scale[1]);
  o += line;
  o += "fit quality (final rotation error, deg; joint fusion measured, paper predicted):\n";
  std::snprintf(line, sizeof(line), "  %-32s %7s %6s %8s %7s %-12s %7s %7s %7s %7s %8s\n",
                "recording", "truth", "sim", "f^z sd", "persist", "explained by", "before", "after",
                "other", "paper", "trans mm");
  o += line;
  for (const auto& r : rep.recordings) {
    std::string name = r.name;
    if (name.size() > 32) name = "..." + name.substr(name.size() - 29);
    char persist[16] = "-";
    if (r.rest_persistence >= 0.0)
      std::snprintf(persist, sizeof(persist), "%.2f", r.rest_persistence);
    char sd[16] = "-";
    if (r.noise_sigma >= 0.0) std::snprintf(sd, sizeof(sd), "%.5f", r.noise_sigma);
    std::snprintf(line, sizeof(line),
                  "  %-32s %7.2f %6s %8s %7s %-12s %7.2f %7.2f %7.2f %7.2f %8.2f\n", name.c_str(),
                  r.truth_rotation_deg.norm(), r.sim_regime.empty() ? "-" : r.sim_regime.c_str(),
                  sd, persist, to_string(r.explained_by), r.before_deg, r.after_deg,
                  r.after_other_deg, r.after_paper_deg, r.translation_after_mm);
    o += line;
  }
  for (const auto& n : rep.notes) o += "note: " + n + "\n";
  if (!rep.check.recordings.empty()) o += format_check(rep.check);
  return o;
}

}  // namespace tacse3::tools
