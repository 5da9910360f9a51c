// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: per-pad contact mechanics (contact patch, normal bulge, stick/slide shear,
// spreading).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "tacse3/sim/object.hpp"
#include "tacse3/sim/scenario.hpp"
#include "tacse3/sim/spread.hpp"
#include "tacse3/sim/types.hpp"

namespace tacse3::sim {

// Modelling choices of the gel (docs/sim-profiles.md). The first value of each is the reference
// physics of docs/simulator.md.
enum class BulgeModel : std::uint8_t {
  kSmoothedGradient = 0,  // U_n = -k grad(G_sigma * d)
  kRadialVolume,          // incompressible layer: displaced volume flows radially outward
};
enum class SlideLaw : std::uint8_t {
  kViscousCapped = 0,  // tau dU/dt = c v - U, |U| <= mu kappa d
  kTanh,               // tau dU/dt = Umax tanh(c|v| / Umax) v/|v| - U
  kCoulombRim,         // viscous slide; a stuck cell is capped too, so the rim slips first
};
enum class SpreadKernel : std::uint8_t {
  kThinLayer = 0,  // screened Poisson (exponential decay), thin layer on a rigid backing
  kHalfSpace,      // rigid-punch elastic half-space (1/r far field), bounded by the thickness
};

const char* to_string(BulgeModel m) noexcept;
const char* to_string(SlideLaw m) noexcept;
const char* to_string(SpreadKernel m) noexcept;

// Mechanical parameters of the gel (docs/simulator.md, "Contact mechanics").
struct GelSpec {
  BulgeModel bulge_model = BulgeModel::kSmoothedGradient;
  SlideLaw slide_law = SlideLaw::kViscousCapped;
  SpreadKernel spread_kernel = SpreadKernel::kThinLayer;
  // Thin-layer decay length of tangential displacement outside the patch (~ gel thickness).
  double spread_length_mm = 2.0;
  // Normal response: in-plane bulge U_n = -bulge_gain * grad(G_sigma * d).
  double bulge_gain_mm = 1.2;
  double bulge_sigma_mm = 1.5;
  // Slide regime: tau dU/dt = c v_slide - U, |U| <= mu * kappa * d.
  double drag_time_s = 0.05;      // c: steady shear displacement per unit sliding speed (s)
  double lag_time_s = 0.06;       // tau: first-order lag (s); the derivation gives tau >= c
  double shear_compliance = 1.5;  // kappa: shear displacement per unit friction-limited traction
  // Radial-volume bulge: U_n(r) = eta V(r) / (2 pi r h), decaying as exp(-(r - r_patch) / sigma)
  // beyond the patch (bulge_sigma_mm is then the extent).
  double bulge_surface_factor = 1.0;  // eta: surface over depth-mean outward displacement
  double gel_thickness_mm = 2.0;      // h
  // Relative amplitude of a smooth friction map over the pad: mu(x) = mu (1 + a m(x)), |m| <= 1.
  double friction_variation = 0.0;
  // Labels: a contact cell counts as slipping when its sliding speed exceeds this (mm/s).
  double slip_speed_mm_s = 0.5;
};

// Shading of the deformed gel surface (Lambertian tilt toward the LEDs, darkening with depth).
struct ShadingSpec {
  Eigen::Vector2d light_dir{0.8, 0.6};  // in-plane direction the LED light comes from (pad u, v)
  double slope_gain = 0.6;              // relative brightness per unit surface slope
  double press_gain_per_mm = 0.04;      // relative darkening per mm of smoothed indentation
};

std::string validate(const GelSpec& spec);
std::string validate(const ShadingSpec& spec);

// Fields on the physics grid (gw x gh cells of kCellPx pixels, row-major). Displacements are
// in mm in the pad frame (= image axes), Eulerian: the gel material now seen at a cell came
// from (cell - displacement) in the undeformed gel. Cells outside the contact have depth 0.
struct PadFields {
  int gw = 0, gh = 0;
  double pitch_mm = 0.1;           // pixel pitch
  double cell_mm = 0.4;            // kCellPx * pitch
  std::vector<double> u_mm, v_mm;  // cell centre coordinates (size gw, gh)
  std::vector<double> height_mm;   // object surface height along n (NaN where the ray misses)
  std::vector<double> depth_mm;    // gel indentation d >= 0
  std::vector<std::uint8_t> contact;
  std::vector<double> smooth_depth_mm;             // Phi = G_sigma * d (gel surface deflection)
  std::vector<double> normal_x, normal_y;          // bulge -k grad(Phi)
  std::vector<double> tangential_x, tangential_y;  // shear field (stick or slide, spread)
  // Stick: the bulge as it was when the motion started (the gel then bonded to the object), and
  // the correction the bond makes to the current bulge, on the patch and spread outside it.
  std::vector<double> bonded_normal_x, bonded_normal_y;
  std::vector<double> bond_x, bond_y;
  std::vector<double> total_x, total_y;    // tangential + bond + normal
  std::vector<double> slide_vx, slide_vy;  // object surface velocity over the pad at contact cells
  std::vector<double> shade;               // multiplicative shading
  double pad_surface_mm = 0.0;  // undeformed gel surface position along n (half the separation)

