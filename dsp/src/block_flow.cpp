// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: fixed-point pyramidal block flow with keyframe chaining (paper Eq. (dense_flow)).
//
// Per grid point p, Eq. (dense_flow) is solved for the translation u of an 8x8 window W(p):
//     u* = argmin_u sum_{s in W} [ I_t(s + u) - (1 + gamma) I_key(s) - beta ]^2
// with a local brightness gain gamma and offset beta per window, eliminated in closed form
// (zero-mean gradients and residuals, Schur complement for the gain): the match is insensitive
// to LED flicker, vignetting and contact shading that vary slowly across a window.
// Gauss-Newton with the keyframe (template) gradient (inverse compositional): the structure
// tensor, its inverse and all template statistics are fixed per keyframe; an iteration only
// samples the current image and accumulates the mismatch vector.
//
// Fixed-point formats (docs/dsp/flow.md has the full table with ranges and rounding):
//   I, T       U8.2 pyramid samples, 0..1020 (luma * 4)
//   g          gx, gy = T(x+1) - T(x-1): int16, |g| <= 1020 (2 * U8.2 per level px)
//   h          horizontal bilinear pass (32 - fx) a + fx b: int16 U8.7, 0..32640, exact
//   v          vertical pass h0 + (h1 - h0) fy / 32 (16-bit high multiply, floor): U8.7
//   r          v - 32 T: int16, |r| <= 32642 (U8.7; v may be 2 LSB below 0 after the floor)
//   S_gr, S_tr sum g r, sum T r over 64 px: int32, |.| <= 64 * 1020 * 32642 = 2130869760 < 2^31
//   S_r        sum r: int32, |S_r| <= 2088960
//   b64        64 S_gr - (sum g) S_r = 64 * sum (g - mean g) r: int64, |b64| < 2^38
//   bT         64 S_tr - (sum T) S_r - compensation: int64, |bT| < 2^39
//   C          64 sum g Txx - (sum g)(sum Txx) etc. (bilinear compensation): int64, < 2^35
//   q          gain coupling k / e, Q16, |q| <= 2^22
//   b_eff      b64 - q bT - compensation, saturated to +-2^39
//   H64        64 sum g g^T - G G^T - k k^T / e (zero-mean, gain eliminated): int64, < 2^33
//   H64^-1     block floating point per window: M * 2^-(shift+12), M int32 mantissas < 2^22
//   step       du = -(16 H64)^-1 b_eff in level px; Q16 = -(M b_eff) >> shift (product < 2^62)
//   u, D, out  Q16 px (int32), working px at level 0
#include "tacse3/dsp/block_flow.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "tacse3/dsp/fixed.hpp"

