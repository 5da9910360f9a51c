// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: per-pad contact mechanics: ray-traced contact patch, bulge, stick/slide shear,
// spreading.
#include "tacse3/sim/pad.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "tacse3/sim/rng.hpp"

namespace tacse3::sim {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kContactEpsMm = 1e-6;
constexpr double kSorOmega = 1.8;
constexpr double kSorTolMm = 1e-4;
constexpr int kSorMaxSweeps = 200;

bool finite_in(double v, double lo, double hi) {
  return std::isfinite(v) && v >= lo && v <= hi;
}

}  // namespace

const char* to_string(BulgeModel m) noexcept {
  return m == BulgeModel::kRadialVolume ? "radial-volume" : "smoothed-gradient";
}
const char* to_string(SlideLaw m) noexcept {
  switch (m) {
    case SlideLaw::kTanh:
      return "tanh";
    case SlideLaw::kCoulombRim:
      return "coulomb-rim";
    case SlideLaw::kViscousCapped:
      break;
  }
  return "viscous-capped";
}
const char* to_string(SpreadKernel m) noexcept {
  return m == SpreadKernel::kHalfSpace ? "half-space" : "thin-layer";
}

std::string validate(const GelSpec& g) {
  if (g.bulge_model > BulgeModel::kRadialVolume) return "gel bulge_model is not a known model";
  if (g.slide_law > SlideLaw::kCoulombRim) return "gel slide_law is not a known law";
  if (g.spread_kernel > SpreadKernel::kHalfSpace) return "gel spread_kernel is not a known kernel";
  if (!finite_in(g.bulge_surface_factor, 0.0, 10.0))
    return "gel bulge_surface_factor must be in [0, 10]";
  if (!finite_in(g.gel_thickness_mm, 0.1, 50.0)) return "gel gel_thickness_mm must be in [0.1, 50]";
  if (!finite_in(g.friction_variation, 0.0, 0.9))
    return "gel friction_variation must be in [0, 0.9]";
  if (!finite_in(g.spread_length_mm, 0.1, 50.0)) return "gel spread_length_mm must be in [0.1, 50]";
  if (!finite_in(g.bulge_gain_mm, 0.0, 20.0)) return "gel bulge_gain_mm must be in [0, 20]";
  if (!finite_in(g.bulge_sigma_mm, 0.1, 20.0)) return "gel bulge_sigma_mm must be in [0.1, 20]";
  if (!finite_in(g.drag_time_s, 0.0, 10.0)) return "gel drag_time_s must be in [0, 10]";
  if (!finite_in(g.lag_time_s, 1e-4, 10.0)) return "gel lag_time_s must be in [1e-4, 10]";
  if (!finite_in(g.shear_compliance, 0.0, 100.0)) return "gel shear_compliance must be in [0, 100]";
  if (!finite_in(g.slip_speed_mm_s, 0.0, 1000.0)) return "gel slip_speed_mm_s must be in [0, 1000]";
  return {};
}

std::string validate(const ShadingSpec& s) {
  if (!std::isfinite(s.light_dir.x()) || !std::isfinite(s.light_dir.y()) ||
      s.light_dir.norm() < 1e-6) {
    return "shading light_dir must be a finite non-zero vector";
  }
  if (!finite_in(s.slope_gain, 0.0, 10.0)) return "shading slope_gain must be in [0, 10]";
  if (!finite_in(s.press_gain_per_mm, 0.0, 1.0))
    return "shading press_gain_per_mm must be in [0, 1]";
  return {};
}

void PadFields::allocate(const RigSpec& rig) {
  gw = rig.width / kCellPx;
  gh = rig.height / kCellPx;
  pitch_mm = rig.pixel_pitch_mm;
  cell_mm = kCellPx * rig.pixel_pitch_mm;
  const double half = 0.5 * (kCellPx - 1);
  u_mm.resize(static_cast<std::size_t>(gw));
  v_mm.resize(static_cast<std::size_t>(gh));
  for (int i = 0; i < gw; ++i) {
    u_mm[static_cast<std::size_t>(i)] = (kCellPx * i + half - 0.5 * (rig.width - 1)) * pitch_mm;
  }
  for (int j = 0; j < gh; ++j) {
    v_mm[static_cast<std::size_t>(j)] = (kCellPx * j + half - 0.5 * (rig.height - 1)) * pitch_mm;
  }
  const auto n = static_cast<std::size_t>(gw) * static_cast<std::size_t>(gh);
  height_mm.assign(n, kNaN);
  depth_mm.assign(n, 0.0);
  contact.assign(n, 0);
  smooth_depth_mm.assign(n, 0.0);
  normal_x.assign(n, 0.0);
  normal_y.assign(n, 0.0);
  tangential_x.assign(n, 0.0);
  tangential_y.assign(n, 0.0);
  bonded_normal_x.assign(n, 0.0);
  bonded_normal_y.assign(n, 0.0);
  bond_x.assign(n, 0.0);
  bond_y.assign(n, 0.0);
  total_x.assign(n, 0.0);
  total_y.assign(n, 0.0);
  slide_vx.assign(n, 0.0);
  slide_vy.assign(n, 0.0);
  shade.assign(n, 1.0);
  pad_surface_mm = 0.0;
}