  std::size_t index(int i, int j) const noexcept {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(gw) + static_cast<std::size_t>(i);
  }
  void allocate(const RigSpec& rig);
};

struct PadLabels {
  bool in_contact = false;
  double area_mm2 = 0.0;
  Eigen::Vector2d centroid_mm = Eigen::Vector2d::Zero();  // pad frame (u, v)
  double peak_depth_mm = 0.0;
  double slip_fraction = 0.0;  // share of contact cells sliding (stick: cells at the Coulomb cap)
  bool slipping = false;       // slip_fraction > 0.5
  int trace_sdf_evals = 0;     // cost counter of the last contact computation
  int spread_sweeps = 0;       // SOR sweeps used by the last spreading solve (0: half-space)
};

// One pad's mechanics. build() allocates everything; step() is allocation-free.
class PadPhysics {
 public:
  // seed draws the friction map (gel.friction_variation > 0); it is unused otherwise.
  void build(Sensor sensor, const RigSpec& rig, const GelSpec& gel, const ShadingSpec& shading,
             std::uint64_t seed = 0);
  void reset() noexcept;
  // Advances the pad to time t (seconds, non-decreasing since the last reset).
  SimStatus step(const Scenario& scenario, const Shape& shape, double t) noexcept;

  Sensor sensor() const noexcept { return sensor_; }
  const PadFields& fields() const noexcept { return f_; }
  PadFields& mutable_fields() noexcept { return f_; }
  const PadLabels& labels() const noexcept { return labels_; }
  double last_time() const noexcept { return t_last_; }

  // Highest object point along n for pad cell (u, v) between n_bot and n_top, or NaN.
  // inside_at_top is set when the band's top is already inside the object.
  static double trace_height(const Shape& shape, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             double n_top, double n_bot, bool* inside_at_top, int* evals) noexcept;

 private:
  bool compute_contact(const Scenario& scn, const Shape& shape, double t, double dt) noexcept;
  void compute_normal() noexcept;
  void radial_bulge() noexcept;
  void build_friction_map(std::uint64_t seed);
  // Scales (ux, uy) down to length umax if longer; true if it did.
  static bool cap(double* ux, double* uy, double umax) noexcept;
  void compute_tangential(const Scenario& scn, const Pose& pose, double t, double dt,
                          double umax_per_mm) noexcept;
  void spread() noexcept;
  int spread_field(double* ux, double* uy) noexcept;  // SOR sweeps used
  void bond_normal(bool sliding, bool moving, double load_ratio) noexcept;
  void compute_labels(bool sliding) noexcept;

  static constexpr int kMaxSubsteps = 64;

  Sensor sensor_ = Sensor::kLeft;
  RigSpec rig_;
  GelSpec gel_;
  ShadingSpec shading_;
  Eigen::Matrix3d rpad_ = Eigen::Matrix3d::Identity();
  PadFields f_;
  PadLabels labels_;
  std::vector<double> gauss_;  // 1-D kernel, radius gauss_radius_
  int gauss_radius_ = 0;
  std::vector<double> scratch_;         // separable blur pass
  std::vector<double> friction_scale_;  // 1 + a m(x) per cell
  std::vector<std::uint8_t> capped_;    // stuck cell held at its friction cap (partial slip)
  std::vector<double> radial_mass_;     // radial-volume bulge: displaced volume per ring
  HalfSpaceSpread halfspace_;
  bool has_last_ = false;
  bool bond_captured_ = false;  // bonded_normal holds the bulge the bond started from
  bool has_height_ = false;
  double t_last_ = 0.0;
  double local_last_ = 0.0;
  double hmax_ = 0.0;
  std::array<Eigen::Vector3d, kMaxSubsteps> sub_w_{};
  std::array<Eigen::Vector3d, kMaxSubsteps> sub_v_{};
};

}  // namespace tacse3::sim
