// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: natural Helmholtz-Hodge decomposition w = d + r + k of the grid flow, Eq. (nhhd).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// Paper Eq. (nhhd): w = d + r + k, d curl-free, r divergence-free, k harmonic. With grid
// coordinates x (right), y (down), unit spacing = 1 grid cell, and central differences Dx, Dy:
//
//   div w  = Dx wx + Dy wy,          curl w = Dx wy - Dy wx
//   lap phi = div w,   d = grad phi = (Dx phi, Dy phi)
//   lap psi = curl w,  r = grad-perp psi = (-Dy psi, Dx psi)   (so curl r = lap psi = curl w)
//   k = w - d - r                                               (exactly, in integers)
//
// "Natural" (Bhatia et al.): phi and psi are the FREE-SPACE potentials of the sources inside the
// grid, phi = G * div w, psi = G * curl w with G = ln(r) / 2 pi; k then carries what the inside
// sources do not explain (uniform shear, pure strain, the influence of the outside). Two choices
// make this so on a finite grid:
//  1. Sources only from inside: div/curl use differences between VALID grid points only (central
//     where both neighbours are valid, one-sided where one is, 0 where none is; 0 at invalid
//     points). The jump from w to "nothing" at the grid edge is NOT a source. (Treating the outside
//     as w = 0 would give the free-space HHD of the zero-extended field, whose harmonic part is
//     identically 0, so a uniform shear would be split into d + r.)
//  2. A padded domain: the Poisson problems live on the grid plus kNhhdPad* cells of padding with
//     no sources; on the ring just outside the padding the potentials are set to the free-space
//     potential of the current sources, truncated after the quadrupole term (multipole boundary,
//     default), or to 0 (NhhdFarBoundary::kZero). The multipole ring carries the far field the
//     padding cuts off, so a padding of 3-5 cells is enough; a zero ring would need several
//     times that padding for the same error (docs/dsp/fields.md).
//
// Solver (fixed cost per call): each Poisson problem is solved by `cycles` V-cycles on the padded
// 47 x 39 grid (coarse levels 23 x 19, 11 x 9, 5 x 4), warm-started from the previous call's
// potentials. Smoother: damped Jacobi, omega = 3/4, `pre_sweeps` before and `post_sweeps` after the
// coarse-grid correction; `coarsest_sweeps` plain Jacobi sweeps on the coarsest level. Restriction
// is full weighting, prolongation bilinear. levels = 1 turns this into plain warm-started Jacobi on
// the padded grid (`coarsest_sweeps` sweeps per cycle). The coarse levels only accelerate the
// smooth error modes that Jacobi alone would need ~400 sweeps per e-fold to remove on this grid.
//
// Scaling and overflow (all integer; B = 2^26):
//  - input w: Q16 working px, any int32. Clamped to +-2^22 (+-64 working px, 2/5 of the image
//    width; no real gel displacement comes near) for the sources only; k uses the unclamped w.
//  - sources div w, curl w: Q12 px/cell, int32, |.| <= 2^19. One rounding (half-up) per value.
//  - potentials phi, psi (all levels, incl. corrections): Q12 px*cell in int32, saturated to +-B
//    (+-16384 px*cell; real fields stay below ~10^3) at the end of every block of damped sweeps,
//    after every plain (coarsest-level) sweep and after every prolongation.
//  - level right-hand sides F_l = h_l^2 f_l (Q12, h_l = 2^l cells), saturated to +-2^26.
//  - Jacobi: sum of 4 neighbours - F in int32 (< 2^29.4), >> 2 with round half-up; damping
//    u + round((3 (t - u)) / 4) with |3 (t - u)| < 2^30 (inside a block |u| grows by at most
//    3 * 2^22 per sweep, so 8 sweeps stay < 2^27.3 before the final saturation).
//  - residual in int32 (<= 2^30), restriction sums in int64, then / 4 rounded, saturated.
//  - multipole ring: source moments in int64 (|.| < 2^41), coefficients Q32 int64, products and
//    their sum < 2^62, result >> 32 rounded, saturated to +-B.
//  - outputs d, r: (u[i+1] - u[i-1]) * 8 = Q16, exact (no rounding), |.| <= 2^30.
//  - k = w - d - r in int64, saturated to int32: the identity w = d + r + k is bit-exact whenever
//    the difference fits int32, which holds for every input inside the +-2^22 clamp (k saturates
//    only for garbage near the int32 limits, e.g. a full-scale checkerboard).
// Exact discrete properties at any iteration count (not only at convergence): with the same
// central differences, curl d == 0 and div r == 0 exactly (bit-exact in Q16) at every grid point
// whose four neighbours are inside the grid, because d and r are exact differences of one integer
// potential and central differences commute.
enum class NhhdFarBoundary : std::uint8_t {
  kMultipole = 0,  // free-space potential of the sources (monopole, dipole, quadrupole)
  kZero = 1,       // Dirichlet 0 on the ring (needs much more padding for the same accuracy)
};

struct NhhdConfig {
  int cycles = 1;            // V-cycles per call and potential, [0, 64]
  int levels = 4;            // [1, kNhhdMaxLevels]; 1 = plain Jacobi on the padded grid
  int pre_sweeps = 2;        // damped Jacobi sweeps before restriction, [0, 8]
  int post_sweeps = 2;       // damped Jacobi sweeps after prolongation, [0, 8]
  int coarsest_sweeps = 24;  // plain Jacobi sweeps on the coarsest level, [1, 4096]
  NhhdFarBoundary far_boundary = NhhdFarBoundary::kMultipole;
};