void PadPhysics::build(Sensor sensor, const RigSpec& rig, const GelSpec& gel,
                       const ShadingSpec& shading, std::uint64_t seed) {
  sensor_ = sensor;
  rig_ = rig;
  gel_ = gel;
  shading_ = shading;
  rpad_ = pad_rotation(sensor);
  f_.allocate(rig);
  const double sigma_cells = gel.bulge_sigma_mm / f_.cell_mm;
  gauss_radius_ = std::max(1, static_cast<int>(std::ceil(3.0 * sigma_cells)));
  gauss_.assign(static_cast<std::size_t>(2 * gauss_radius_ + 1), 0.0);
  double sum = 0.0;
  for (int k = -gauss_radius_; k <= gauss_radius_; ++k) {
    sum += std::exp(-0.5 * k * k / (sigma_cells * sigma_cells));
  }
  for (int k = -gauss_radius_; k <= gauss_radius_; ++k) {
    gauss_[static_cast<std::size_t>(k + gauss_radius_)] =
        static_cast<double>(std::exp(-0.5 * k * k / (sigma_cells * sigma_cells)) / sum);
  }
  scratch_.assign(f_.depth_mm.size(), 0.0);
  build_friction_map(seed);
  capped_.assign(f_.depth_mm.size(), 0);
  radial_mass_.clear();
  if (gel.bulge_model == BulgeModel::kRadialVolume) {
    const double diag =
        std::hypot(f_.u_mm.back() - f_.u_mm.front(), f_.v_mm.back() - f_.v_mm.front());
    radial_mass_.assign(static_cast<std::size_t>(std::ceil(diag / (0.5 * f_.cell_mm))) + 2, 0.0);
  }
  if (gel.spread_kernel == SpreadKernel::kHalfSpace) {
    halfspace_.build(f_.gw, f_.gh, f_.cell_mm, gel.spread_length_mm);
  }
  reset();
}

// mu(x) = mu (1 + a m(x)): m is the mean of three plane waves of 4-12 mm wavelength (a gel's
// coating and the object's surface vary on the scale of millimetres), so |m| <= 1.
void PadPhysics::build_friction_map(std::uint64_t seed) {
  friction_scale_.assign(f_.depth_mm.size(), 1.0);
  if (gel_.friction_variation <= 0.0) return;
  Rng rng(hash_combine(seed, 0xF71C7 + static_cast<std::uint64_t>(sensor_)));
  double kx[3], ky[3], ph[3];
  for (int q = 0; q < 3; ++q) {
    const double k = 2.0 * std::numbers::pi / rng.uniform(4.0, 12.0);
    const double dir = rng.uniform(0.0, 2.0 * std::numbers::pi);
    kx[q] = k * std::cos(dir);
    ky[q] = k * std::sin(dir);
    ph[q] = rng.uniform(0.0, 2.0 * std::numbers::pi);
  }
  for (int j = 0; j < f_.gh; ++j) {
    for (int i = 0; i < f_.gw; ++i) {
      const double u = f_.u_mm[static_cast<std::size_t>(i)],
                   v = f_.v_mm[static_cast<std::size_t>(j)];
      double m = 0.0;
      for (int q = 0; q < 3; ++q) m += std::cos(kx[q] * u + ky[q] * v + ph[q]) / 3.0;
      friction_scale_[f_.index(i, j)] = 1.0 + gel_.friction_variation * m;
    }
  }
}

