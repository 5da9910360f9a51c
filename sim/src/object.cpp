// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: signed distance functions of the object shapes, presets and validation.
#include "tacse3/sim/object.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "tacse3/sim/rng.hpp"

namespace tacse3::sim {
namespace {

struct PresetEntry {
  const char* name;
  void (*apply)(ObjectSpec&);
};

void preset_sphere(ObjectSpec& o) {
  o.shape = ShapeKind::kSphere;
  o.size_mm = 20.0;
  o.friction = 0.6;
}
void preset_large_sphere(ObjectSpec& o) {
  preset_sphere(o);
  o.size_mm = 25.0;
}
void preset_ellipsoid(ObjectSpec& o) {
  o.shape = ShapeKind::kEllipsoid;
  o.size_mm = 16.0;
  o.aspect_x = 1.5;
  o.aspect_y = 1.25;
  o.friction = 0.6;
}
void preset_bumpy(ObjectSpec& o) {
  o.shape = ShapeKind::kBumpy;
  o.size_mm = 18.0;
  o.aspect_x = 1.1;
  o.aspect_y = 0.92;
  o.bump_count = 12;
  o.bump_height_mm = 1.0;
  o.bump_width_mm = 4.5;
  o.friction = 0.6;
}
void preset_cylinder(ObjectSpec& o) {
  o.shape = ShapeKind::kCylinder;
  o.size_mm = 15.0;
  o.length_mm = 80.0;
  o.edge_radius_mm = 2.0;
  o.friction = 0.6;
}
void preset_plastic_cube(ObjectSpec& o) {
  o.shape = ShapeKind::kRoundedCube;
  o.size_mm = 10.0;
  o.edge_radius_mm = 2.0;
  o.friction = 0.45;
}
void preset_wooden_cube(ObjectSpec& o) {
  preset_plastic_cube(o);
  o.edge_radius_mm = 1.5;
  o.friction = 0.65;
  o.texture_height_mm = 0.03;  // fine grain
  o.texture_period_mm = 0.8;
}
void preset_textured_cube(ObjectSpec& o) {
  preset_plastic_cube(o);
  o.friction = 0.9;
  o.texture_height_mm = 0.15;
  o.texture_period_mm = 2.0;
}
void preset_screwdriver(ObjectSpec& o) {
  o.shape = ShapeKind::kScrewdriver;
  o.size_mm = 14.0;
  o.length_mm = 100.0;
  o.edge_radius_mm = 3.0;
  o.flute_count = 6;
  o.flute_depth_mm = 1.2;
  o.flute_sharpness = 3.0;
  o.friction = 0.7;
}

constexpr PresetEntry kPresets[] = {
    {"sphere", preset_sphere},           {"large-sphere", preset_large_sphere},
    {"ellipsoid", preset_ellipsoid},     {"bumpy", preset_bumpy},
    {"irregular", preset_bumpy},         {"cylinder", preset_cylinder},
    {"cube", preset_plastic_cube},       {"plastic-cube", preset_plastic_cube},
    {"wooden-cube", preset_wooden_cube}, {"textured-cube", preset_textured_cube},
    {"screwdriver", preset_screwdriver},
};

bool finite_in(double v, double lo, double hi) {
  return std::isfinite(v) && v >= lo && v <= hi;
}

}  // namespace

const char* to_string(ShapeKind k) noexcept {
  switch (k) {
    case ShapeKind::kSphere:
      return "sphere";
    case ShapeKind::kEllipsoid:
      return "ellipsoid";
    case ShapeKind::kCylinder:
      return "cylinder";
    case ShapeKind::kRoundedCube:
      return "cube";
    case ShapeKind::kBumpy:
      return "bumpy";
    case ShapeKind::kScrewdriver:
      return "screwdriver";
  }
  return "unknown";
}

bool parse_shape(std::string_view name, ShapeKind* out) noexcept {
  for (int i = 0; i <= static_cast<int>(ShapeKind::kScrewdriver); ++i) {
    const auto k = static_cast<ShapeKind>(i);
    if (name == to_string(k)) {
      *out = k;
      return true;
    }
  }
  return false;
}

bool object_preset(std::string_view name, ObjectSpec* out) noexcept {
  for (const auto& p : kPresets) {
    if (name == p.name) {
      ObjectSpec o;
      p.apply(o);
      o.offset_mm = out->offset_mm;
      o.seed = out->seed;
      *out = o;
      return true;
    }
  }
  return false;
}

const char* object_preset_names() noexcept {
  return "sphere, large-sphere, ellipsoid, bumpy, irregular, cylinder, cube, plastic-cube, "
         "wooden-cube, textured-cube, screwdriver";
}

std::string validate(const ObjectSpec& o) {
  if (!finite_in(o.size_mm, 1.0, 200.0)) return "object size_mm must be in [1, 200]";
  if (!finite_in(o.aspect_x, 0.2, 5.0)) return "object aspect_x must be in [0.2, 5]";
  if (!finite_in(o.aspect_y, 0.2, 5.0)) return "object aspect_y must be in [0.2, 5]";
  if (!finite_in(o.friction, 0.01, 5.0)) return "object friction must be in [0.01, 5]";
  if (!finite_in(o.texture_height_mm, 0.0, 2.0))
    return "object texture_height_mm must be in [0, 2]";
  if (!finite_in(o.texture_period_mm, 0.1, 100.0)) {
    return "object texture_period_mm must be in [0.1, 100]";
  }
  if (!std::isfinite(o.offset_mm.x()) || !std::isfinite(o.offset_mm.y()) ||
      o.offset_mm.norm() > 100.0) {
    return "object offset_mm must be finite and within 100 mm";
  }
  const double min_half = o.size_mm * std::min({1.0, o.aspect_x, o.aspect_y});
  switch (o.shape) {
    case ShapeKind::kSphere:
    case ShapeKind::kEllipsoid:
      break;
    case ShapeKind::kBumpy:
      if (o.bump_count < 0 || o.bump_count > Shape::kMaxBumps) {
        return "object bump_count must be in [0, 32]";
      }
      if (!finite_in(o.bump_height_mm, 0.0, 0.3 * min_half)) {
        return "object bump_height_mm must be in [0, 0.3 * smallest semi-axis]";
      }
      if (!finite_in(o.bump_width_mm, 0.5, 2.0 * o.size_mm)) {
        return "object bump_width_mm must be in [0.5, 2 * size_mm]";
      }
      break;
    case ShapeKind::kCylinder:
    case ShapeKind::kScrewdriver:
      if (!finite_in(o.length_mm, 2.0, 1000.0)) return "object length_mm must be in [2, 1000]";
      if (!finite_in(o.edge_radius_mm, 0.0, std::min(o.size_mm, o.length_mm / 2.0) * 0.9)) {
        return "object edge_radius_mm must be in [0, 0.9 * min(size, length/2)]";
      }
      if (o.shape == ShapeKind::kScrewdriver) {
        if (o.flute_count < 0 || o.flute_count > 32) return "object flute_count must be in [0, 32]";
        if (!finite_in(o.flute_depth_mm, 0.0, 0.4 * o.size_mm)) {
          return "object flute_depth_mm must be in [0, 0.4 * size_mm]";
        }
        if (!finite_in(o.flute_sharpness, 1.0, 16.0)) {
          return "object flute_sharpness must be in [1, 16]";
        }
      }
      break;
    case ShapeKind::kRoundedCube:
      if (!finite_in(o.edge_radius_mm, 0.0, 0.95 * min_half)) {
        return "object edge_radius_mm must be in [0, 0.95 * smallest half-edge]";
      }
      break;
    default:
      return "object shape is not a known ShapeKind";
  }
  return {};
}

Shape::Shape(const ObjectSpec& spec) noexcept : spec_(spec) {
  const double r = spec.size_mm;
  const Eigen::Vector3d semi(r * spec.aspect_x, r * spec.aspect_y, r);
  double extra_lipschitz = 0.0;
  switch (spec.shape) {
    case ShapeKind::kSphere:
      bounding_radius_ = r;
      break;
    case ShapeKind::kEllipsoid:
      bounding_radius_ = semi.maxCoeff();
      // The k0(k0-1)/k1 bound of an ellipsoid has a gradient up to the axis ratio.
      extra_lipschitz = semi.maxCoeff() / semi.minCoeff() - 1.0;
      break;
    case ShapeKind::kCylinder:
      bounding_radius_ = std::hypot(r, spec.length_mm / 2.0);
      break;
    case ShapeKind::kRoundedCube:
      bounding_radius_ = semi.norm();
      break;
    case ShapeKind::kBumpy: {
      Rng rng(hash_combine(spec.seed, 0xB0B0));
      bump_count_ = spec.bump_count;
      double worst = 0.0;
      for (int i = 0; i < bump_count_; ++i) {
        // Uniform direction on the sphere.
        const double zc = rng.uniform(-1.0, 1.0);
        const double phi = rng.uniform(0.0, 2.0 * std::numbers::pi);
        const double s = std::sqrt(std::max(0.0, 1.0 - zc * zc));
        bump_dir_[static_cast<std::size_t>(i)] = {s * std::cos(phi), s * std::sin(phi), zc};
        const double h = spec.bump_height_mm * rng.uniform(-0.5, 1.0);
        const double w = spec.bump_width_mm * rng.uniform(0.6, 1.4);
        bump_height_[static_cast<std::size_t>(i)] = h;
        // exp((cos(angle) - 1) R^2 / w^2) ~ exp(-(R angle)^2 / (2 w^2)): Gaussian of sigma w.
        bump_inv_width2_[static_cast<std::size_t>(i)] = r * r / (w * w);
        worst = std::max(worst, std::abs(h) * 0.61 / w);
      }
      // Base ellipsoid bound plus at most two overlapping bump slopes.
      extra_lipschitz = semi.maxCoeff() / semi.minCoeff() - 1.0 + 2.0 * worst;
      bounding_radius_ = semi.maxCoeff() + spec.bump_height_mm;
      break;
    }
    case ShapeKind::kScrewdriver: {
      const double n = spec.flute_count;
      const double slope = spec.flute_depth_mm * spec.flute_sharpness * n / 2.0 /
                           std::max(1.0, r - spec.flute_depth_mm);
      extra_lipschitz = std::sqrt(1.0 + slope * slope) - 1.0;
      bounding_radius_ = std::hypot(r, spec.length_mm / 2.0);
      break;
    }
  }
  if (spec.texture_height_mm > 0.0) {
    const double k = 2.0 * std::numbers::pi / spec.texture_period_mm;
    extra_lipschitz += spec.texture_height_mm * k / (2.0 * std::sqrt(3.0));
    bounding_radius_ += spec.texture_height_mm;
  }
  lipschitz_ = 1.0 + extra_lipschitz;
}

double Shape::base_sdf(const Eigen::Vector3d& p) const noexcept {
  const ObjectSpec& o = spec_;
  const double r = o.size_mm;
  switch (o.shape) {
    case ShapeKind::kSphere:
      return p.norm() - r;
    case ShapeKind::kEllipsoid:
    case ShapeKind::kBumpy: {
      const Eigen::Vector3d a(r * o.aspect_x, r * o.aspect_y, r);
      const double k0 = p.cwiseQuotient(a).norm();
      const double k1 = p.cwiseQuotient(a.cwiseProduct(a)).norm();
      double d = k1 > 1e-12 ? k0 * (k0 - 1.0) / k1 : -a.minCoeff();
      if (o.shape == ShapeKind::kBumpy && bump_count_ > 0) {
        const double rho = p.norm();
        if (rho > 1e-9) {
          const Eigen::Vector3d n = p / rho;
          double lift = 0.0;
          for (int i = 0; i < bump_count_; ++i) {
            const auto k = static_cast<std::size_t>(i);
            const double c = n.dot(bump_dir_[k]);
            lift += bump_height_[k] * std::exp((c - 1.0) * bump_inv_width2_[k]);
          }
          d -= lift;
        }
      }
      return d;
    }
    case ShapeKind::kCylinder:
    case ShapeKind::kScrewdriver: {
      const double rho = std::hypot(p.x(), p.z());
      double radius = r;
      if (o.shape == ShapeKind::kScrewdriver && o.flute_count > 0) {
        // Lobe crest at angle 0 (facing +z); flute bottoms between lobes.
        const double phi = std::atan2(p.x(), p.z());
        const double s = 0.5 * (1.0 - std::cos(o.flute_count * phi));
        radius = r - o.flute_depth_mm * std::pow(s, o.flute_sharpness);
      }
      const double e = o.edge_radius_mm;
      const double dx = rho - (radius - e);
      const double dy = std::abs(p.y()) - (o.length_mm / 2.0 - e);
      const double outside = std::hypot(std::max(dx, 0.0), std::max(dy, 0.0));
      return outside + std::min(std::max(dx, dy), 0.0) - e;
    }
    case ShapeKind::kRoundedCube: {
      const Eigen::Vector3d b(r * o.aspect_x, r * o.aspect_y, r);
      const double e = o.edge_radius_mm;
      const Eigen::Vector3d q = p.cwiseAbs() - (b - Eigen::Vector3d::Constant(e));
      return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0) - e;
    }
  }
  return p.norm() - r;
}

double Shape::sdf(const Eigen::Vector3d& p) const noexcept {
  double d = base_sdf(p);
  if (spec_.texture_height_mm > 0.0) {
    const double k = 2.0 * std::numbers::pi / spec_.texture_period_mm;
    const double t = (std::cos(k * p.x()) + std::cos(k * p.y()) + std::cos(k * p.z())) / 3.0;
    d -= 0.5 * spec_.texture_height_mm * t;
  }
  return d;
}

}  // namespace tacse3::sim