namespace tacse3::dsp {
namespace {

constexpr std::int32_t kOne = std::int32_t{1} << 16;  // 1.0 in Q16
constexpr std::int32_t kHalf = kOne / 2;
constexpr std::int64_t kN = kFlowWindowPixels;
// Window centre relative to its origin: (8 - 1) / 2 = 3.5 px.
constexpr std::int32_t kWindowCentreQ16 = (kFlowWindow - 1) * kHalf;
// Sub-pixel sampling resolution: positions are rounded to 1/32 px (Q5) before sampling; the
// Gauss-Newton step computed there is added to the rounded position, so the rounding only
// enters at second order (see docs/dsp/flow.md).
constexpr int kPosFrac = 5;
constexpr int kQ16ToPos = 16 - kPosFrac;
// Window origins are kept one pixel inside the image: every template pixel then has both
// neighbours (exact central differences), and a border window can move outwards by 1 px. A
// window may be pushed inwards by at most kMaxWindowOffset (level 0; 3 px for the outer ring).
constexpr int kWindowMargin = 1;
constexpr std::int32_t kMaxWindowOffsetQ16 = 7 * kHalf;       // 3.5 px
constexpr std::int32_t kMaxCoarseWindowOffsetQ16 = 4 * kOne;  // coarse levels only seed
// Bounds that keep the per-iteration products inside int64 (see the format table).
constexpr std::int64_t kMaxMismatch = std::int64_t{1} << 39;
constexpr std::int64_t kMaxMantissa = std::int64_t{1} << 22;
constexpr std::int64_t kMaxGainCoupling = std::int64_t{1} << 22;  // |k / e| <= 64
// Fixed-point passes refining the flow gradient J and the window-centre flows together
// (write_output()); 3 passes leave < 5 % of the first-pass J error.
constexpr int kJacobianPasses = 3;
// Pyramid slots: 0 and 1 alternate between keyframe and current frame; 2 keeps the tare frame.
constexpr std::size_t kTareSlot = 2;

int bit_length(std::uint64_t x) noexcept {
  return x == 0 ? 0 : 64 - __builtin_clzll(x);
}

// x * 2^-s with round-half-up for s > 0, exact left shift for s < 0 (caller keeps it in range).
std::int64_t scale_pow2(std::int64_t x, int s) noexcept {
  if (s >= 0) return rshift_round(x, s);
  return static_cast<std::int64_t>(static_cast<std::uint64_t>(x) << -s);
}

// Rounded division num / den for den > 0 (half away from zero).
std::int64_t div_round(std::int64_t num, std::int64_t den) noexcept {
  return num >= 0 ? (num + den / 2) / den : -((-num + den / 2) / den);
}

std::int32_t clamp_abs(std::int32_t v, std::int32_t limit) noexcept {
  return std::clamp(v, -limit, limit);
}

// Sums accumulated while sampling one window (see the format table at the top).
struct WindowSums {
  std::int32_t gr_x;
  std::int32_t gr_y;
  std::int32_t tr;
  std::int32_t r;
};

// The hot loop. (1) Bilinear sample of the current image at a constant sub-pixel offset (the
// displacement is constant over the window, so the weights are too), separably: a horizontal
// pass over the 9 source rows, h = (32 - fx) a + fx b (exact, <= 32 * 1020 = 32640, U8.7), then
// a vertical pass v = h0 + 2 * ((h1 - h0) * (fy << 10) >> 16) = h0 + (h1 - h0) fy / 32, whose
// product is a 16x16 -> high-16 multiply (pmulhw / sqdmulh class), floor-rounded (<= 2 LSB of
// U8.7, i.e. 1/64 luma); (2) the residual against the template; (3) the four mismatch sums as
// flat 64-long dot products over the packed template. Arithmetic is 16-bit with 32-bit sums,
// which g++ -O2 vectorises (pmullw/pmulhw/pmaddwd on x86-64 SSE2, NEON on aarch64).
//   cur: top-left sample of the 9x9 source block; fx, fy: Q5 fractions. `res` receives the 64
//   residuals r = v - 32 T (|r| <= 32642, int16).
// fy / 32 in Q15 (fy << 10) from a table: computed inline, g++ would fold the shift into the
// product and lose the 16-bit high-multiply form of the vertical pass.
constexpr std::array<std::int16_t, 32> make_fraction_q15() noexcept {
  std::array<std::int16_t, 32> a{};
  for (int f = 0; f < 32; ++f) a[static_cast<std::size_t>(f)] = static_cast<std::int16_t>(f << 10);
  return a;
}
constexpr auto kFractionQ15 = make_fraction_q15();

// Vertical half of the bilinear sample and the residual: v = h0 + 2 * ((h1 - h0) * wy >> 16)
// with wy = fy << 10 (fy / 32 in Q15), r = v - 32 T. A separate function with restrict
// pointers so that g++ maps the product to the 16-bit high multiply.
inline void vertical_residual(const std::int16_t* __restrict h, const std::int16_t* __restrict t,
                              std::int16_t wy, std::int16_t* __restrict res) noexcept {
  // Left uninitialised: every element is written before it is read, and zeroing it costs a
  // `rep stos` per iteration, a quarter of the window's time.
  alignas(16) std::array<std::int16_t, kFlowWindowPixels> hi;
  for (int k = 0; k < kFlowWindowPixels; ++k) {  // kept alone: the high-multiply pattern
    const auto d = static_cast<std::int16_t>(h[k + kFlowWindow] - h[k]);
    hi[static_cast<std::size_t>(k)] = static_cast<std::int16_t>((std::int32_t{d} * wy) >> 16);
  }
  for (int k = 0; k < kFlowWindowPixels; ++k) {
    res[k] = static_cast<std::int16_t>(h[k] + 2 * hi[static_cast<std::size_t>(k)] - (t[k] << 5));
  }
}

inline WindowSums sample_window(const std::uint16_t* __restrict cur, std::size_t stride,
                                const FlowWindowTemplate& tpl, int fx, int fy,
                                std::int16_t* __restrict res) noexcept {
  alignas(16) std::array<std::int16_t, (kFlowWindow + 1) * kFlowWindow> h;  // see `hi`
  const int wa = 32 - fx;
  const int wb = fx;
  for (int row = 0; row <= kFlowWindow; ++row) {
    const std::uint16_t* c = cur + static_cast<std::size_t>(row) * stride;
    std::int16_t* __restrict o = h.data() + row * kFlowWindow;
    for (int j = 0; j < kFlowWindow; ++j) {
      o[j] = static_cast<std::int16_t>(wa * c[j] + wb * c[j + 1]);
    }
  }
  const std::int16_t* __restrict t = tpl.t.data();
  vertical_residual(h.data(), t, kFractionQ15[static_cast<std::size_t>(fy)], res);
  const std::int16_t* __restrict gx = tpl.gx.data();
  const std::int16_t* __restrict gy = tpl.gy.data();
  std::int32_t sx = 0;
  std::int32_t sy = 0;
  std::int32_t st = 0;
  std::int32_t s1 = 0;
  for (int k = 0; k < kFlowWindowPixels; ++k) {
    sx += gx[k] * res[k];
    sy += gy[k] * res[k];
    st += t[k] * res[k];
    s1 += res[k];
  }
  return {sx, sy, st, s1};
}

// Residual energy in U8.3 units: sum (r >> 4)^2 <= 64 * 2040^2 < 2^28 (int32).
inline std::int32_t residual_energy(const std::int16_t* __restrict res) noexcept {
  std::int32_t s = 0;
  for (int k = 0; k < kFlowWindowPixels; ++k) {
    const auto e = static_cast<std::int16_t>(res[k] >> 4);
    s += e * e;
  }
  return s;
}

// Q16 reciprocals 1/d for the small integer window spacings used by the output correction.
constexpr int kMinSpacing = 3;
constexpr int kMaxSpacing = 32;
constexpr std::array<std::int32_t, kMaxSpacing + 1> make_reciprocals() noexcept {
  std::array<std::int32_t, kMaxSpacing + 1> r{};
  for (int d = 1; d <= kMaxSpacing; ++d) r[static_cast<std::size_t>(d)] = (kOne + d / 2) / d;
  return r;
}
constexpr auto kReciprocalQ16 = make_reciprocals();

// Column and row offsets of the 64 window samples from the window centre, doubled so they are
// integers: d = 2 (j - 3.5) in {-7, -5, ..., 7}.
constexpr std::array<std::int16_t, kFlowWindowPixels> make_offsets(bool rows) noexcept {
  std::array<std::int16_t, kFlowWindowPixels> d{};
  for (int k = 0; k < kFlowWindowPixels; ++k) {
    const int j = rows ? k / kFlowWindow : k % kFlowWindow;
    d[static_cast<std::size_t>(k)] = static_cast<std::int16_t>(2 * j - (kFlowWindow - 1));
  }
  return d;
}
constexpr auto kOffsetX = make_offsets(false);
constexpr auto kOffsetY = make_offsets(true);

// Raw first moments sum a b d of one window for d = kOffsetX or kOffsetY, as 16-bit products
// (a d fits int16: |.| <= 1020 * 7) summed in int32 (|.| <= 64 * 1020 * 7140 < 2^29).
struct MomentSums {
  std::int32_t gxgx, gxgy, gygy, tgx, tgy, gx, gy, t;
};
inline MomentSums moment_sums(const FlowWindowTemplate& tpl,
                              const std::int16_t* __restrict d) noexcept {
  const std::int16_t* __restrict gx = tpl.gx.data();
  const std::int16_t* __restrict gy = tpl.gy.data();
  const std::int16_t* __restrict t = tpl.t.data();
  MomentSums m{0, 0, 0, 0, 0, 0, 0, 0};
  for (int k = 0; k < kFlowWindowPixels; ++k) {
    const auto gxd = static_cast<std::int16_t>(gx[k] * d[k]);
    const auto gyd = static_cast<std::int16_t>(gy[k] * d[k]);
    const auto td = static_cast<std::int16_t>(t[k] * d[k]);
    m.gxgx += gxd * gx[k];
    m.gxgy += gxd * gy[k];
    m.gygy += gyd * gy[k];
    m.tgx += td * gx[k];
    m.tgy += td * gy[k];
    m.gx += gxd;
    m.gy += gyd;
    m.t += td;
  }
  return m;
}

// Measurement-point moments of a level-0 window (used by write_output()). For an affine flow
// u(s) = u(c) + J (s - c) over the window, the residual is r(s) = grad T(s) . (t - u(s)), and
// the zero-mean, gain-eliminated LK converges where sum g_eff r = 0, i.e. at
//   t = u(c) + P_x J(:, x) + P_y J(:, y),   P_k = H_eff^-1 sum g_eff g^T (s_k - c_k),
// with g_eff = (g - mean g) - q (T - mean T) and the RAW gradient g in the second factor (the
// mean gradient does not drop out of this term). Textured spots off the window centre pull the
// estimate towards them; P says by how much per unit strain.
//
// Scaling and overflow: with 64-scaled values (G = sum g, T = sum T over the window) and the
// doubled offsets d (sum d = 0), the moment sums come from the raw int32 sums of moment_sums()
// (no per-pixel int64 work):
//   A[r][c] = sum (64 g_r - G_r) 64 g_c d = 4096 sum g_r g_c d - 64 G_r sum g_c d   (< 2^42)
//   B[c]    = sum (64 T - T) 64 g_c d    = 4096 sum T g_c d - 64 T sum g_c d        (< 2^42)
//   M[r][c] = A[r][c] - q_r B[c]     (q Q16 <= 2^22; B pre-shifted by 8 bits: q B < 2^56)
// M is normalised to < 2^39 before the product with the < 2^22 inverse mantissas (< 2^62), then
// shifted to Q16: P = H64^-1 M / 128 = inv * M * 2^-(shift + 12 + 7) -> Q16: >> (shift + 3).
void measurement_moments(const FlowWindowTemplate& tpl, FlowWindowModel& m) noexcept {
  std::array<std::int64_t, 8> sum{};  // [k][row][col] of M_k, k = x, y
  const std::int64_t gx = m.gsum_x, gy = m.gsum_y, ts = m.tsum;
  for (int k = 0; k < 2; ++k) {
    const MomentSums r = moment_sums(tpl, k == 0 ? kOffsetX.data() : kOffsetY.data());
    const std::int64_t axx = 4096 * std::int64_t{r.gxgx} - 64 * gx * r.gx;
    const std::int64_t axy = 4096 * std::int64_t{r.gxgy} - 64 * gx * r.gy;
    const std::int64_t ayx = 4096 * std::int64_t{r.gxgy} - 64 * gy * r.gx;
    const std::int64_t ayy = 4096 * std::int64_t{r.gygy} - 64 * gy * r.gy;
    const std::int64_t bx = rshift_round(4096 * std::int64_t{r.tgx} - 64 * ts * r.gx, 8);
    const std::int64_t by = rshift_round(4096 * std::int64_t{r.tgy} - 64 * ts * r.gy, 8);
    std::int64_t* out = sum.data() + 4 * k;
    out[0] = axx - rshift_round(m.gain_qx * bx, 8);
    out[1] = axy - rshift_round(m.gain_qx * by, 8);
    out[2] = ayx - rshift_round(m.gain_qy * bx, 8);
    out[3] = ayy - rshift_round(m.gain_qy * by, 8);
  }
  std::uint64_t largest = 0;
  for (const std::int64_t v : sum) {
    largest = std::max(largest, static_cast<std::uint64_t>(v < 0 ? -v : v));
  }
  const int pre = std::max(0, bit_length(largest) - 39);
  for (std::int64_t& v : sum) v = rshift_round(v, pre);
  const int out_shift = m.shift + 3 - pre;
  const auto q16 = [&](std::int64_t v) { return sat32(scale_pow2(v, out_shift)); };
  for (int k = 0; k < 2; ++k) {
    const std::int64_t* s = sum.data() + 4 * k;  // [[s0 s1] [s2 s3]] = M_k
    auto& p = k == 0 ? m.moment_x : m.moment_y;
    p[0] = q16(m.inv_a * s[0] + m.inv_b * s[2]);
    p[1] = q16(m.inv_a * s[1] + m.inv_b * s[3]);
    p[2] = q16(m.inv_b * s[0] + m.inv_c * s[2]);
    p[3] = q16(m.inv_b * s[1] + m.inv_c * s[3]);
  }
}

// One packed template row: T, central differences gx, gy and second differences Txx, Tyy
// (|.| <= 2040, int16) from the keyframe row r0 and the rows above (ru) and below (rd).
inline void pack_row(const std::uint16_t* __restrict r0, const std::uint16_t* __restrict ru,
                     const std::uint16_t* __restrict rd, std::int16_t* __restrict t,
                     std::int16_t* __restrict gx, std::int16_t* __restrict gy,
                     std::int16_t* __restrict txx, std::int16_t* __restrict tyy) noexcept {
  for (int j = 0; j < kFlowWindow; ++j) {
    const int c = r0[j];
    t[j] = static_cast<std::int16_t>(c);
    gx[j] = static_cast<std::int16_t>(r0[j + 1] - r0[j - 1]);
    gy[j] = static_cast<std::int16_t>(rd[j] - ru[j]);
    txx[j] = static_cast<std::int16_t>(r0[j + 1] + r0[j - 1] - 2 * c);
    tyy[j] = static_cast<std::int16_t>(rd[j] + ru[j] - 2 * c);
  }
}

// Template statistics of one window: 16-bit products summed in int32. Scaling and overflow:
// |a b| <= 1020 * 2040 for every product, 64 of them < 2^27, so every sum is exact.
struct TemplateSums {
  std::int32_t gx, gy, t, gxgx, gxgy, gygy, tt, gxt, gyt;
  std::int32_t xx, yy, gx_xx, gy_xx, t_xx, gx_yy, gy_yy, t_yy;  // second-difference terms
};
inline TemplateSums template_sums(const FlowWindowTemplate& tpl, const std::int16_t* __restrict txx,
                                  const std::int16_t* __restrict tyy) noexcept {
  const std::int16_t* __restrict gx = tpl.gx.data();
  const std::int16_t* __restrict gy = tpl.gy.data();
  const std::int16_t* __restrict t = tpl.t.data();
  TemplateSums s{};
  for (int k = 0; k < kFlowWindowPixels; ++k) {
    s.gx += gx[k];
    s.gy += gy[k];
    s.t += t[k];
    s.gxgx += gx[k] * gx[k];
    s.gxgy += gx[k] * gy[k];
    s.gygy += gy[k] * gy[k];
    s.tt += t[k] * t[k];
    s.gxt += gx[k] * t[k];
    s.gyt += gy[k] * t[k];
    s.xx += txx[k];
    s.yy += tyy[k];
    s.gx_xx += gx[k] * txx[k];
    s.gy_xx += gy[k] * txx[k];
    s.t_xx += t[k] * txx[k];
    s.gx_yy += gx[k] * tyy[k];
    s.gy_yy += gy[k] * tyy[k];
    s.t_yy += t[k] * tyy[k];
  }
  return s;
}

// Neighbour consensus (a PIV-style outlier test) on one grid level: a tracked point (ok = 1) is
// rejected when fewer than half of its tracked 8-neighbours agree with it within `tol` (Q16, per
// axis), or when fewer than two agree at all: a lone match, or a pair of matches that only agree
// with each other, in a failed region is more likely wrong than right. Decisions use the flags
// as they were on entry.
void reject_outliers(int gw, int gh, const std::int32_t* fx, const std::int32_t* fy,
                     std::uint8_t* ok, std::int32_t tol, std::uint8_t* scratch) noexcept {
  std::copy_n(ok, gw * gh, scratch);
  // |a - b| <= tol as one unsigned compare, in 64 bits (flows are within +-2^30, so the
  // difference needs 32 bits plus sign).
  const auto close = [tol](std::int32_t a, std::int32_t b) {
    return static_cast<std::uint64_t>(std::int64_t{a} - b + tol) <=
           2u * static_cast<std::uint64_t>(tol);
  };
  const auto decide = [&](int i, int tracked, int agree) {
    if (agree < 2 || 2 * agree < tracked) ok[i] = 0;
  };
  const int offsets[8] = {-gw - 1, -gw, -gw + 1, -1, 1, gw - 1, gw, gw + 1};
  for (int y = 0; y < gh; ++y) {
    for (int x = 0; x < gw; ++x) {
      const int i = y * gw + x;
      if (!scratch[i]) continue;
      int tracked = 0;
      int agree = 0;
      if (x > 0 && y > 0 && x < gw - 1 && y < gh - 1) {
        for (const int d : offsets) {  // interior: all 8 neighbours exist
          const int j = i + d;
          const int t = scratch[j];
          tracked += t;
          agree += t & static_cast<int>(close(fx[j], fx[i]) && close(fy[j], fy[i]));
        }
      } else {
        for (int ny = std::max(y - 1, 0); ny <= std::min(y + 1, gh - 1); ++ny) {
          for (int nx = std::max(x - 1, 0); nx <= std::min(x + 1, gw - 1); ++nx) {
            const int j = ny * gw + nx;
            if (j == i || !scratch[j]) continue;
            ++tracked;
            agree += static_cast<int>(close(fx[j], fx[i]) && close(fy[j], fy[i]));
          }
        }
      }
      decide(i, tracked, agree);
    }
  }
}

// Fills points without a usable estimate (ok = 0) with the mean of their ok 8-neighbours, in up
// to `passes` sweeps (each sweep only reads points that were ok when it started). Points still
// unfilled afterwards keep their values.
void fill_missing(int gw, int gh, std::int32_t* fx, std::int32_t* fy, std::uint8_t* ok, int passes,
                  std::uint8_t* scratch) noexcept {
  for (int pass = 0; pass < passes; ++pass) {
    std::copy_n(ok, gw * gh, scratch);
    bool changed = false;
    for (int y = 0; y < gh; ++y) {
      const int y0 = std::max(y - 1, 0), y1 = std::min(y + 1, gh - 1);
      for (int x = 0; x < gw; ++x) {
        const int i = y * gw + x;
        if (scratch[i]) continue;
        const int x0 = std::max(x - 1, 0), x1 = std::min(x + 1, gw - 1);
        std::int64_t sx = 0, sy = 0;
        int count = 0;
        for (int ny = y0; ny <= y1; ++ny) {
          for (int nx = x0; nx <= x1; ++nx) {
            const int j = ny * gw + nx;
            if (!scratch[j]) continue;
            sx += fx[j];
            sy += fy[j];
            ++count;
          }
        }
        if (count == 0) continue;
        fx[i] = static_cast<std::int32_t>(div_round(sx, count));
        fy[i] = static_cast<std::int32_t>(div_round(sy, count));
        ok[i] = 1;
        changed = true;
      }
    }
    if (!changed) break;
  }
}

// Flows are kept within +-2^30 (16384 px) so that differences never overflow int32.
std::int32_t clamp_flow(std::int64_t v) noexcept {
  constexpr std::int64_t kMax = std::int64_t{1} << 30;
  return static_cast<std::int32_t>(std::clamp(v, -kMax, kMax));
}

}  // namespace

Status validate(const BlockFlowConfig& c) noexcept {
  auto in = [](double v, double lo, double hi) { return v >= lo && v <= hi; };  // NaN -> false
  if (c.pyramid_levels < 1 || c.pyramid_levels > kMaxPyramidLevels) return Status::kBadArgument;
  if (c.fine_iterations < 1 || c.fine_iterations > 16) return Status::kBadArgument;
  if (c.coarse_iterations < 1 || c.coarse_iterations > 16) return Status::kBadArgument;
  if (!in(c.keyframe_switch_px, 0.0, 32.0)) return Status::kBadArgument;
  if (!in(c.keyframe_min_valid_fraction, 0.0, 1.0)) return Status::kBadArgument;
  if (!in(c.min_texture, 0.0, 64.0)) return Status::kBadArgument;
  if (!in(c.min_eigen_ratio, 0.0, 1.0)) return Status::kBadArgument;
  if (!in(c.max_residual_ratio, 1.0 / 256.0, 4.0)) return Status::kBadArgument;
  if (!in(c.max_step_px, 1.0 / 64.0, 8.0)) return Status::kBadArgument;
  if (!in(c.converged_step_px, 1.0 / 1024.0, 8.0)) return Status::kBadArgument;
  if (!in(c.reanchor_tolerance_px, 0.0, 8.0)) return Status::kBadArgument;
  if (c.coarse_trigger < 0 || c.coarse_trigger > kGridCount) return Status::kBadArgument;
  return Status::kOk;
}

BlockFlow::BlockFlow() noexcept : BlockFlow(BlockFlowConfig{}) {}

BlockFlow::BlockFlow(const BlockFlowConfig& config) noexcept {
  if (configure(config) != Status::kOk) configure(BlockFlowConfig{});
}

Status BlockFlow::configure(const BlockFlowConfig& config) noexcept {
  const Status s = validate(config);
  if (s != Status::kOk) return s;
  config_ = config;
  // Configure-time conversions (double is fine here; nothing below runs per pixel).
  // lambda_min(H64) = 64 * 64 * lambda_min(per-pixel covariance of g), g = 8 * luma gradient.
  const double mt = config.min_texture;
  th_.min_eigen_h64 = static_cast<std::int64_t>(4096.0 * 64.0 * mt * mt + 0.5);
  // lambda_min / lambda_max >= rho  <=>  det >= kappa * trace^2 with kappa = rho / (1 + rho)^2.
  const double rho = config.min_eigen_ratio;
  th_.eigen_ratio_kappa_q16 =
      static_cast<std::int64_t>(rho / ((1.0 + rho) * (1.0 + rho)) * 65536.0 + 0.5);
  th_.residual_ratio_q8 = static_cast<std::int64_t>(config.max_residual_ratio * 256.0 + 0.5);
  th_.max_step_q16 = to_q32<16>(config.max_step_px);
  th_.converged_q16 = to_q32<16>(config.converged_step_px);
  const double k = config.keyframe_switch_px * 65536.0;
  th_.keyframe_switch_sq_q32 = static_cast<std::int64_t>(k * k + 0.5);
  th_.reanchor_tolerance_q16 = to_q32<16>(config.reanchor_tolerance_px);
  th_.keyframe_min_valid_q16 =
      static_cast<std::int64_t>(config.keyframe_min_valid_fraction * 65536.0 + 0.5);
  has_reference_ = false;
  reference_pending_ = false;
  deferred_pending_ = false;  // a switch decided under the old config is dropped with the reference
  return Status::kOk;
}

void BlockFlow::tare(const WorkImage& frame) noexcept {
  if (reference_pending_) {  // a first frame still to become the reference: this one replaces it
    reference_pending_ = false;
    deferred_pending_ = false;
  }
  run_deferred();  // the state a tare leaves is then that of every earlier frame's work done
  // The tare frame keeps its own pyramid slot and its own level-0 window models for the whole
  // session (re-anchoring, see re_anchor()).
  build_pyramid(frame, config_.pyramid_levels, pyramid_[kTareSlot]);
  take_reference();
}

// The frame in the tare slot's pyramid (every level) becomes the reference and the keyframe.
void BlockFlow::take_reference() noexcept {
  key_index_ = static_cast<int>(kTareSlot);
  key_coarse_pyramid_ = true;
  cur_index_ = 0;
  key_displacement_ = VectorField{};
  window_flow_ = VectorField{};
  output_ = VectorField{};
  lost_ = GridMask{};
  reanchored_ = GridMask{};
  key_level0_is_tare_ = true;
  build_level0();
  tare_origin_x_ = window_origin_x_;
  tare_origin_y_ = window_origin_y_;
  tare_offset_ = window_offset_;
  coarse_pending_ = config_.pyramid_levels > 1;
  has_reference_ = true;
  keyframe_switches_ = 0;
  coarse_fallback_ = CoarseFallback{};
  frames_since_keyframe_ = 0;
  last_frame_was_keyframe_ = true;
  for (int i = 0; i < kGridCount; ++i) {
    frame_valid_.v[static_cast<std::size_t>(i)] = level_models(0)[i].valid;
  }
  valid_count_ = keyframe_valid_count_;
}

void BlockFlow::build_level0() noexcept {
  build_models(0);
  const FlowWindowModel* level0 = level_models(0);
  int count = 0;
  for (int i = 0; i < kGridCount; ++i) count += level0[i].valid;
  keyframe_valid_count_ = count;
}

void BlockFlow::build_coarse() noexcept {
  if (!coarse_pending_) return;
  if (!key_coarse_pyramid_) {
    extend_pyramid(pyramid_[static_cast<std::size_t>(key_index_)], config_.pyramid_levels);
    key_coarse_pyramid_ = true;
  }
  for (int l = 1; l < config_.pyramid_levels; ++l) build_models(l);
  coarse_pending_ = false;
}

void BlockFlow::complete_keyframe() noexcept {
  if (!has_reference_) return;
  run_deferred();
  build_coarse();
}

// Window models of one level at the current keyframe. Each window is placed on its material
// point's position in the keyframe (undeformed grid position + keyframe displacement), rounded
// to the nearest integer origin and pushed inside the image; the residual offset delta is kept
// (level 0) for the first-order correction in write_output(). Its template is packed and the
// statistics, the inverse structure tensor and the validity tests are computed once here.
void BlockFlow::build_models(int level) noexcept {
  const int gw = flow_grid_width(level);
  const int gh = flow_grid_height(level);
  const int w = pyramid_width(level);
  const int h = pyramid_height(level);
  const std::size_t stride = static_cast<std::size_t>(pyramid_stride(level));
  const std::uint16_t* key = pyramid_[static_cast<std::size_t>(key_index_)].level(level);
  const int block = 1 << level;
  const std::int32_t max_offset = level == 0 ? kMaxWindowOffsetQ16 : kMaxCoarseWindowOffsetQ16;

  for (int jy = 0; jy < gh; ++jy) {
    for (int jx = 0; jx < gw; ++jx) {
      const int index = jy * gw + jx;
      FlowWindowModel& m = level_models(level)[index];
      FlowWindowTemplate& tpl = level_templates(level)[index];
      m = FlowWindowModel{};
      // Keyframe displacement of the block of level-0 points this window stands for (Q16
      // working px), block mean; then in level-l px.
      std::int64_t dsx = 0;
      std::int64_t dsy = 0;
      for (int by = 0; by < block; ++by) {
        for (int bx = 0; bx < block; ++bx) {
          dsx += key_displacement_.x(jx * block + bx, jy * block + by);
          dsy += key_displacement_.y(jx * block + bx, jy * block + by);
        }
      }
      const std::int64_t dx = rshift_round(dsx, 3 * level);  // mean (2l) then / 2^l (l)
      const std::int64_t dy = rshift_round(dsy, 3 * level);
      const std::int64_t px = std::int64_t{kGridStride * jx} * kOne + 3 * kHalf + dx;
      const std::int64_t py = std::int64_t{kGridStride * jy} * kOne + 3 * kHalf + dy;
      const std::int64_t ox = std::clamp<std::int64_t>(
          (px - kWindowCentreQ16 + kHalf) >> 16, kWindowMargin, w - kFlowWindow - kWindowMargin);
      const std::int64_t oy = std::clamp<std::int64_t>(
          (py - kWindowCentreQ16 + kHalf) >> 16, kWindowMargin, h - kFlowWindow - kWindowMargin);
      const std::int64_t off_x = px - (ox * kOne + kWindowCentreQ16);
      const std::int64_t off_y = py - (oy * kOne + kWindowCentreQ16);
      m.ox = static_cast<std::int16_t>(ox);
      m.oy = static_cast<std::int16_t>(oy);
      if (level == 0) {
        window_origin_x_[static_cast<std::size_t>(index)] = m.ox;
        window_origin_y_[static_cast<std::size_t>(index)] = m.oy;
        window_offset_.x.v[static_cast<std::size_t>(index)] = sat32(off_x);
        window_offset_.y.v[static_cast<std::size_t>(index)] = sat32(off_y);
      }
      if (off_x > max_offset || off_x < -max_offset || off_y > max_offset || off_y < -max_offset) {
        continue;  // the material point has left the image (or nearly): not trackable
      }

      // Pack the template with its gradients; keep the second differences for the bilinear
      // compensation. All neighbours are inside the image thanks to the 1 px margin.
      // |Txx|, |Tyy| <= 2040 (int16).
      alignas(16) std::array<std::int16_t, kFlowWindowPixels> txx;  // pack_row writes every row
      alignas(16) std::array<std::int16_t, kFlowWindowPixels> tyy;
      for (int row = 0; row < kFlowWindow; ++row) {
        const std::uint16_t* r0 =
            key + (static_cast<std::size_t>(oy) + static_cast<std::size_t>(row)) * stride +
            static_cast<std::size_t>(ox);
        const auto o = static_cast<std::size_t>(row * kFlowWindow);
        pack_row(r0, r0 - stride, r0 + stride, tpl.t.data() + o, tpl.gx.data() + o,
                 tpl.gy.data() + o, txx.data() + o, tyy.data() + o);
      }
      const TemplateSums ts = template_sums(tpl, txx.data(), tyy.data());
      const std::int32_t sgx = ts.gx, sgy = ts.gy, st = ts.t, sxx = ts.gxgx, sxy = ts.gxgy,
                         syy = ts.gygy, stt = ts.tt, sgxt = ts.gxt, sgyt = ts.gyt;
      const std::int32_t s_xx = ts.xx, s_yy = ts.yy, gx_xx = ts.gx_xx, gy_xx = ts.gy_xx,
                         t_xx = ts.t_xx, gx_yy = ts.gx_yy, gy_yy = ts.gy_yy, t_yy = ts.t_yy;
      m.gsum_x = sgx;
      m.gsum_y = sgy;
      m.tsum = st;
      // Zero-mean template energy in U8.3 units (2T), times 64: < 2^36.
      m.template_energy = 4 * (kN * stt - std::int64_t{st} * st);
      m.curvature = {kN * gx_xx - std::int64_t{sgx} * s_xx, kN * gy_xx - std::int64_t{sgy} * s_xx,
                     kN * t_xx - std::int64_t{st} * s_xx,   kN * gx_yy - std::int64_t{sgx} * s_yy,
                     kN * gy_yy - std::int64_t{sgy} * s_yy, kN * t_yy - std::int64_t{st} * s_yy};

      // Local gain: the match model is I(s + u) = (1 + gamma) T(s) + beta. Eliminating beta
      // centres everything; eliminating gamma (Schur complement) leaves the 2x2 system
      //   (H64 - k k^T / e) du = -(b64 - k bT / e) / 16,
      // k = 64 sum g T - G sum T (< 2^33), e = 64 sum T^2 - (sum T)^2 (< 2^33), bT the mismatch
      // against T. q = k / e is stored in Q16 (|q| <= 2^22, else the window is rejected).
      const std::int64_t e64 = kN * stt - std::int64_t{st} * st;
      if (e64 <= 0) continue;
      const std::int64_t kx = kN * sgxt - std::int64_t{sgx} * st;
      const std::int64_t ky = kN * sgyt - std::int64_t{sgy} * st;
      const std::int64_t qx = div_round(kx * 65536, e64);
      const std::int64_t qy = div_round(ky * 65536, e64);
      if (qx > kMaxGainCoupling || qx < -kMaxGainCoupling || qy > kMaxGainCoupling ||
          qy < -kMaxGainCoupling) {
        continue;
      }
      m.gain_qx = static_cast<std::int32_t>(qx);
      m.gain_qy = static_cast<std::int32_t>(qy);

      // H64 = 64 * zero-mean structure tensor with the gain eliminated (PSD, entries < 2^33):
      // H64 - k k^T / e, the k k^T / e terms as k * q >> 16 (|k q| < 2^56).
      const std::int64_t ha = kN * sxx - std::int64_t{sgx} * sgx - rshift_round(kx * qx, 16);
      const std::int64_t hb =
          kN * sxy - std::int64_t{sgx} * sgy -
          rshift_round(rshift_round(kx * qy, 16) + rshift_round(ky * qx, 16), 1);
      const std::int64_t hc = kN * syy - std::int64_t{sgy} * sgy - rshift_round(ky * qy, 16);
      const std::int64_t tau = th_.min_eigen_h64;
      if (ha <= 0 || hc <= 0 || ha < tau || hc < tau) continue;  // blank / one-dimensional

      // Normalise so the largest entry is in [2^29, 2^30): products below stay < 2^62.
      const int s = bit_length(static_cast<std::uint64_t>(std::max(ha, hc))) - 30;
      const std::int64_t a = scale_pow2(ha, s);
      const std::int64_t b = scale_pow2(hb, s);
      const std::int64_t c = scale_pow2(hc, s);
      const std::int64_t tau_n = scale_pow2(tau, s);  // <= max(a, c), so no overflow for s < 0
      // lambda_min >= tau  <=>  H - tau I is PSD.
      if ((a - tau_n) * (c - tau_n) < b * b) continue;
      const std::int64_t det = a * c - b * b;
      if (det <= 0) continue;
      // Conditioning: det >= kappa * trace^2, both sides scaled by 2^-16.
      const std::int64_t tr = a + c;
      const auto tr2_hi = static_cast<std::int64_t>(static_cast<std::uint64_t>(tr * tr) >> 32);
      if ((det >> 16) < tr2_hi * th_.eigen_ratio_kappa_q16) continue;

      // Inverse [c -b; -b a] / det as mantissas M with ~21 significant bits:
      // H64^-1 = M * 2^-(k + t + s).
      const int t = std::max(0, bit_length(static_cast<std::uint64_t>(det)) - 31);
      const std::int64_t d = std::max<std::int64_t>(rshift_round(det, t), 1);
      const int k = std::clamp(20 + bit_length(static_cast<std::uint64_t>(d)) -
                                   bit_length(static_cast<std::uint64_t>(std::max(a, c))),
                               0, 32);
      const std::int64_t inv_a = div_round(c << k, d);
      const std::int64_t inv_b = div_round(-b * (std::int64_t{1} << k), d);
      const std::int64_t inv_c = div_round(a << k, d);
      // Step (Q16) = -(16 H64)^-1 b * 2^16 = -(M b) * 2^-(k + t + s - 12).
      const int shift = k + t + s - 12;
      if (shift < 1 || shift > 62) continue;
      if (std::max({inv_a, -inv_a, inv_b, -inv_b, inv_c, -inv_c}) >= kMaxMantissa) {
        continue;  // only reachable with min_eigen_ratio = 0 on a near-singular window
      }
      m.inv_a = static_cast<std::int32_t>(inv_a);
      m.inv_b = static_cast<std::int32_t>(inv_b);
      m.inv_c = static_cast<std::int32_t>(inv_c);
      m.shift = static_cast<std::int8_t>(shift);
      if (level == 0) {
        if (lost_.v[static_cast<std::size_t>(index)]) continue;  // see switch_keyframe()
        measurement_moments(tpl, m);
      }
      m.valid = 1;
    }
  }
}

// Gauss-Newton iterations of one window at one level from the start position (ux, uy) (Q16
// level px). Stops early when the rounded sampling position repeats (a further iteration would
// compute the same step). Invalid if the window leaves the image, has not converged, or the
// zero-mean residual is too large.
BlockFlow::WindowResult BlockFlow::track_window(int level, int index, std::int32_t ux,
                                                std::int32_t uy, int iterations) const noexcept {
  const FlowWindowModel& m = level_models(level)[index];
  const FlowWindowTemplate& tpl = level_templates(level)[index];
  const std::size_t stride = static_cast<std::size_t>(pyramid_stride(level));
  const std::uint16_t* cur = pyramid_[static_cast<std::size_t>(cur_index_)].level(level);
  const std::int32_t max_x = (pyramid_width(level) - kFlowWindow) << kPosFrac;
  const std::int32_t max_y = (pyramid_height(level) - kFlowWindow) << kPosFrac;

  alignas(16) std::array<std::int16_t, kFlowWindowPixels> res;  // written by each sample
  std::int32_t qx = static_cast<std::int32_t>(rshift_round(ux, kQ16ToPos));
  std::int32_t qy = static_cast<std::int32_t>(rshift_round(uy, kQ16ToPos));
  std::int32_t step_x = 0;
  std::int32_t step_y = 0;
  bool converged = false;
  WindowSums sums{0, 0, 0, 0};
  for (int it = 0; it < iterations; ++it) {
    const std::int32_t sx = (std::int32_t{m.ox} << kPosFrac) + qx;
    const std::int32_t sy = (std::int32_t{m.oy} << kPosFrac) + qy;
    if (sx < 0 || sy < 0 || sx > max_x || sy > max_y) return {ux, uy, false, true};
    const int fx = sx & ((1 << kPosFrac) - 1);
    const int fy = sy & ((1 << kPosFrac) - 1);
    const std::uint16_t* src = cur + static_cast<std::size_t>(sy >> kPosFrac) * stride +
                               static_cast<std::size_t>(sx >> kPosFrac);
    sums = sample_window(src, stride, tpl, fx, fy, res.data());
    // Bilinear interpolation at fraction f of a signal G returns G + f (1 - f) / 2 * G'' (to
    // second order): the sampled window is a slightly smoothed copy of the template. That
    // smoothing biases the match by up to ~0.04 px on 8x8 windows, independent of texture
    // scale. Its predicted residual, f(1-f)/2 * (Txx, Tyy), is removed from the mismatch:
    //   b -= C_xx * fx (32 - fx) / 64 + C_yy * fy (32 - fy) / 64   (fx, fy in Q5).
    const std::int64_t ax = fx * (32 - fx);  // <= 256
    const std::int64_t ay = fy * (32 - fy);
    const auto compensation = [&](std::size_t i) {
      return rshift_round(ax * m.curvature[i] + ay * m.curvature[i + 3], 6);
    };
    const std::int64_t bt = kN * sums.tr - std::int64_t{m.tsum} * sums.r - compensation(2);
    // Zero-mean mismatch with the gain eliminated: b_eff = b64 - q bT (q Q16, |q bT| < 2^61),
    // saturated to +-2^39 so that M b stays below 2^62 (a saturated b only occurs for steps far
    // beyond max_step).
    const std::int64_t bx = std::clamp(kN * sums.gr_x - std::int64_t{m.gsum_x} * sums.r -
                                           compensation(0) - rshift_round(m.gain_qx * bt, 16),
                                       -kMaxMismatch, kMaxMismatch);
    const std::int64_t by = std::clamp(kN * sums.gr_y - std::int64_t{m.gsum_y} * sums.r -
                                           compensation(1) - rshift_round(m.gain_qy * bt, 16),
                                       -kMaxMismatch, kMaxMismatch);
    step_x =
        clamp_abs(sat32(-rshift_round(m.inv_a * bx + m.inv_b * by, m.shift)), th_.max_step_q16);
    step_y =
        clamp_abs(sat32(-rshift_round(m.inv_b * bx + m.inv_c * by, m.shift)), th_.max_step_q16);
    ux = clamp_flow((std::int64_t{qx} << kQ16ToPos) + step_x);
    uy = clamp_flow((std::int64_t{qy} << kQ16ToPos) + step_y);
    const auto nqx = static_cast<std::int32_t>(rshift_round(ux, kQ16ToPos));
    const auto nqy = static_cast<std::int32_t>(rshift_round(uy, kQ16ToPos));
    if (nqx == qx && nqy == qy) {
      converged = true;
      break;
    }
    qx = nqx;
    qy = nqy;
  }
  if (!converged) {
    converged = step_x <= th_.converged_q16 && step_x >= -th_.converged_q16 &&
                step_y <= th_.converged_q16 && step_y >= -th_.converged_q16;
  }
  // Match quality at the last sampled position: zero-mean residual energy (U8.3, times 64)
  // against the template's. E_r < 2^34, times 2^8 stays far below 2^63.
  const std::int64_t mean_r = sums.r >> 4;  // sum (r >> 4) up to rounding
  const std::int64_t e_r =
      std::max<std::int64_t>(0, kN * residual_energy(res.data()) - mean_r * mean_r);
  const bool matched = (e_r << 8) <= th_.residual_ratio_q8 * m.template_energy;
  return {ux, uy, converged && matched, false};
}

void BlockFlow::coarse_to_fine() noexcept {
  const int levels = config_.pyramid_levels;
  // Only the coarse windows the retry of the failed level-0 windows draws on (CoarseRegion).
  const FlowWindowModel* level0 = level_models(0);
  for (int i = 0; i < kGridCount; ++i) {
    const auto u = static_cast<std::size_t>(i);
    retry_[u] = static_cast<std::uint8_t>(level0[u].valid && !ok_[u]);
  }
  coarse_region_.build(retry_.data(), levels);
  // Warm starts of the coarse grids: block means of the level-0 window flow (Q16 working px).
  for (int l = 1; l < levels; ++l) {
    const int gw = flow_grid_width(l);
    const int gh = flow_grid_height(l);
    const int block = 1 << l;
    for (int jy = 0; jy < gh; ++jy) {
      for (int jx = 0; jx < gw; ++jx) {
        std::int64_t sx = 0;
        std::int64_t sy = 0;
        for (int by = 0; by < block; ++by) {
          for (int bx = 0; bx < block; ++bx) {
            sx += window_flow_.x(jx * block + bx, jy * block + by);
            sy += window_flow_.y(jx * block + bx, jy * block + by);
          }
        }
        const auto i = static_cast<std::size_t>(flow_grid_offset(l) + jy * gw + jx);
        warm_x_[i] = static_cast<std::int32_t>(rshift_round(sx, 2 * l));
        warm_y_[i] = static_cast<std::int32_t>(rshift_round(sy, 2 * l));
      }
    }
  }

  // Coarse levels, top down. Each level tracks its windows from warm start + the upsampled
  // correction of the level above, rejects inconsistent estimates (neighbour consensus), fills
  // the gaps from tracked neighbours (windows that left the image at the border, blank
  // patches), and passes on its correction = estimate - warm start.
  for (int l = levels - 1; l >= 1; --l) {
    const int gw = flow_grid_width(l);
    const int gh = flow_grid_height(l);
    const int off = flow_grid_offset(l);
    std::int32_t* fx = flow_x_.data() + off;
    std::int32_t* fy = flow_y_.data() + off;
    std::uint8_t* ok = ok_.data() + off;
    upsample_correction(l);
    for (int jy = 0; jy < gh; ++jy) {
      for (int jx = 0; jx < gw; ++jx) {
        const int j = jy * gw + jx;
        const auto i = static_cast<std::size_t>(off + j);
        fx[j] = clamp_flow(std::int64_t{warm_x_[i]} + up_x_[i]);
        fy[j] = clamp_flow(std::int64_t{warm_y_[i]} + up_y_[i]);
        ok[j] = 0;
        if (!models_[i].valid || !coarse_region_.tracked(l, j)) continue;
        const WindowResult r = track_window(l, j, static_cast<std::int32_t>(rshift_round(fx[j], l)),
                                            static_cast<std::int32_t>(rshift_round(fy[j], l)),
                                            config_.coarse_iterations);
        if (!r.valid) continue;
        fx[j] = clamp_flow(std::int64_t{r.ux} << l);
        fy[j] = clamp_flow(std::int64_t{r.uy} << l);
        ok[j] = 1;
      }
    }
    reject_outliers(gw, gh, fx, fy, ok, kOne << l, scratch_.data());
    fill_missing(gw, gh, fx, fy, ok, gw, scratch_.data());
    for (int j = 0; j < gw * gh; ++j) {
      const auto i = static_cast<std::size_t>(off + j);
      corr_x_[i] = sub_sat32(fx[j], warm_x_[i]);
      corr_y_[i] = sub_sat32(fy[j], warm_y_[i]);
    }
  }
}

// Correction of the coarser level l + 1 (Q16 working px) upsampled to every point of level l
// (cell-centred bilinear: 9/16, 3/16, 3/16, 1/16), into up_x_/up_y_ at level l's offset. Zero
// for the top level. Scaling: |corr| <= 2^31, 16 * that < 2^36 (int64), rounded once (>> 4).
void BlockFlow::upsample_correction(int l) noexcept {
  const int gw = flow_grid_width(l);
  const int gh = flow_grid_height(l);
  std::int32_t* ux = up_x_.data() + flow_grid_offset(l);
  std::int32_t* uy = up_y_.data() + flow_grid_offset(l);
  if (l + 1 >= config_.pyramid_levels) {
    std::fill_n(ux, gw * gh, 0);
    std::fill_n(uy, gw * gh, 0);
    return;
  }
  const int cw = flow_grid_width(l + 1);
  const int ch = flow_grid_height(l + 1);
  const std::int32_t* cx = corr_x_.data() + flow_grid_offset(l + 1);
  const std::int32_t* cy = corr_y_.data() + flow_grid_offset(l + 1);
  std::array<int, kGridWidth> near_x{}, far_x{};
  for (int x = 0; x < gw; ++x) {
    upsample_taps(x, cw, near_x[static_cast<std::size_t>(x)], far_x[static_cast<std::size_t>(x)]);
  }
  for (int y = 0; y < gh; ++y) {
    int y0, y1;
    upsample_taps(y, ch, y0, y1);
    const std::int32_t* ax0 = cx + y0 * cw;
    const std::int32_t* ax1 = cx + y1 * cw;
    const std::int32_t* ay0 = cy + y0 * cw;
    const std::int32_t* ay1 = cy + y1 * cw;
    for (int x = 0; x < gw; ++x) {
      const int x0 = near_x[static_cast<std::size_t>(x)];
      const int x1 = far_x[static_cast<std::size_t>(x)];
      ux[y * gw + x] = sat32(rshift_round(9 * std::int64_t{ax0[x0]} + 3 * std::int64_t{ax0[x1]} +
                                              3 * std::int64_t{ax1[x0]} + ax1[x1],
                                          4));
      uy[y * gw + x] = sat32(rshift_round(9 * std::int64_t{ay0[x0]} + 3 * std::int64_t{ay0[x1]} +
                                              3 * std::int64_t{ay1[x0]} + ay1[x1],
                                          4));
    }
  }
}

// Level 0. First pass (retry = false): every trackable window from its warm start
// window_flow_. Retry pass (after coarse_to_fine()): only the windows that failed, from warm
// start + the upsampled coarse correction. Then the consensus test over all. Failed points hold
// their previous window flow. Returns how many trackable windows failed for a reason other than
// leaving the image (the trigger for the coarse levels); `fresh` gets how many of those the
// previous frame had tracked.
int BlockFlow::track_fine(bool retry, int* fresh) noexcept {
  std::int32_t* fx = flow_x_.data();
  std::int32_t* fy = flow_y_.data();
  std::uint8_t* ok = ok_.data();
  const FlowWindowModel* level0 = level_models(0);
  if (retry) upsample_correction(0);
  int failed = 0;
  int failed_fresh = 0;  // frame_valid_ still holds the previous frame's until the end
  for (int i = 0; i < kGridCount; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    if (retry && ok[i]) continue;  // keeps its first-pass estimate in fx, fy
    ok[i] = 0;
    fx[i] = window_flow_.x.v[ui];
    fy[i] = window_flow_.y.v[ui];
    if (!level0[ui].valid) continue;
    const std::int32_t cx = retry ? up_x_[ui] : 0;
    const std::int32_t cy = retry ? up_y_[ui] : 0;
    const WindowResult r =
        track_window(0, i, clamp_flow(std::int64_t{fx[i]} + cx),
                     clamp_flow(std::int64_t{fy[i]} + cy), config_.fine_iterations);
    if (!r.valid) {
      failed += r.outside ? 0 : 1;
      failed_fresh += !r.outside && frame_valid_.v[ui] ? 1 : 0;
      continue;
    }
    fx[i] = r.ux;
    fy[i] = r.uy;
    ok[i] = 1;
  }
  reject_outliers(kGridWidth, kGridHeight, fx, fy, ok, kOne, scratch_.data());
  int count = 0;
  for (int i = 0; i < kGridCount; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    const bool rejected = scratch_[ui] && !ok[i];  // by the consensus test: a failure too
    failed += rejected ? 1 : 0;
    failed_fresh += rejected && frame_valid_.v[ui] ? 1 : 0;
    frame_valid_.v[ui] = ok[i];
    if (!ok[i]) continue;
    window_flow_.x.v[ui] = fx[i];
    window_flow_.y.v[ui] = fy[i];
    ++count;
  }
  valid_count_ = count;
  if (fresh != nullptr) *fresh = failed_fresh;
  return failed;
}

// Output: total displacement of the material point p =
//   D_key(p) + c(p) + delta_x J(:, x) + delta_y J(:, y),   c = t_w - P_x J(:, x) - P_y J(:, y),
// the window flow t_w corrected to first order in the flow gradient J = d f / d x (f = flow
// from the keyframe, keyframe coordinates) for (a) the window's measurement point P (see
// measurement_moments()), giving the flow c at the window centre, and (b) the offset delta
// between p and the window centre (window origins are integers and pushed inside the image at
// the border). J comes from the neighbouring windows' centre flows divided by their integer
// centre spacing; since c itself depends on J, J and c are refined together in
// kJacobianPasses fixed-point passes (contraction ~|P| / spacing, ~0.3). Exact for affine
// flow up to the accuracy of J.
void BlockFlow::update_stencils() noexcept {
  if (stencil_built_ && stencil_mask_.v == frame_valid_.v &&
      stencil_origin_x_ == window_origin_x_ && stencil_origin_y_ == window_origin_y_) {
    return;  // a pure function of these three: the stencils of the last frame still hold
  }
  stencil_built_ = true;
  stencil_mask_ = frame_valid_;
  stencil_origin_x_ = window_origin_x_;
  stencil_origin_y_ = window_origin_y_;
  // Difference stencils of this frame's valid points, one per grid axis: J column =
  // (c[b] - c[a]) * recip, recip = 1 / (centre spacing of windows a and b) in Q16, or 0 when
  // there are no usable neighbours. Central difference, one-sided at gaps, widened by one grid
  // step where windows pushed inside at the border sit less than kMinSpacing px apart.
  const auto make_stencil = [&](int gx, int gy, bool along_x) {
    JacobianStencil st{0, 0, 0};
    const int step_x = along_x ? 1 : 0;
    const int step_y = along_x ? 0 : 1;
    const auto usable = [&](int x, int y) {
      return x >= 0 && y >= 0 && x < kGridWidth && y < kGridHeight && frame_valid_(x, y) != 0;
    };
    const auto origin = [&](int x, int y) {
      return (along_x ? window_origin_x_
                      : window_origin_y_)[static_cast<std::size_t>(y * kGridWidth + x)];
    };
    const bool has_l = usable(gx - step_x, gy - step_y);
    const bool has_r = usable(gx + step_x, gy + step_y);
    if (!has_l && !has_r) return st;
    int ax = has_l ? gx - step_x : gx, ay = has_l ? gy - step_y : gy;
    int bx = has_r ? gx + step_x : gx, by = has_r ? gy + step_y : gy;
    int spacing = origin(bx, by) - origin(ax, ay);
    if (spacing < kMinSpacing) {
      if (usable(bx + step_x, by + step_y)) {
        bx += step_x;
        by += step_y;
      } else if (usable(ax - step_x, ay - step_y)) {
        ax -= step_x;
        ay -= step_y;
      }
      spacing = origin(bx, by) - origin(ax, ay);
    }
    if (spacing < kMinSpacing || spacing > kMaxSpacing) return st;
    st.a = static_cast<std::int16_t>(ay * kGridWidth + ax);
    st.b = static_cast<std::int16_t>(by * kGridWidth + bx);
    st.recip = kReciprocalQ16[static_cast<std::size_t>(spacing)];
    return st;
  };
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const auto i = static_cast<std::size_t>(gy * kGridWidth + gx);
      if (!frame_valid_.v[i]) continue;
      stencil_[i] = {make_stencil(gx, gy, true), make_stencil(gx, gy, false)};
    }
  }
}