void PadPhysics::reset() noexcept {
  std::fill(f_.height_mm.begin(), f_.height_mm.end(), kNaN);
  for (auto* v : {&f_.depth_mm, &f_.smooth_depth_mm, &f_.normal_x, &f_.normal_y, &f_.tangential_x,
                  &f_.tangential_y, &f_.bonded_normal_x, &f_.bonded_normal_y, &f_.bond_x,
                  &f_.bond_y, &f_.total_x, &f_.total_y, &f_.slide_vx, &f_.slide_vy}) {
    std::fill(v->begin(), v->end(), 0.0);
  }
  std::fill(f_.contact.begin(), f_.contact.end(), std::uint8_t{0});
  std::fill(capped_.begin(), capped_.end(), std::uint8_t{0});
  std::fill(f_.shade.begin(), f_.shade.end(), 1.0);
  labels_ = PadLabels{};
  has_last_ = false;
  bond_captured_ = false;
  has_height_ = false;
  t_last_ = 0.0;
  local_last_ = 0.0;
  hmax_ = 0.0;
}

double PadPhysics::trace_height(const Shape& shape, const Eigen::Vector3d& a,
                                const Eigen::Vector3d& b, double n_top, double n_bot,
                                bool* inside_at_top, int* evals) noexcept {
  const double lip = shape.lipschitz();
  double n_out = n_top;
  double f_out = shape.sdf(a + n_top * b);
  ++*evals;
  if (f_out <= 0.0) {
    *inside_at_top = true;
    return n_top;
  }
  if (f_out > (n_top - n_bot) * lip) return kNaN;  // the surface is farther than the band
  double n_in = kNaN;
  double f_in = 0.0;
  // Sphere tracing along -n: steps of f / L never cross the surface.
  for (int it = 0; it < 160; ++it) {
    const double step = std::max(f_out / lip, 1e-3);
    double n_next = n_out - step;
    if (n_next < n_bot) n_next = n_bot;
    const double f_next = shape.sdf(a + n_next * b);
    ++*evals;
    if (f_next <= 0.0) {
      n_in = n_next;
      f_in = f_next;
      break;
    }
    if (n_next <= n_bot) return kNaN;
    n_out = n_next;
    f_out = f_next;
  }
  if (std::isnan(n_in)) return kNaN;  // grazing ray
  // Illinois regula falsi on the bracket [n_in (inside), n_out (outside)].
  int side = 0;
  for (int it = 0; it < 24 && (n_out - n_in) > 1e-7; ++it) {
    const double n_mid = (n_in * f_out - n_out * f_in) / (f_out - f_in);
    const double f_mid = shape.sdf(a + n_mid * b);
    ++*evals;
    if (f_mid > 0.0) {
      n_out = n_mid;
      f_out = f_mid;
      if (side == -1) f_in *= 0.5;
      side = -1;
    } else {
      n_in = n_mid;
      f_in = f_mid;
      if (side == 1) f_out *= 0.5;
      side = 1;
    }
    if (std::abs(f_mid) < 1e-9) break;
  }
  return f_out < -f_in ? n_out : n_in;
}

