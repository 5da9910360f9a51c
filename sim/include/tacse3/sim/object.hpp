// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: grasped-object shapes as signed distance functions, and the paper's object presets.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace tacse3::sim {

enum class ShapeKind : std::uint8_t {
  kSphere = 0,
  kEllipsoid,
  kCylinder,     // axis along G y
  kRoundedCube,  // flat faces normal to the G axes, rounded edges
  kBumpy,        // sphere with random smooth bumps and dents ("irregular-shaped object")
  kScrewdriver,  // cylinder along G y with rounded lobes and narrow flutes (grooves)
};

const char* to_string(ShapeKind k) noexcept;
bool parse_shape(std::string_view name, ShapeKind* out) noexcept;

// Geometry and surface of the grasped object. All lengths in millimetres. At the first frame the
// object's centre is at (offset_mm.x, offset_mm.y, 0) in G and its canonical axes are G's axes.
struct ObjectSpec {
  ShapeKind shape = ShapeKind::kSphere;
  // Half-width along G z (the grasp axis) at rest: sphere/cylinder/screwdriver radius,
  // ellipsoid z semi-axis, cube half-edge along z.
  double size_mm = 20.0;
  double aspect_x = 1.0;    // ellipsoid/cube: semi-axis (half-edge) along x, relative to size_mm
  double aspect_y = 1.0;    // ellipsoid/cube: semi-axis (half-edge) along y, relative to size_mm
  double length_mm = 80.0;  // cylinder/screwdriver length along G y
  double edge_radius_mm = 2.0;     // rounding of the cube's edges and the cylinder's end rims
  int bump_count = 10;             // bumpy: number of bumps/dents
  double bump_height_mm = 1.0;     // bumpy: largest bump height (dents are up to half as deep)
  double bump_width_mm = 5.0;      // bumpy: typical bump width (Gaussian sigma along the surface)
  int flute_count = 6;             // screwdriver: number of flutes (even keeps a lobe on both pads)
  double flute_depth_mm = 1.2;     // screwdriver: flute depth below the lobes
  double flute_sharpness = 3.0;    // screwdriver: >= 1, larger = narrower flutes, flatter lobes
  double texture_height_mm = 0.0;  // peak-to-peak of a periodic surface relief (0 = smooth)
  double texture_period_mm = 2.0;  // its period
  double friction = 0.8;           // Coulomb friction coefficient against the gel
  Eigen::Vector2d offset_mm = Eigen::Vector2d::Zero();
  std::uint64_t seed = 1;  // bumpy shape
};

// Named presets: the six shapes ("sphere", "ellipsoid", "cylinder", "cube", "bumpy",
// "screwdriver") and the paper's eight objects of Sec. V-C ("large-sphere", "ellipsoid",
// "irregular", "cylinder", "plastic-cube", "wooden-cube", "textured-cube", "screwdriver").
bool object_preset(std::string_view name, ObjectSpec* out) noexcept;
// Comma-separated list of the preset names, for help texts.
const char* object_preset_names() noexcept;

// Empty string if the spec is usable, else a message naming the offending field.
std::string validate(const ObjectSpec& spec);

// Immutable shape: signed distance (negative inside) in object-centred, G-aligned coordinates.
// For the bumpy, fluted and textured shapes the function is a bound rather than an exact
// distance; lipschitz() bounds its gradient so sphere tracing never overshoots the surface.
class Shape {
 public:
  static constexpr int kMaxBumps = 32;

  explicit Shape(const ObjectSpec& spec) noexcept;  // precondition: validate(spec) is empty

  double sdf(const Eigen::Vector3d& r) const noexcept;
  double lipschitz() const noexcept { return lipschitz_; }
  double bounding_radius() const noexcept { return bounding_radius_; }
  const ObjectSpec& spec() const noexcept { return spec_; }

 private:
  double base_sdf(const Eigen::Vector3d& r) const noexcept;

  ObjectSpec spec_;
  int bump_count_ = 0;
  std::array<Eigen::Vector3d, kMaxBumps> bump_dir_{};
  std::array<double, kMaxBumps> bump_height_{};
  std::array<double, kMaxBumps> bump_inv_width2_{};
  double lipschitz_ = 1.0;
  double bounding_radius_ = 0.0;
};

}  // namespace tacse3::sim