void BlockFlow::write_output(VectorField& displacement, GridMask& valid) noexcept {
  update_stencils();
  // Q16 difference quotient, clamped to +-1/2: |difference| < 2^31, recip <= 2^16.
  const auto quotient = [](std::int64_t diff, std::int32_t recip) {
    return static_cast<std::int32_t>(
        std::clamp<std::int64_t>(rshift_round(diff * recip, 16), -kHalf, kHalf));
  };

  centre_ = window_flow_;
  const FlowWindowModel* level0 = level_models(0);
  for (int pass = 0; pass < kJacobianPasses; ++pass) {
    for (int i = 0; i < kGridCount; ++i) {
      const auto u = static_cast<std::size_t>(i);
      if (!frame_valid_.v[u]) continue;
      auto& j = jacobian_[u];  // {dfx/dx, dfy/dx, dfx/dy, dfy/dy}
      for (int axis = 0; axis < 2; ++axis) {
        const JacobianStencil& st = stencil_[u][static_cast<std::size_t>(axis)];
        const auto a = static_cast<std::size_t>(st.a), b = static_cast<std::size_t>(st.b);
        j[static_cast<std::size_t>(2 * axis)] =
            quotient(std::int64_t{centre_.x.v[b]} - centre_.x.v[a], st.recip);
        j[static_cast<std::size_t>(2 * axis + 1)] =
            quotient(std::int64_t{centre_.y.v[b]} - centre_.y.v[a], st.recip);
      }
    }
    // c = t_w - P_x J(:, x) - P_y J(:, y): |P| < 2^21, |J| <= 2^15, products < 2^37.
    for (int i = 0; i < kGridCount; ++i) {
      const auto u = static_cast<std::size_t>(i);
      if (!frame_valid_.v[u]) continue;
      const auto& px = level0[u].moment_x;
      const auto& py = level0[u].moment_y;
      const auto& j = jacobian_[u];
      const std::int64_t cx = std::int64_t{px[0]} * j[0] + std::int64_t{px[1]} * j[1] +
                              std::int64_t{py[0]} * j[2] + std::int64_t{py[1]} * j[3];
      const std::int64_t cy = std::int64_t{px[2]} * j[0] + std::int64_t{px[3]} * j[1] +
                              std::int64_t{py[2]} * j[2] + std::int64_t{py[3]} * j[3];
      centre_.x.v[u] = clamp_flow(window_flow_.x.v[u] - rshift_round(cx, 16));
      centre_.y.v[u] = clamp_flow(window_flow_.y.v[u] - rshift_round(cy, 16));
    }
  }

  for (int i = 0; i < kGridCount; ++i) {
    const auto u = static_cast<std::size_t>(i);
    valid.v[u] = frame_valid_.v[u];
    if (frame_valid_.v[u]) {
      // delta (Q16, |.| <= 3.5 px) times J (Q16): products < 2^34.
      const std::int64_t dx = window_offset_.x.v[u];
      const std::int64_t dy = window_offset_.y.v[u];
      const auto& j = jacobian_[u];
      const std::int64_t ox = rshift_round(dx * j[0] + dy * j[2], 16);
      const std::int64_t oy = rshift_round(dx * j[1] + dy * j[3], 16);
      output_.x.v[u] = sat32(std::int64_t{key_displacement_.x.v[u]} + centre_.x.v[u] + ox);
      output_.y.v[u] = sat32(std::int64_t{key_displacement_.y.v[u]} + centre_.y.v[u] + oy);
    }
    displacement.x.v[u] = output_.x.v[u];
    displacement.y.v[u] = output_.y.v[u];
  }
}