bool PadPhysics::compute_contact(const Scenario& scn, const Shape& shape, double t,
                                 double dt) noexcept {
  const Pose pose = scn.pose(t);
  const Eigen::Matrix3d rt = pose.q.conjugate().toRotationMatrix();
  const Eigen::Matrix3d m = rt * rpad_.transpose();  // pad vectors -> object-centred vectors
  const Eigen::Vector3d off(scn.object().offset_mm.x(), scn.object().offset_mm.y(), 0.0);
  const Eigen::Vector3d base = -(rt * pose.p) - off;
  const Eigen::Vector3d mu = m.col(0), mv = m.col(1), b = m.col(2);
  const double reach = shape.bounding_radius() + off.norm() + pose.p.norm() + 1.0;
  const double indent = scn.indentation_mm(t);

  bool full = !has_height_;
  int hits = 0;
  double hmax = -std::numeric_limits<double>::infinity();
  int evals = 0;
  for (int attempt = 0; attempt < 2; ++attempt) {
    double top = reach, bot = -reach;
    if (!full) {
      const Twist tw1 = scn.twist(t);
      const Twist tw0 = scn.twist(std::max(0.0, t - dt));
      const double speed =
          std::max(tw1.w.norm(), tw0.w.norm()) * reach + std::max(tw1.v.norm(), tw0.v.norm());
      const double margin = 1.5 * speed * dt + 0.02;
      top = hmax_ + margin;
      bot = hmax_ - margin - std::max(0.0, indent) - 0.05;
    }
    bool inside = false;
    hits = 0;
    hmax = -std::numeric_limits<double>::infinity();
    for (int j = 0; j < f_.gh; ++j) {
      const Eigen::Vector3d row = base + f_.v_mm[static_cast<std::size_t>(j)] * mv;
      for (int i = 0; i < f_.gw; ++i) {
        const Eigen::Vector3d a = row + f_.u_mm[static_cast<std::size_t>(i)] * mu;
        const double h = trace_height(shape, a, b, top, bot, &inside, &evals);
        f_.height_mm[f_.index(i, j)] = h;
        if (!std::isnan(h)) {
          ++hits;
          hmax = std::max(hmax, h);
        }
      }
    }
    if (!full && (inside || hits == 0)) {
      full = true;  // the object moved out of the tracked band: trace the whole range again
      continue;
    }
    break;
  }
  labels_.trace_sdf_evals = evals;
  if (hits == 0) {
    has_height_ = false;
    std::fill(f_.depth_mm.begin(), f_.depth_mm.end(), 0.0);
    std::fill(f_.contact.begin(), f_.contact.end(), std::uint8_t{0});
    return false;
  }
  has_height_ = true;
  // The highest object point generally lies between cell centres: refine it with a few extra
  // rays, moving to the vertex of a parabola through three samples along u, then along v
  // (exact for a locally quadratic cap; a flat face has no curvature and stays as sampled).
  std::size_t kmax = 0;
  for (std::size_t k = 0; k < f_.height_mm.size(); ++k) {
    if (f_.height_mm[k] == hmax) {
      kmax = k;
      break;
    }
  }
  {
    double pu = f_.u_mm[kmax % static_cast<std::size_t>(f_.gw)];
    double pv = f_.v_mm[kmax / static_cast<std::size_t>(f_.gw)];
    const double top = hmax + 0.5 * f_.cell_mm, bot = hmax - f_.cell_mm;
    auto h_at = [&](double u, double v) {
      bool inside = false;
      const double h = trace_height(shape, base + u * mu + v * mv, b, top, bot, &inside, &evals);
      return std::isnan(h) ? -1e30 : h;
    };
    double step = 0.5 * f_.cell_mm;
    for (int round = 0; round < 3; ++round, step *= 0.5) {
      for (int axis = 0; axis < 2; ++axis) {
        const double du = axis == 0 ? step : 0.0, dv = axis == 0 ? 0.0 : step;
        const double hm = h_at(pu - du, pv - dv), hp = h_at(pu + du, pv + dv);
        const double curv = hm - 2.0 * hmax + hp;
        if (curv >= -1e-12) continue;
        const double x = std::clamp(0.5 * (hm - hp) / curv, -1.0, 1.0);
        const double h = h_at(pu + x * du, pv + x * dv);
        if (h > hmax) {
          hmax = h;
          pu += x * du;
          pv += x * dv;
        }
      }
    }
  }
  labels_.trace_sdf_evals = evals;
  hmax_ = hmax;
  // Force-controlled pad: its undeformed surface sits `indent` below the highest object point.
  const double surface = hmax - indent;
  f_.pad_surface_mm = surface;
  for (std::size_t k = 0; k < f_.depth_mm.size(); ++k) {
    const double h = f_.height_mm[k];
    const double d = std::isnan(h) ? 0.0 : std::max(0.0, h - surface);
    f_.depth_mm[k] = static_cast<double>(d);
    f_.contact[k] = d > kContactEpsMm ? 1 : 0;
  }
  return true;
}

void PadPhysics::compute_normal() noexcept {
  const int gw = f_.gw, gh = f_.gh, r = gauss_radius_;
  // Separable Gaussian with clamped borders: Phi = G_sigma * d.
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      double acc = 0.0;
      for (int k = -r; k <= r; ++k) {
        const int ii = std::clamp(i + k, 0, gw - 1);
        acc += gauss_[static_cast<std::size_t>(k + r)] * f_.depth_mm[f_.index(ii, j)];
      }
      scratch_[f_.index(i, j)] = acc;
    }
  }
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      double acc = 0.0;
      for (int k = -r; k <= r; ++k) {
        const int jj = std::clamp(j + k, 0, gh - 1);
        acc += gauss_[static_cast<std::size_t>(k + r)] * scratch_[f_.index(i, jj)];
      }
      f_.smooth_depth_mm[f_.index(i, j)] = acc;
    }
  }
  const Eigen::Vector2d l = shading_.light_dir.normalized();
  const auto k_n = static_cast<double>(gel_.bulge_gain_mm);
  const auto inv2c = static_cast<double>(0.5 / f_.cell_mm);
  const auto& phi = f_.smooth_depth_mm;
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      const std::size_t k = f_.index(i, j);
      const int i0 = std::max(i - 1, 0), i1 = std::min(i + 1, gw - 1);
      const int j0 = std::max(j - 1, 0), j1 = std::min(j + 1, gh - 1);
      const double gx = (phi[f_.index(i1, j)] - phi[f_.index(i0, j)]) * inv2c *
                        (2.0 / static_cast<double>(i1 - i0));
      const double gy = (phi[f_.index(i, j1)] - phi[f_.index(i, j0)]) * inv2c *
                        (2.0 / static_cast<double>(j1 - j0));
      f_.normal_x[k] = -k_n * gx;
      f_.normal_y[k] = -k_n * gy;
      f_.shade[k] = static_cast<double>(1.0 +
                                        shading_.slope_gain * (static_cast<double>(gx) * l.x() +
                                                               static_cast<double>(gy) * l.y()) -
                                        shading_.press_gain_per_mm * static_cast<double>(phi[k]));
    }
  }
  if (gel_.bulge_model == BulgeModel::kRadialVolume) radial_bulge();
}