// Padded-domain geometry, shared with the double reference (dsp_ref/nhhd_ref.hpp).
inline constexpr int kNhhdPadLeft = 3;
inline constexpr int kNhhdPadRight = 4;
inline constexpr int kNhhdPadTop = 4;
inline constexpr int kNhhdPadBottom = 5;
inline constexpr int kNhhdMaxLevels = 4;
// Unknowns per level (the ring of fixed values lies outside); level l+1 has (n_l - 1) / 2 so that
// coarse point I sits on fine point 2I (vertex-centred coarsening, ring on ring).
inline constexpr std::array<int, kNhhdMaxLevels> kNhhdLevelNx{47, 23, 11, 5};
inline constexpr std::array<int, kNhhdMaxLevels> kNhhdLevelNy{39, 19, 9, 4};
// Multipole centre: the grid centre, in grid-cell coordinates.
inline constexpr double kNhhdCentreX = 0.5 * (kGridWidth - 1);
inline constexpr double kNhhdCentreY = 0.5 * (kGridHeight - 1);

static_assert(kNhhdLevelNx[0] == kGridWidth + kNhhdPadLeft + kNhhdPadRight);
static_assert(kNhhdLevelNy[0] == kGridHeight + kNhhdPadTop + kNhhdPadBottom);
static_assert(kNhhdLevelNx[1] * 2 + 1 == kNhhdLevelNx[0] &&
              kNhhdLevelNy[1] * 2 + 1 == kNhhdLevelNy[0]);
static_assert(kNhhdLevelNx[2] * 2 + 1 == kNhhdLevelNx[1] &&
              kNhhdLevelNy[2] * 2 + 1 == kNhhdLevelNy[1]);
static_assert(kNhhdLevelNx[3] * 2 + 1 == kNhhdLevelNx[2] &&
              kNhhdLevelNy[3] * 2 + 1 == kNhhdLevelNy[2]);

namespace nhhd_detail {
// Storage of level l (ring included) and its offset in a buffer holding all levels.
constexpr int level_size(int l) noexcept {
  return (kNhhdLevelNx[static_cast<std::size_t>(l)] + 2) *
         (kNhhdLevelNy[static_cast<std::size_t>(l)] + 2);
}
constexpr int level_offset(int l) noexcept {
  int o = 0;
  for (int i = 0; i < l; ++i) o += level_size(i);
  return o;
}
}  // namespace nhhd_detail

class Nhhd {
 public:
  static constexpr int kPotentialFrac = 12;                               // Q12
  static constexpr std::int32_t kPotentialLimit = std::int32_t{1} << 26;  // B
  static constexpr std::int32_t kRhsLimit = std::int32_t{1} << 26;
  static constexpr std::int32_t kInputLimit = std::int32_t{1} << 22;  // Q16, 64 working px

  Nhhd() noexcept;  // default NhhdConfig, potentials 0

  // Validates and applies the configuration; potentials are kept (call reset() to clear them).
  Status configure(const NhhdConfig& config) noexcept;

  // Zeroes the warm-start potentials (on tare: the next decomposition starts from scratch).
  void reset() noexcept;

  // Decomposes w (Q16) into d, r, k (Q16). Runs the configured number of V-cycles for phi and psi
  // starting from the previous call's potentials. Outputs must not alias `w`.
  void decompose(const VectorField& w, const GridMask& valid, VectorField& d, VectorField& r,
                 VectorField& k) noexcept;

  const NhhdConfig& config() const noexcept { return config_; }
  // Potentials (Q12 px*cell) at a grid point, or at a padded-domain index (0..48, 0..40 with the
  // ring) via the *_padded accessors.
  std::int32_t phi(int gx, int gy) const noexcept;
  std::int32_t psi(int gx, int gy) const noexcept;
  std::int32_t phi_padded(int i, int j) const noexcept;
  std::int32_t psi_padded(int i, int j) const noexcept;

 private:
  static constexpr int level_offset(int l) noexcept { return nhhd_detail::level_offset(l); }
  static constexpr int kStorage = nhhd_detail::level_offset(kNhhdMaxLevels);
  static constexpr int kRing = 2 * (kNhhdLevelNx[0] + 2) + 2 * kNhhdLevelNy[0];
  static constexpr int kMoments = 5;  // M0, Re M1, Im M1, Re M2, Im M2

  // One potential: two Jacobi buffers and the right-hand side for every level.
  struct Potential {
    std::array<std::int32_t, kStorage> buf[2];
    std::array<std::int32_t, kStorage> rhs;
    std::array<std::uint8_t, kNhhdMaxLevels> cur;  // which buffer holds the current iterate
  };

  void solve(Potential& p) noexcept;
  void set_ring(Potential& p, const std::array<std::int64_t, kMoments>& moments) noexcept;
  void sweeps(Potential& p, int level, int count, bool damped) noexcept;
  void restrict_residual(Potential& p, int level) noexcept;
  void prolong_add(Potential& p, int level) noexcept;

  NhhdConfig config_{};
  Potential phi_{};
  Potential psi_{};
  // Ring geometry and multipole coefficients (Q32), computed once in the constructor.
  std::array<std::int32_t, kRing> ring_index_{};
  std::array<std::array<std::int64_t, kMoments>, kRing> ring_coeff_{};
  std::array<std::int32_t, kGridCount> wx_{};  // clamped input, Q16
  std::array<std::int32_t, kGridCount> wy_{};
};

}  // namespace tacse3::dsp