// Keyframe chaining: when some valid point has moved more than keyframe_switch_px from the
// keyframe, and the frame is healthy, the current frame becomes the keyframe. The material
// points' current displacements become the new keyframe displacements, so the total relative
// to the tare frame carries over (invalid points carry their held value).
bool BlockFlow::keyframe_switch_due() const noexcept {
  if (th_.keyframe_switch_sq_q32 == 0) return false;
  std::int64_t max_sq = 0;
  for (int i = 0; i < kGridCount; ++i) {
    if (!frame_valid_.v[static_cast<std::size_t>(i)]) continue;
    const std::int64_t x = window_flow_.x.v[static_cast<std::size_t>(i)];
    const std::int64_t y = window_flow_.y.v[static_cast<std::size_t>(i)];
    max_sq = std::max(max_sq, x * x + y * y);  // |x|, |y| <= 2^30: sum < 2^61
  }
  if (max_sq <= th_.keyframe_switch_sq_q32) return false;
  return std::int64_t{valid_count_} * 65536 >= th_.keyframe_min_valid_q16 * keyframe_valid_count_;
}

// The switch itself, in run_deferred() after the frame that decided it (keyframe_switch_due()
// in track()): it reads only that frame's state, which nothing changes in between.
void BlockFlow::switch_keyframe() noexcept {
  // Points not tracked in this frame only have a stale (held) displacement; a window placed
  // there would follow the wrong material from now on. Their keyframe displacement is instead
  // re-estimated from the tracked neighbours (local affine fit); points without enough tracked
  // neighbours are lost until the next keyframe or tare.
  key_displacement_ = output_;
  reanchored_ = GridMask{};
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const auto i = static_cast<std::size_t>(gy * kGridWidth + gx);
      lost_.v[i] = 0;
      if (frame_valid_.v[i]) continue;
      if (!fit_from_neighbours(gx, gy, key_displacement_.x.v[i], key_displacement_.y.v[i])) {
        lost_.v[i] = 1;
      }
    }
  }
  if (th_.reanchor_tolerance_q16 > 0) re_anchor();
  key_index_ = cur_index_;  // the current frame becomes the keyframe
  key_coarse_pyramid_ = coarse_built_;
  cur_index_ = 1 - cur_index_;
  window_flow_ = VectorField{};
  // Its level-0 models follow at once (run_deferred()), the coarse levels when a coarse pass
  // first needs them or in the frame after. They depend only on the keyframe image and
  // displacement, fixed from here on.
  key_level0_is_tare_ = false;
  coarse_pending_ = config_.pyramid_levels > 1;
}