// Incompressible layer of thickness h: the volume V(r) pressed down within radius r of the
// patch's depth-weighted centre flows out through the cylinder of radius r, so the depth-mean
// outward displacement is V(r) / (2 pi r h); the surface moves eta times that. Beyond the
// patch the gel's finite extent damps it as exp(-(r - r_patch) / sigma). The shading keeps the
// smoothed surface (the surface shape, not its in-plane flow, tilts it).
void PadPhysics::radial_bulge() noexcept {
  double mass = 0.0, cu = 0.0, cv = 0.0;
  for (int j = 0; j < f_.gh; ++j) {
    for (int i = 0; i < f_.gw; ++i) {
      const double d = f_.depth_mm[f_.index(i, j)];
      mass += d;
      cu += d * f_.u_mm[static_cast<std::size_t>(i)];
      cv += d * f_.v_mm[static_cast<std::size_t>(j)];
    }
  }
  std::fill(f_.normal_x.begin(), f_.normal_x.end(), 0.0);
  std::fill(f_.normal_y.begin(), f_.normal_y.end(), 0.0);
  if (mass <= 0.0) return;
  cu /= mass;
  cv /= mass;
  const double bin = 0.5 * f_.cell_mm, area = f_.cell_mm * f_.cell_mm;
  const std::size_t nb = radial_mass_.size();
  std::fill(radial_mass_.begin(), radial_mass_.end(), 0.0);
  double r_patch = 0.0;
  for (int j = 0; j < f_.gh; ++j) {
    for (int i = 0; i < f_.gw; ++i) {
      const double d = f_.depth_mm[f_.index(i, j)];
      if (d <= 0.0) continue;
      const double r = std::hypot(f_.u_mm[static_cast<std::size_t>(i)] - cu,
                                  f_.v_mm[static_cast<std::size_t>(j)] - cv);
      r_patch = std::max(r_patch, r);
      radial_mass_[std::min(nb - 1, static_cast<std::size_t>(r / bin))] += d * area;
    }
  }
  for (std::size_t b = 1; b < nb; ++b) radial_mass_[b] += radial_mass_[b - 1];  // V at bin ends
  const double gain = gel_.bulge_surface_factor / (2.0 * std::numbers::pi * gel_.gel_thickness_mm);
  for (int j = 0; j < f_.gh; ++j) {
    for (int i = 0; i < f_.gw; ++i) {
      const double du = f_.u_mm[static_cast<std::size_t>(i)] - cu;
      const double dv = f_.v_mm[static_cast<std::size_t>(j)] - cv;
      const double r = std::hypot(du, dv);
      if (r < 1e-9) continue;
      // V(r) interpolated between bin ends (bin b ends at (b + 1) * bin).
      const double x = r / bin - 1.0;
      double vol = radial_mass_[nb - 1];
      if (x < 0.0) {
        vol = radial_mass_[0] * (r / bin);
      } else if (x < static_cast<double>(nb - 1)) {
        const auto b = static_cast<std::size_t>(x);
        vol = radial_mass_[b] +
              (x - static_cast<double>(b)) * (radial_mass_[b + 1] - radial_mass_[b]);
      }
      const double damp = std::exp(-std::max(0.0, r - r_patch) / gel_.bulge_sigma_mm);
      const double mag = gain * vol / r * damp;
      f_.normal_x[f_.index(i, j)] = mag * du / r;
      f_.normal_y[f_.index(i, j)] = mag * dv / r;
    }
  }
}

