// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: natural Helmholtz-Hodge decomposition w = d + r + k of the grid flow, Eq. (nhhd).
#include "tacse3/dsp/nhhd.hpp"

#include <cmath>
#include <cstring>
#include <numbers>
#include <utility>

#include "tacse3/dsp/fixed.hpp"

namespace tacse3::dsp {
namespace {

constexpr int kS0 = kNhhdLevelNx[0] + 2;  // fine stride (ring included)
constexpr int kGridOriginX = kNhhdPadLeft + 1;
constexpr int kGridOriginY = kNhhdPadTop + 1;
constexpr int kSourceShift = kFieldFrac - Nhhd::kPotentialFrac + 1;  // Q16 diff pair -> Q12, /2
constexpr int kOutputScale = 1 << (kFieldFrac - Nhhd::kPotentialFrac - 1);  // Q12 diff -> Q16, /2

constexpr std::size_t fine_index(int gx, int gy) noexcept {
  return static_cast<std::size_t>((gy + kGridOriginY) * kS0 + gx + kGridOriginX);
}

constexpr std::int32_t clamp_to(std::int32_t v, std::int32_t limit) noexcept {
  return v > limit ? limit : (v < -limit ? -limit : v);
}
constexpr std::int32_t clamp_to(std::int64_t v, std::int32_t limit) noexcept {
  return v > limit ? limit : (v < -limit ? -limit : static_cast<std::int32_t>(v));
}

// Twice the derivative of f along one axis at point p, from valid neighbours only (Q16 units):
// central (f[+1] - f[-1]) when both neighbours are valid, 2 * one-sided when one is, else 0.
// |result| <= 2^24 for |f| <= 2^22.
std::int32_t twice_derivative(const std::int32_t* f, const std::uint8_t* valid, std::size_t p,
                              std::size_t step, bool has_prev, bool has_next) noexcept {
  const bool prev = has_prev && valid[p - step] != 0;
  const bool next = has_next && valid[p + step] != 0;
  if (prev && next) return f[p + step] - f[p - step];
  if (next) return 2 * (f[p + step] - f[p]);
  if (prev) return 2 * (f[p] - f[p - step]);
  return 0;
}

// Four int32 lanes as a GCC generic vector: SSE2 on x86-64, NEON on aarch64, plain scalar code
// where the target has no SIMD (armhf without NEON). Loads/stores go through memcpy (unaligned).
using V4 = std::int32_t __attribute__((vector_size(16)));
inline V4 load4(const std::int32_t* p) noexcept {
  V4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void store4(std::int32_t* p, V4 v) noexcept {
  std::memcpy(p, &v, sizeof v);
}
inline V4 splat4(std::int32_t a) noexcept {
  return V4{a, a, a, a};
}

inline V4 clamp4(V4 v, V4 lo, V4 hi) noexcept {
  v = v > hi ? hi : v;
  return v < lo ? lo : v;
}

// One Jacobi sweep of lap(u) = F on the interior of an (NX+2) x (NY+2) level (h^2 folded into F):
//   t = (u_W + u_E + u_N + u_S - F) / 4,   u' = t (plain) or u + 3/4 (t - u) (damped)
// Bounds (B = 2^26, |F| <= 2^26, |u| < 2^27.3 on input): |sum - F| < 2^29.4, |3 (t - u)| < 2^30,
// u' saturated to +-B when kClamp.
// Rows are processed 4 points at a time; when NX is not a multiple of 4 the last group is aligned
// to the row end and overlaps the previous one, which is harmless because Jacobi reads only `u`
// and writes only `out`. The level size is a template parameter so addressing is constant.
template <int NX, int NY, bool kDamped, bool kClamp>
void jacobi_sweep(const std::int32_t* __restrict u, const std::int32_t* __restrict f,
                  std::int32_t* __restrict out) noexcept {
  static_assert(NX >= 4);
  constexpr int s = NX + 2;
  const V4 hi = splat4(Nhhd::kPotentialLimit);
  const V4 lo = -hi;
  const V4 two = splat4(2);
  const auto group = [&](const std::int32_t* a, const std::int32_t* fr, std::int32_t* o) {
    const V4 c = load4(a);
    const V4 sum = load4(a - 1) + load4(a + 1) + load4(a - s) + load4(a + s);
    const V4 t = (sum - load4(fr) + two) >> 2;
    const V4 v = kDamped ? c + ((3 * (t - c) + two) >> 2) : t;
    store4(o, kClamp ? clamp4(v, lo, hi) : v);
  };
  for (int j = 1; j <= NY; ++j) {
    const std::int32_t* a = u + j * s;
    const std::int32_t* fr = f + j * s;
    std::int32_t* o = out + j * s;
    int i = 1;
    for (; i + 3 <= NX; i += 4) group(a + i, fr + i, o + i);
    if constexpr (NX % 4 != 0) group(a + NX - 3, fr + NX - 3, o + NX - 3);
  }
}

// Residual R = F - (sum of 4 neighbours - 4u) on the interior (|R| < 2^30), same row scheme.
template <int NX, int NY>
void residual(const std::int32_t* __restrict u, const std::int32_t* __restrict f,
              std::int32_t* __restrict res) noexcept {
  constexpr int s = NX + 2;
  const auto group = [&](const std::int32_t* a, const std::int32_t* fr, std::int32_t* o) {
    const V4 lap = load4(a - 1) + load4(a + 1) + load4(a - s) + load4(a + s) - 4 * load4(a);
    store4(o, load4(fr) - lap);
  };
  for (int j = 1; j <= NY; ++j) {
    const std::int32_t* a = u + j * s;
    const std::int32_t* fr = f + j * s;
    std::int32_t* o = res + j * s;
    int i = 1;
    for (; i + 3 <= NX; i += 4) group(a + i, fr + i, o + i);
    if constexpr (NX % 4 != 0) group(a + NX - 3, fr + NX - 3, o + NX - 3);
  }
}

template <int L>
constexpr int kNx = kNhhdLevelNx[L];
template <int L>
constexpr int kNy = kNhhdLevelNy[L];

// Damped sweeps saturate only in the last sweep of a block (see Nhhd::sweeps); plain sweeps
// (coarsest level, any number in a row) saturate every time.
void sweep_level(int level, bool damped, bool clamp, const std::int32_t* u, const std::int32_t* f,
                 std::int32_t* out) noexcept {
  if (!damped) {
    switch (level) {
      case 0:
        return jacobi_sweep<kNx<0>, kNy<0>, false, true>(u, f, out);
      case 1:
        return jacobi_sweep<kNx<1>, kNy<1>, false, true>(u, f, out);
      case 2:
        return jacobi_sweep<kNx<2>, kNy<2>, false, true>(u, f, out);
      default:
        return jacobi_sweep<kNx<3>, kNy<3>, false, true>(u, f, out);
    }
  }
  switch (level * 2 + (clamp ? 1 : 0)) {
    case 0:
      return jacobi_sweep<kNx<0>, kNy<0>, true, false>(u, f, out);
    case 1:
      return jacobi_sweep<kNx<0>, kNy<0>, true, true>(u, f, out);
    case 2:
      return jacobi_sweep<kNx<1>, kNy<1>, true, false>(u, f, out);
    case 3:
      return jacobi_sweep<kNx<1>, kNy<1>, true, true>(u, f, out);
    case 4:
      return jacobi_sweep<kNx<2>, kNy<2>, true, false>(u, f, out);
    case 5:
      return jacobi_sweep<kNx<2>, kNy<2>, true, true>(u, f, out);
    case 6:
      return jacobi_sweep<kNx<3>, kNy<3>, true, false>(u, f, out);
    default:
      return jacobi_sweep<kNx<3>, kNy<3>, true, true>(u, f, out);
  }
}

void residual_level(int level, const std::int32_t* u, const std::int32_t* f,
                    std::int32_t* res) noexcept {
  switch (level) {
    case 0:
      return residual<kNx<0>, kNy<0>>(u, f, res);
    case 1:
      return residual<kNx<1>, kNy<1>>(u, f, res);
    case 2:
      return residual<kNx<2>, kNy<2>>(u, f, res);
    default:
      return residual<kNx<3>, kNy<3>>(u, f, res);
  }
}

}  // namespace

Nhhd::Nhhd() noexcept {
  (void)configure(NhhdConfig{});
  reset();
  // Ring points of the fine level (corners included; the 5-point stencil never reads them).
  int n = 0;
  const auto add = [&](int i, int j) {
    ring_index_[static_cast<std::size_t>(n)] = j * kS0 + i;
    // Position relative to the multipole centre (the grid centre), in cells.
    const double x = (i - kGridOriginX) - kNhhdCentreX;
    const double y = (j - kGridOriginY) - kNhhdCentreY;
    const double r2 = x * x + y * y;
    const double pi = std::numbers::pi;
    // Free-space potential of the sources, phi(z) = (1/2pi) [M0 ln|z| - Re(M1/z) - Re(M2/z^2)/2],
    // with the moments taken in doubled coordinates (zeta2 = 2 zeta, odd integers), so
    // M1 = M1'/2 and M2 = M2'/4 are folded into the coefficients.
    const double c[kMoments] = {
        std::log(r2) / (4.0 * pi),                 // M0 * ln|z| / 2pi
        -x / (4.0 * pi * r2),                      // Re M1'
        -y / (4.0 * pi * r2),                      // Im M1'
        -(x * x - y * y) / (16.0 * pi * r2 * r2),  // Re M2'
        -(2.0 * x * y) / (16.0 * pi * r2 * r2),    // Im M2'
    };
    for (int t = 0; t < kMoments; ++t) {
      ring_coeff_[static_cast<std::size_t>(n)][static_cast<std::size_t>(t)] =
          std::llround(std::ldexp(c[t], 32));
    }
    ++n;
  };
  const int nx = kNhhdLevelNx[0];
  const int ny = kNhhdLevelNy[0];
  for (int i = 0; i <= nx + 1; ++i) {
    add(i, 0);
    add(i, ny + 1);
  }
  for (int j = 1; j <= ny; ++j) {
    add(0, j);
    add(nx + 1, j);
  }
}

Status Nhhd::configure(const NhhdConfig& config) noexcept {
  if (config.cycles < 0 || config.cycles > 64) return Status::kBadArgument;
  if (config.levels < 1 || config.levels > kNhhdMaxLevels) return Status::kBadArgument;
  if (config.pre_sweeps < 0 || config.pre_sweeps > 8) return Status::kBadArgument;
  if (config.post_sweeps < 0 || config.post_sweeps > 8) return Status::kBadArgument;
  if (config.coarsest_sweeps < 1 || config.coarsest_sweeps > 4096) return Status::kBadArgument;
  if (config.far_boundary != NhhdFarBoundary::kMultipole &&
      config.far_boundary != NhhdFarBoundary::kZero) {
    return Status::kBadArgument;
  }
  config_ = config;
  return Status::kOk;
}

void Nhhd::reset() noexcept {
  for (Potential* p : {&phi_, &psi_}) {
    p->buf[0].fill(0);
    p->buf[1].fill(0);
    p->rhs.fill(0);
    p->cur.fill(0);
  }
}

std::int32_t Nhhd::phi(int gx, int gy) const noexcept {
  if (gx < 0 || gy < 0 || gx >= kGridWidth || gy >= kGridHeight) return 0;
  return phi_.buf[phi_.cur[0]][fine_index(gx, gy)];
}
std::int32_t Nhhd::psi(int gx, int gy) const noexcept {
  if (gx < 0 || gy < 0 || gx >= kGridWidth || gy >= kGridHeight) return 0;
  return psi_.buf[psi_.cur[0]][fine_index(gx, gy)];
}
std::int32_t Nhhd::phi_padded(int i, int j) const noexcept {
  if (i < 0 || j < 0 || i >= kS0 || j > kNhhdLevelNy[0] + 1) return 0;
  return phi_.buf[phi_.cur[0]][static_cast<std::size_t>(j * kS0 + i)];
}
std::int32_t Nhhd::psi_padded(int i, int j) const noexcept {
  if (i < 0 || j < 0 || i >= kS0 || j > kNhhdLevelNy[0] + 1) return 0;
  return psi_.buf[psi_.cur[0]][static_cast<std::size_t>(j * kS0 + i)];
}

void Nhhd::set_ring(Potential& p, const std::array<std::int64_t, kMoments>& moments) noexcept {
  for (int n = 0; n < kRing; ++n) {
    std::int32_t v = 0;
    if (config_.far_boundary == NhhdFarBoundary::kMultipole) {
      // |M0 c0| < 2^60.3, the four other products < 2^58.6 each: the sum stays < 2^62.
      std::int64_t acc = 0;
      for (int t = 0; t < kMoments; ++t) {
        acc += moments[static_cast<std::size_t>(t)] *
               ring_coeff_[static_cast<std::size_t>(n)][static_cast<std::size_t>(t)];
      }
      v = clamp_to(rshift_round(acc, 32), kPotentialLimit);
    }
    const std::size_t idx = static_cast<std::size_t>(ring_index_[static_cast<std::size_t>(n)]);
    p.buf[0][idx] = v;
    p.buf[1][idx] = v;
  }
}

void Nhhd::sweeps(Potential& p, int level, int count, bool damped) noexcept {
  const std::size_t off = static_cast<std::size_t>(level_offset(level));
  std::uint8_t& cur = p.cur[static_cast<std::size_t>(level)];
  for (int n = 0; n < count; ++n) {
    // Saturation bound: a block starts from |u| <= B; a damped sweep grows |u| by at most
    // 3/4 |F| / 4 <= 3 * 2^22, so after 7 unsaturated sweeps |u| < 2^27.3 and the 8th (saturating)
    // sweep still keeps every int32 intermediate below 2^30.
    sweep_level(level, damped, n + 1 == count, p.buf[cur].data() + off, p.rhs.data() + off,
                p.buf[cur ^ 1].data() + off);
    cur ^= 1;
  }
}

void Nhhd::restrict_residual(Potential& p, int level) noexcept {
  const std::size_t l = static_cast<std::size_t>(level);
  const int nx = kNhhdLevelNx[l];
  const int s = nx + 2;
  const std::size_t off = static_cast<std::size_t>(level_offset(level));
  const std::int32_t* u = p.buf[p.cur[l]].data() + off;
  const std::int32_t* f = p.rhs.data() + off;
  // The free buffer's interior holds the residual R = F - (sum of 4 - 4u); its ring is untouched.
  std::int32_t* res = p.buf[p.cur[l] ^ 1].data() + off;
  residual_level(level, u, f, res);
  // Full weighting onto level l+1: F_{l+1} = h_{l+1}^2 FW(r) = 4 FW(R) = (sum w R) / 4.
  const std::size_t lc = l + 1;
  const int cnx = kNhhdLevelNx[lc];
  const int cny = kNhhdLevelNy[lc];
  const int cs = cnx + 2;
  const std::size_t coff = static_cast<std::size_t>(level_offset(level + 1));
  std::int32_t* cf = p.rhs.data() + coff;
  std::int32_t* cu = p.buf[p.cur[lc]].data() + coff;
  for (int jc = 1; jc <= cny; ++jc) {
    for (int ic = 1; ic <= cnx; ++ic) {
      const int q = 2 * jc * s + 2 * ic;
      const std::int64_t sum =
          4 * static_cast<std::int64_t>(res[q]) +
          2 * (static_cast<std::int64_t>(res[q - 1]) + res[q + 1] + res[q - s] + res[q + s]) +
          (static_cast<std::int64_t>(res[q - s - 1]) + res[q - s + 1] + res[q + s - 1] +
           res[q + s + 1]);
      cf[jc * cs + ic] = clamp_to(rshift_round(sum, 2), kRhsLimit);
      cu[jc * cs + ic] = 0;  // the correction starts from 0; the ring is 0 on coarse levels
    }
  }
}

void Nhhd::prolong_add(Potential& p, int level) noexcept {
  const std::size_t l = static_cast<std::size_t>(level);
  const int nx = kNhhdLevelNx[l];
  const int ny = kNhhdLevelNy[l];
  const int s = nx + 2;
  const int cnx = kNhhdLevelNx[l + 1];
  const int cs = cnx + 2;
  std::int32_t* u = p.buf[p.cur[l]].data() + level_offset(level);
  const std::int32_t* e = p.buf[p.cur[l + 1]].data() + level_offset(level + 1);
  // Bilinear interpolation, done as twice the column-interpolated coarse row (exact sums), then
  //   even i: (2e + 1) >> 1 = e (or the vertical mean),  odd i: (sum of two + 2) >> 2,
  // which rounds exactly like the 1-, 2- and 4-point means written out. The interpolated fine row
  // is built in `corr` (scalar), then added and saturated 4 points at a time.
  std::array<std::int32_t, kNhhdLevelNx[1] + 2 + 4> row{};
  std::array<std::int32_t, kNhhdLevelNx[0] + 2 + 8> corr{};
  const V4 hi = splat4(kPotentialLimit);
  const V4 lo = -hi;
  const V4 one = splat4(1);
  const V4 two = splat4(2);
  for (int j = 1; j <= ny; ++j) {
    const std::int32_t* c0 = e + (j >> 1) * cs;
    const std::int32_t* c1 = (j & 1) != 0 ? c0 + cs : c0;
    for (int ic = 0; ic <= cnx + 1; ++ic) row[static_cast<std::size_t>(ic)] = c0[ic] + c1[ic];
    int ic = 0;
    for (; ic + 4 <= cnx + 1; ic += 4) {
      const V4 a = load4(row.data() + ic);
      const V4 b = load4(row.data() + ic + 1);
      const V4 even = (a + one) >> 1;
      const V4 odd = (a + b + two) >> 2;  // |.| <= 2^27
      store4(corr.data() + 2 * ic, __builtin_shuffle(even, odd, V4{0, 4, 1, 5}));
      store4(corr.data() + 2 * ic + 4, __builtin_shuffle(even, odd, V4{2, 6, 3, 7}));
    }
    for (; ic <= cnx; ++ic) {
      const std::size_t c = static_cast<std::size_t>(ic);
      corr[2 * c] = (row[c] + 1) >> 1;
      corr[2 * c + 1] = (row[c] + row[c + 1] + 2) >> 2;
    }
    std::int32_t* ur = u + j * s;
    int i = 1;
    for (; i + 3 <= nx; i += 4)
      store4(ur + i, clamp4(load4(ur + i) + load4(corr.data() + i), lo, hi));
    for (; i <= nx; ++i)
      ur[i] = clamp_to(ur[i] + corr[static_cast<std::size_t>(i)], kPotentialLimit);
  }
}

void Nhhd::solve(Potential& p) noexcept {
  const int levels = config_.levels;
  for (int c = 0; c < config_.cycles; ++c) {
    if (levels == 1) {
      sweeps(p, 0, config_.coarsest_sweeps, false);
      continue;
    }
    for (int l = 0; l + 1 < levels; ++l) {
      sweeps(p, l, config_.pre_sweeps, true);
      restrict_residual(p, l);
    }
    sweeps(p, levels - 1, config_.coarsest_sweeps, false);
    for (int l = levels - 2; l >= 0; --l) {
      prolong_add(p, l);
      sweeps(p, l, config_.post_sweeps, true);
    }
  }
}

void Nhhd::decompose(const VectorField& w, const GridMask& valid, VectorField& d, VectorField& r,
                     VectorField& k) noexcept {
  for (std::size_t q = 0; q < kGridCount; ++q) {
    wx_[q] = clamp_to(w.x.v[q], kInputLimit);
    wy_[q] = clamp_to(w.y.v[q], kInputLimit);
  }

  // Sources (Q12) on the grid part of the fine level and their multipole moments. The padding
  // rhs stays 0 (set by reset(), never written). Moments are taken in doubled centred coordinates
  // (zx = 2 gx - 39, zy = 2 gy - 29): per row the sums of s, s zx, s zx^2 (int64), combined with
  // zy at the row end: M0 = sum s, M1 = sum s (zx + i zy), M2 = sum s (zx + i zy)^2.
  std::array<std::int64_t, kMoments> mdiv{};
  std::array<std::int64_t, kMoments> mcurl{};
  std::int32_t* fdiv = phi_.rhs.data();
  std::int32_t* fcurl = psi_.rhs.data();
  const std::uint8_t* m = valid.v.data();
  constexpr std::size_t kRow = kGridWidth;
  for (int gy = 0; gy < kGridHeight; ++gy) {
    std::int64_t rd[3] = {0, 0, 0};
    std::int64_t rc[3] = {0, 0, 0};
    const bool north = gy > 0;
    const bool south = gy + 1 < kGridHeight;
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const std::size_t p = static_cast<std::size_t>(gy * kGridWidth + gx);
      const std::size_t fi = fine_index(gx, gy);
      std::int32_t sd = 0;
      std::int32_t sc = 0;
      if (m[p] != 0) {
        const bool west = gx > 0;
        const bool east = gx + 1 < kGridWidth;
        std::int32_t dxx;
        std::int32_t dxy;
        std::int32_t dyx;
        std::int32_t dyy;
        if (west && east && north && south &&
            (m[p - 1] & m[p + 1] & m[p - kRow] & m[p + kRow]) != 0) {
          dxx = wx_[p + 1] - wx_[p - 1];  // the common case: all four neighbours valid
          dxy = wy_[p + 1] - wy_[p - 1];
          dyx = wx_[p + kRow] - wx_[p - kRow];
          dyy = wy_[p + kRow] - wy_[p - kRow];
        } else {
          dxx = twice_derivative(wx_.data(), m, p, 1, west, east);
          dxy = twice_derivative(wy_.data(), m, p, 1, west, east);
          dyx = twice_derivative(wx_.data(), m, p, kRow, north, south);
          dyy = twice_derivative(wy_.data(), m, p, kRow, north, south);
        }
        sd = static_cast<std::int32_t>(rshift_round(dxx + dyy, kSourceShift));
        sc = static_cast<std::int32_t>(rshift_round(dxy - dyx, kSourceShift));
        const std::int64_t zx = 2 * gx - (kGridWidth - 1);
        rd[0] += sd;
        rd[1] += sd * zx;
        rd[2] += sd * zx * zx;
        rc[0] += sc;
        rc[1] += sc * zx;
        rc[2] += sc * zx * zx;
      }
      fdiv[fi] = sd;
      fcurl[fi] = sc;
    }
    const std::int64_t zy = 2 * gy - (kGridHeight - 1);
    for (auto [mm, rr] : {std::pair{&mdiv, rd}, std::pair{&mcurl, rc}}) {
      (*mm)[0] += rr[0];
      (*mm)[1] += rr[1];
      (*mm)[2] += zy * rr[0];
      (*mm)[3] += rr[2] - zy * zy * rr[0];
      (*mm)[4] += 2 * zy * rr[1];
    }
  }