void BlockFlow::run_deferred() noexcept {
  if (!deferred_pending_) return;
  deferred_pending_ = false;
  if (reference_pending_) {
    reference_pending_ = false;
    extend_pyramid(pyramid_[kTareSlot], config_.pyramid_levels);
    take_reference();
    return;
  }
  if (last_frame_was_keyframe_) {
    switch_keyframe();
    build_level0();  // the next track() matches against it
  } else if (frames_since_keyframe_ >= 2) {
    // The coarse models of a keyframe no coarse pass has needed yet, in its second frame.
    build_coarse();
  }
}

// Re-anchoring at a keyframe switch. The chained displacement D_key + flow carries the
// measurement error of every keyframe interval; summed over switches it drifts. Before the
// current frame becomes the keyframe, it is matched directly against the tare frame (level-0
// windows of the tare frame, warm-started from the chained displacement, so no pyramid is
// needed). Where that direct match is valid and agrees with the chained value within
// reanchor_tolerance_px (by default any valid match), it replaces it: the drift is reset instead
// of accumulated, and so is a chain that took a wrong match (the direct match is measured
// against the frame every displacement refers to; the chain is the sum of every interval's
// matches). Where the appearance has changed too much for a direct match (large
// deformation, shading), the chained value is kept. Cost: one level-0 pass against the tare
// frame's level-0 models (kept since the tare), on switch frames only.
void BlockFlow::re_anchor() noexcept {
  // What this frame reported stays as it was (held values, valid mask and count). The copies
  // live in member scratch (no large stack frames).
  VectorField& reported = reanchor_reported_;
  VectorField& chained = reanchor_chained_;
  VectorField& direct = reanchor_direct_;
  GridMask& reported_valid = reanchor_reported_valid_;
  GridMask& chained_lost = reanchor_chained_lost_;
  GridMask& direct_valid = reanchor_direct_valid_;
  reported = output_;
  reported_valid = frame_valid_;
  const int reported_count = valid_count_;
  chained = key_displacement_;
  chained_lost = lost_;
  key_displacement_ = VectorField{};
  lost_ = GridMask{};
  key_level0_is_tare_ = true;
  window_origin_x_ = tare_origin_x_;
  window_origin_y_ = tare_origin_y_;
  window_offset_ = tare_offset_;
  window_flow_ = chained;  // warm start: tare windows sit at the undeformed positions
  track_fine(false);
  output_ = chained;
  write_output(direct, direct_valid);
  const std::int32_t tol = th_.reanchor_tolerance_q16;
  key_displacement_ = chained;
  lost_ = chained_lost;
  for (int i = 0; i < kGridCount; ++i) {
    const auto u = static_cast<std::size_t>(i);
    if (!direct_valid.v[u]) continue;
    const std::int64_t ex = std::int64_t{direct.x.v[u]} - chained.x.v[u];
    const std::int64_t ey = std::int64_t{direct.y.v[u]} - chained.y.v[u];
    // A lost point has no usable chained value: its (consensus-checked) direct match is taken.
    if (!chained_lost.v[u] && (ex > tol || ex < -tol || ey > tol || ey < -tol)) continue;
    key_displacement_.x.v[u] = direct.x.v[u];
    key_displacement_.y.v[u] = direct.y.v[u];
    lost_.v[u] = 0;
    reanchored_.v[u] = 1;
  }
  output_ = reported;
  frame_valid_ = reported_valid;
  valid_count_ = reported_count;
}