bool PadPhysics::cap(double* ux, double* uy, double umax) noexcept {
  const double mag = std::hypot(*ux, *uy);
  if (mag <= umax) return false;
  const double scale = umax / mag;
  *ux *= scale;
  *uy *= scale;
  return true;
}

void PadPhysics::compute_tangential(const Scenario& scn, const Pose& pose, double t, double dt,
                                    double umax_per_mm) noexcept {
  const Twist tw = scn.twist(t);
  const bool sliding = scn.sliding();
  int nsub = 0;
  double decay = 0.0;
  if (sliding && dt > 0.0) {
    nsub = std::clamp(static_cast<int>(std::ceil(dt / (0.25 * gel_.lag_time_s))), 1, kMaxSubsteps);
    const double hs = dt / nsub;
    decay = 1.0 - std::exp(-hs / gel_.lag_time_s);
    for (int s = 0; s < nsub; ++s) {
      const Twist tws = scn.twist(t - dt + (s + 0.5) * hs);
      sub_w_[static_cast<std::size_t>(s)] = tws.w;
      sub_v_[static_cast<std::size_t>(s)] = tws.v;
    }
  }
  const double c = gel_.drag_time_s;
  for (int j = 0; j < f_.gh; ++j) {
    for (int i = 0; i < f_.gw; ++i) {
      const std::size_t k = f_.index(i, j);
      if (!f_.contact[k]) {
        f_.slide_vx[k] = 0.0;
        f_.slide_vy[k] = 0.0;
        continue;
      }
      // Contact point: the object's surface point now touching this gel cell, in G.
      const Eigen::Vector3d c_pad(f_.u_mm[static_cast<std::size_t>(i)],
                                  f_.v_mm[static_cast<std::size_t>(j)], f_.height_mm[k]);
      const Eigen::Vector3d c_g = rpad_.transpose() * c_pad;
      const Eigen::Vector3d vel = rpad_ * tw.velocity_at(c_g);
      f_.slide_vx[k] = static_cast<double>(vel.x());
      f_.slide_vy[k] = static_cast<double>(vel.y());
      const double umax = umax_per_mm * static_cast<double>(f_.depth_mm[k]) * friction_scale_[k];
      if (!sliding) {
        // Stick: the gel point now at c was carried there by the object, from where the same
        // object point was before the motion (the pose is the identity before the motion).
        const Eigen::Vector3d disp = rpad_ * (c_g - pose.apply_inverse(c_g));
        double ux = disp.x(), uy = disp.y();
        // Coulomb rim: a stuck cell holds at most mu kappa d; the shallow rim reaches it first
        // and slips there while the centre still sticks (Cattaneo-Mindlin partial slip).
        capped_[k] = gel_.slide_law == SlideLaw::kCoulombRim && cap(&ux, &uy, umax) ? 1 : 0;
        f_.tangential_x[k] = ux;
        f_.tangential_y[k] = uy;
        continue;
      }
      double ux = f_.tangential_x[k], uy = f_.tangential_y[k];
      if (gel_.slide_law == SlideLaw::kTanh) {
        // tau dU/dt = Umax tanh(c|v| / Umax) v/|v| - U: a smooth saturation, no hard cap.
        for (int s = 0; s < nsub; ++s) {
          const auto si = static_cast<std::size_t>(s);
          const Eigen::Vector3d vs = rpad_ * (sub_w_[si].cross(c_g) + sub_v_[si]);
          double tx = c * vs.x(), ty = c * vs.y();
          const double mag = std::hypot(tx, ty);
          const double scale = mag > 0.0 && umax > 0.0 ? umax * std::tanh(mag / umax) / mag : 0.0;
          tx *= scale;
          ty *= scale;
          ux += (tx - ux) * decay;
          uy += (ty - uy) * decay;
        }
        f_.tangential_x[k] = ux;
        f_.tangential_y[k] = uy;
        continue;
      }
      // Slide: tau dU/dt = c v - U, integrated exactly per sub-step, then the Coulomb cap.
      for (int s = 0; s < nsub; ++s) {
        const auto si = static_cast<std::size_t>(s);
        const Eigen::Vector3d vs = rpad_ * (sub_w_[si].cross(c_g) + sub_v_[si]);
        ux += (c * vs.x() - ux) * decay;
        uy += (c * vs.y() - uy) * decay;
        (void)cap(&ux, &uy, umax);
      }
      (void)cap(&ux, &uy, umax);
      f_.tangential_x[k] = static_cast<double>(ux);
      f_.tangential_y[k] = static_cast<double>(uy);
    }
  }
}