  set_ring(phi_, mdiv);
  set_ring(psi_, mcurl);
  solve(phi_);
  solve(psi_);

  // d = grad phi, r = (-Dy psi, Dx psi): exact integer differences, Q12 -> Q16 (x 16 / 2).
  const std::int32_t* ph = phi_.buf[phi_.cur[0]].data();
  const std::int32_t* ps = psi_.buf[psi_.cur[0]].data();
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const std::size_t p = static_cast<std::size_t>(gy * kGridWidth + gx);
      const std::size_t i = fine_index(gx, gy);
      const std::int32_t dx = (ph[i + 1] - ph[i - 1]) * kOutputScale;
      const std::int32_t dy = (ph[i + kS0] - ph[i - kS0]) * kOutputScale;
      const std::int32_t rx = -(ps[i + kS0] - ps[i - kS0]) * kOutputScale;
      const std::int32_t ry = (ps[i + 1] - ps[i - 1]) * kOutputScale;
      d.x.v[p] = dx;
      d.y.v[p] = dy;
      r.x.v[p] = rx;
      r.y.v[p] = ry;
      k.x.v[p] = sat32(static_cast<std::int64_t>(w.x.v[p]) - dx - rx);
      k.y.v[p] = sat32(static_cast<std::int64_t>(w.y.v[p]) - dy - ry);
    }
  }
}

}  // namespace tacse3::dsp