// Displacement of grid point (gx, gy) from its tracked neighbours within +-2 grid steps: least
// squares fit of u = a + b dx + c dy per component, evaluated at the point (= a, by Cramer's
// rule). Needs >= 6 neighbours that are not collinear. Exact for affine fields; the error of a
// smooth field is second order (curvature x (8 px)^2).
// Scaling and overflow: offsets |dx|, |dy| <= 2, at most 24 neighbours, so the design sums are
// <= 96 and its determinant < 2^24; flows are within +-2^30, so the right-hand sums are < 2^36
// and the numerator determinant < 2^52 (int64). One rounded division per component.
bool BlockFlow::fit_from_neighbours(int gx, int gy, std::int32_t& ux,
                                    std::int32_t& uy) const noexcept {
  std::int64_t n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  std::int64_t su[2] = {0, 0}, sux[2] = {0, 0}, suy[2] = {0, 0};
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) {
      const int x = gx + dx, y = gy + dy;
      if ((dx == 0 && dy == 0) || x < 0 || y < 0 || x >= kGridWidth || y >= kGridHeight) continue;
      if (!frame_valid_(x, y)) continue;
      ++n;
      sx += dx;
      sy += dy;
      sxx += dx * dx;
      sxy += dx * dy;
      syy += dy * dy;
      const std::int64_t u[2] = {output_.x(x, y), output_.y(x, y)};
      for (int c = 0; c < 2; ++c) {
        su[c] += u[c];
        sux[c] += u[c] * dx;
        suy[c] += u[c] * dy;
      }
    }
  }
  if (n < 6) return false;
  const std::int64_t m11 = sxx * syy - sxy * sxy;
  const std::int64_t det = n * m11 - sx * (sx * syy - sxy * sy) + sy * (sx * sxy - sxx * sy);
  if (det <= 0) return false;
  std::int32_t* out[2] = {&ux, &uy};
  for (int c = 0; c < 2; ++c) {
    const std::int64_t num =
        su[c] * m11 - sx * (sux[c] * syy - sxy * suy[c]) + sy * (sux[c] * sxy - sxx * suy[c]);
    *out[c] = clamp_flow(div_round(num, det));
  }
  return true;
}