void PadPhysics::spread() noexcept {
  bool any = false;
  for (auto c : f_.contact) any = any || c != 0;
  if (!any) {
    std::fill(f_.tangential_x.begin(), f_.tangential_x.end(), 0.0);
    std::fill(f_.tangential_y.begin(), f_.tangential_y.end(), 0.0);
    labels_.spread_sweeps = 0;
    return;
  }
  labels_.spread_sweeps = spread_field(f_.tangential_x.data(), f_.tangential_y.data());
}

// Thin elastic layer on a rigid backing: outside the patch the in-plane displacement obeys
// lambda^2 lap(U) = U (screened Poisson), with U given on the patch and free (Neumann) image
// borders. Red-black SOR, warm-started from the previous frame's values off the patch.
int PadPhysics::spread_field(double* ux, double* uy) noexcept {
  if (gel_.spread_kernel == SpreadKernel::kHalfSpace) {
    halfspace_.apply(f_.contact.data(), ux, uy);
    return 0;
  }
  const int gw = f_.gw, gh = f_.gh;
  const double alpha = static_cast<double>(std::pow(f_.cell_mm / gel_.spread_length_mm, 2.0));
  const auto omega = static_cast<double>(kSorOmega);
  const std::uint8_t* fixed = f_.contact.data();
  int sweep = 0;
  for (; sweep < kSorMaxSweeps; ++sweep) {
    double max_delta = 0.0;
    for (int parity = 0; parity < 2; ++parity) {
      for (int j = 0; j < gh; ++j) {
        for (int i = (j + parity) & 1; i < gw; i += 2) {
          const std::size_t k = f_.index(i, j);
          if (fixed[k]) continue;
          double sx = 0.0, sy = 0.0, n = 0.0;
          if (i > 0) {
            sx += ux[k - 1];
            sy += uy[k - 1];
            n += 1.0;
          }
          if (i + 1 < gw) {
            sx += ux[k + 1];
            sy += uy[k + 1];
            n += 1.0;
          }
          if (j > 0) {
            sx += ux[k - static_cast<std::size_t>(gw)];
            sy += uy[k - static_cast<std::size_t>(gw)];
            n += 1.0;
          }
          if (j + 1 < gh) {
            sx += ux[k + static_cast<std::size_t>(gw)];
            sy += uy[k + static_cast<std::size_t>(gw)];
            n += 1.0;
          }
          const double inv = 1.0 / (n + alpha);
          const double dx = sx * inv - ux[k];
          const double dy = sy * inv - uy[k];
          ux[k] += omega * dx;
          uy[k] += omega * dy;
          max_delta = std::max(max_delta, std::max(std::abs(dx), std::abs(dy)));
        }
      }
    }
    if (max_delta < static_cast<double>(kSorTolMm)) {
      ++sweep;
      break;
    }
  }
  return sweep;
}

void PadPhysics::compute_labels(bool sliding) noexcept {
  int count = 0, slipping = 0;
  double su = 0.0, sv = 0.0, peak = 0.0;
  const double thr2 = gel_.slip_speed_mm_s * gel_.slip_speed_mm_s;
  for (int j = 0; j < f_.gh; ++j) {
    for (int i = 0; i < f_.gw; ++i) {
      const std::size_t k = f_.index(i, j);
      if (!f_.contact[k]) continue;
      ++count;
      su += f_.u_mm[static_cast<std::size_t>(i)];
      sv += f_.v_mm[static_cast<std::size_t>(j)];
      peak = std::max(peak, static_cast<double>(f_.depth_mm[k]));
      const double vx = f_.slide_vx[k], vy = f_.slide_vy[k];
      const double v2 = vx * vx + vy * vy;
      if ((sliding && v2 > thr2) || (!sliding && capped_[k])) ++slipping;
    }
  }
  labels_.in_contact = count > 0;
  labels_.area_mm2 = count * f_.cell_mm * f_.cell_mm;
  labels_.centroid_mm =
      count > 0 ? Eigen::Vector2d(su / count, sv / count) : Eigen::Vector2d::Zero();
  labels_.peak_depth_mm = peak;
  labels_.slip_fraction = count > 0 ? static_cast<double>(slipping) / count : 0.0;
  labels_.slipping = labels_.slip_fraction > 0.5;
}

// Stick: the gel over the patch is bonded to the object, so the material now at c is where the
// object carried it since the motion started, bulge and all: it sat at c − U_t(c) then, displaced
// by that moment's bulge U_n0, so U(c) = U_t(c) + U_n0(c − U_t(c)) over the patch (docs/
// simulator.md §6). The bond's correction to the current bulge, B = U_n0(c − U_t(c)) − U_n(c), is
// set on the patch and spread outside it like U_t. A plain sum U_t + U_n would make a stuck
// torsion's bulged gel turn 1/(1 − k) times as fast as the object (U_n ≈ k r inside the patch):
// the bulge vector would stay unturned while the material carrying it turns. Where the bulge
// moves with the object (a translation) B is ≈ 0. A slide is not bonded (B = 0): the bulge
// follows the indenter. U_n0 is sampled bilinearly between cells. load_ratio (the commanded
// indentation over the grasp's, in [0, 1]) scales U_n0: as the pads open the bonded gel's bulge
// relaxes with the load, so B falls to 0 with the contact instead of vanishing with its last cell.
void PadPhysics::bond_normal(bool sliding, bool moving, double load_ratio) noexcept {
  if (sliding || !moving || !bond_captured_) {
    // Nothing bonded yet: keep the bulge as it is now. Before the motion B = 0 (and a slide is
    // never bonded); a pad first stepped during the motion (the live camera joins a scenario at
    // the present) bonds the bulge it finds.
    f_.bonded_normal_x = f_.normal_x;
    f_.bonded_normal_y = f_.normal_y;
    bond_captured_ = !sliding;
    std::fill(f_.bond_x.begin(), f_.bond_x.end(), 0.0);
    std::fill(f_.bond_y.begin(), f_.bond_y.end(), 0.0);
    if (sliding || !moving) return;
  }
  const double scale = std::clamp(load_ratio, 0.0, 1.0);
  const int gw = f_.gw, gh = f_.gh;
  const double inv_cell = 1.0 / f_.cell_mm;
  bool any = false;
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      const std::size_t k = f_.index(i, j);
      if (!f_.contact[k]) continue;
      any = true;
      const double fi =
          std::clamp(i - f_.tangential_x[k] * inv_cell, 0.0, static_cast<double>(gw - 1));
      const double fj =
          std::clamp(j - f_.tangential_y[k] * inv_cell, 0.0, static_cast<double>(gh - 1));
      const int i0 = std::min(static_cast<int>(fi), gw - 2);
      const int j0 = std::min(static_cast<int>(fj), gh - 2);
      const double wx = fi - i0, wy = fj - j0;
      const auto bilinear = [&](const std::vector<double>& v) {
        const double top =
            v[f_.index(i0, j0)] + wx * (v[f_.index(i0 + 1, j0)] - v[f_.index(i0, j0)]);
        const double bottom =
            v[f_.index(i0, j0 + 1)] + wx * (v[f_.index(i0 + 1, j0 + 1)] - v[f_.index(i0, j0 + 1)]);
        return top + wy * (bottom - top);
      };
      f_.bond_x[k] = scale * bilinear(f_.bonded_normal_x) - f_.normal_x[k];
      f_.bond_y[k] = scale * bilinear(f_.bonded_normal_y) - f_.normal_y[k];
    }
  }
  if (!any) {
    std::fill(f_.bond_x.begin(), f_.bond_x.end(), 0.0);
    std::fill(f_.bond_y.begin(), f_.bond_y.end(), 0.0);
    return;
  }
  (void)spread_field(f_.bond_x.data(), f_.bond_y.data());
}

SimStatus PadPhysics::step(const Scenario& scn, const Shape& shape, double t) noexcept {
  if (has_last_ && t < t_last_ - 1e-12) return SimStatus::kTimeBackwards;
  const double local = scn.local_time(t);
  if (has_last_ && local < local_last_ - 1e-12) reset();  // a new loop cycle starts afresh
  const double dt = has_last_ ? local - local_last_ : 0.0;
  const Pose pose = scn.pose(local);
  compute_contact(scn, shape, local, dt);
  compute_normal();
  compute_tangential(scn, pose, local, dt, shape.spec().friction * gel_.shear_compliance);
  spread();
  bond_normal(scn.sliding(), local >= scn.motion_start_s(),
              scn.indentation_mm(local) / scn.spec().indentation_mm);
  for (std::size_t k = 0; k < f_.total_x.size(); ++k) {
    f_.total_x[k] = f_.tangential_x[k] + f_.bond_x[k] + f_.normal_x[k];
    f_.total_y[k] = f_.tangential_y[k] + f_.bond_y[k] + f_.normal_y[k];
  }
  compute_labels(scn.sliding());
  t_last_ = t;
  local_last_ = local;
  has_last_ = true;
  return SimStatus::kOk;
}

}  // namespace tacse3::sim