void BlockFlow::track(const WorkImage& frame, VectorField& displacement, GridMask& valid) noexcept {
  if (!has_reference_) {
    // The first frame becomes the reference as a tare's frame does, in the deferred work: its
    // window models cost about as much as tracking a frame. Nothing is tracked in it.
    build_pyramid(frame, 1, pyramid_[kTareSlot]);
    has_reference_ = true;
    reference_pending_ = true;
    deferred_pending_ = true;
    last_frame_was_keyframe_ = true;
    keyframe_switches_ = 0;
    coarse_fallback_ = CoarseFallback{};
    valid_count_ = 0;
    displacement = VectorField{};
    valid = GridMask{};
    return;
  }
  // Level 0 from the warm start first. The coarse levels (pyramid, coarse tracking, retry of the
  // failed windows) only run when enough windows failed, e.g. after a jump larger than the
  // convergence range of level 0 (~1-2 px) or on the first frames after a tare; at steady state
  // the warm start is within a fraction of a pixel and level 0 alone converges.
  // The keyframe's window models are built in bounded pieces (see complete_keyframe()).
  run_deferred();
  ImagePyramid& cur = pyramid_[static_cast<std::size_t>(cur_index_)];
  build_pyramid(frame, 1, cur);
  coarse_built_ = false;
  int fresh = 0;
  const int failed = track_fine(false, &fresh);
  coarse_fallback_ = CoarseFallback{false, failed, fresh, 0, 0};
  if (config_.pyramid_levels > 1 && failed >= config_.coarse_trigger) {
    build_coarse();
    extend_pyramid(cur, config_.pyramid_levels);
    coarse_built_ = true;
    coarse_to_fine();
    const int before = valid_count_;
    track_fine(true);
    coarse_fallback_.ran = true;
    coarse_fallback_.recovered = valid_count_ - before;
    coarse_fallback_.coarse_windows = coarse_region_.tracked_count();
  }
  write_output(displacement, valid);
  ++frames_since_keyframe_;
  last_frame_was_keyframe_ = keyframe_switch_due();
  if (last_frame_was_keyframe_) {
    ++keyframe_switches_;
    frames_since_keyframe_ = 0;
  }
  deferred_pending_ = true;
}

}  // namespace tacse3::dsp
