// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: separable Gaussian smoothing of the grid flow by normalised convolution.
#include "tacse3/dsp/smoothing.hpp"

#include <cmath>

#include "smoothing_kernels.hpp"
#include "tacse3/dsp/fixed.hpp"

namespace tacse3::dsp {
namespace {

constexpr std::int64_t kFullWeight = std::int64_t{1} << (2 * FlowSmoother::kTapFrac);  // Q30

// floor((2a + b) / (2b)) for b > 0, i.e. a / b rounded half-up, the same rule as rshift_round.
// |a| <= 2^61 and b <= 2^31 keep 2a + b inside int64.
std::int64_t div_round_half_up(std::int64_t a, std::int64_t b) noexcept {
  const std::int64_t num = 2 * a + b;
  const std::int64_t den = 2 * b;
  std::int64_t q = num / den;
  if (num % den != 0 && num < 0) --q;  // C++ truncates towards zero; we want floor
  return q;
}

// out(p) = numerator / weight, or invalid below the support threshold: the last step of both paths.
[[gnu::always_inline]] inline void normalise(std::int64_t nx, std::int64_t ny, std::int64_t w,
                                             std::int64_t min_weight, VectorField& out,
                                             GridMask& out_valid, std::size_t p) noexcept {
  if (w == kFullWeight) {
    // Whole support valid and inside the grid: the division is a rounding shift.
    out.x.v[p] = sat32(rshift_round(nx, 2 * FlowSmoother::kTapFrac));
    out.y.v[p] = sat32(rshift_round(ny, 2 * FlowSmoother::kTapFrac));
    out_valid.v[p] = 1;
  } else if (w >= min_weight) {
    out.x.v[p] = sat32(div_round_half_up(nx, w));
    out.y.v[p] = sat32(div_round_half_up(ny, w));
    out_valid.v[p] = 1;
  } else {
    out.x.v[p] = 0;
    out.y.v[p] = 0;
    out_valid.v[p] = 0;
  }
}

}  // namespace

FlowSmoother::FlowSmoother() noexcept {
  (void)configure(SmoothingConfig{});
}

Status FlowSmoother::configure(const SmoothingConfig& config) noexcept {
  const double sigma = config.sigma_cells;
  if (!(sigma >= kMinSigmaCells && sigma <= kMaxSigmaCells)) return Status::kBadArgument;
  if (!(config.min_support > 0.0 && config.min_support <= 1.0)) return Status::kBadArgument;

  // Gaussian taps in double (init time), normalised to sum 1 over [-R, R], then rounded to Q15.
  int radius = static_cast<int>(std::ceil(3.0 * sigma));
  if (radius > kMaxRadius) radius = kMaxRadius;
  std::array<double, kMaxRadius + 1> g{};
  for (;;) {
    double sum = 0.0;
    for (int i = 0; i <= radius; ++i) {
      g[static_cast<std::size_t>(i)] = std::exp(-0.5 * (i * i) / (sigma * sigma));
      sum += (i == 0 ? 1.0 : 2.0) * g[static_cast<std::size_t>(i)];
    }
    for (int i = 0; i <= radius; ++i) g[static_cast<std::size_t>(i)] /= sum;
    // Every tap must stay >= 1 LSB, so that "weight == 2^30" identifies full support.
    if (radius > 1 && to_q32<kTapFrac>(g[static_cast<std::size_t>(radius)]) < 1) {
      --radius;
      continue;
    }
    break;
  }
  std::array<std::int32_t, kMaxRadius + 1> taps{};
  std::int32_t outer = 0;
  for (int i = 1; i <= radius; ++i) {
    taps[static_cast<std::size_t>(i)] = to_q32<kTapFrac>(g[static_cast<std::size_t>(i)]);
    outer += taps[static_cast<std::size_t>(i)];
  }
  // The centre tap absorbs the rounding so the taps sum to exactly 2^15: a constant field is then
  // reproduced bit-exactly and full support is recognised by weight == 2^30.
  taps[0] = (std::int32_t{1} << kTapFrac) - 2 * outer;

  config_ = config;
  radius_ = radius;
  taps_ = taps;
  // Kernel mass inside the grid per column / row (Q15): the weights of an all-valid field.
  for (int x = 0; x < kGridWidth; ++x) {
    std::int32_t w = 0;
    for (int i = -radius; i <= radius; ++i) {
      if (x + i >= 0 && x + i < kGridWidth) w += taps[static_cast<std::size_t>(i < 0 ? -i : i)];
    }
    edge_wx_[static_cast<std::size_t>(x)] = w;
  }
  for (int y = 0; y < kGridHeight; ++y) {
    std::int32_t w = 0;
    for (int i = -radius; i <= radius; ++i) {
      if (y + i >= 0 && y + i < kGridHeight) w += taps[static_cast<std::size_t>(i < 0 ? -i : i)];
    }
    edge_wy_[static_cast<std::size_t>(y)] = w;
  }
  min_weight_ = static_cast<std::int64_t>(std::llround(config.min_support * kFullWeight));
  if (min_weight_ < 1) min_weight_ = 1;
  return Status::kOk;
}

std::int32_t FlowSmoother::tap(int i) const noexcept {
  const int a = i < 0 ? -i : i;
  return a <= radius_ ? taps_[static_cast<std::size_t>(a)] : 0;
}

namespace {

// Row pass of one row: numerators sum_i g_i m w (int64, <= 2^46) and weights sum_i g_i m
// (<= 2^15). Symmetric taps multiply pair sums; outside the grid counts as invalid. The interior
// loop has no bound checks; kR > 0 fixes the radius at compile time (fully unrolled), kR == 0 uses
// the runtime radius r.
template <int kR, bool kWeights>
void row_pass(const std::int32_t* g, int r, const std::int32_t* mx, const std::int32_t* my,
              const std::int32_t* mw, std::int64_t* ox, std::int64_t* oy,
              std::int32_t* ow) noexcept {
  const int rr = kR > 0 ? kR : r;
  for (int x = 0; x < kGridWidth; ++x) {
    std::int64_t ax = static_cast<std::int64_t>(g[0]) * mx[x];
    std::int64_t ay = static_cast<std::int64_t>(g[0]) * my[x];
    std::int32_t aw = kWeights ? g[0] * mw[x] : 0;
    if (x >= rr && x + rr < kGridWidth) {
#pragma GCC unroll 10
      for (int i = 1; i <= rr; ++i) {
        ax += g[i] * (static_cast<std::int64_t>(mx[x - i]) + mx[x + i]);
        ay += g[i] * (static_cast<std::int64_t>(my[x - i]) + my[x + i]);
        if constexpr (kWeights) aw += g[i] * (mw[x - i] + mw[x + i]);
      }
    } else {
      for (int i = 1; i <= rr; ++i) {
        const bool left = x - i >= 0;
        const bool right = x + i < kGridWidth;
        ax += g[i] * ((left ? mx[x - i] : 0) + static_cast<std::int64_t>(right ? mx[x + i] : 0));
        ay += g[i] * ((left ? my[x - i] : 0) + static_cast<std::int64_t>(right ? my[x + i] : 0));
        if constexpr (kWeights) aw += g[i] * ((left ? mw[x - i] : 0) + (right ? mw[x + i] : 0));
      }
    }
    ox[x] = ax;
    oy[x] = ay;
    ow[x] = aw;
  }
}

// Column pass for output row y over all x: numerators (<= 2^61) and weights (<= 2^30) in int64,
// pairs of rows y - j, y + j per tap, inner loop along contiguous memory.
template <int kR>
void column_pass(const std::int32_t* g, int r, int y, const std::int64_t* rx,
                 const std::int64_t* ry, const std::int32_t* rw, bool weights, std::int64_t* nx,
                 std::int64_t* ny, std::int64_t* wt) noexcept {
  const int rr = kR > 0 ? kR : r;
  const std::size_t base = static_cast<std::size_t>(y * kGridWidth);
  const std::int64_t* cx = rx + base;
  const std::int64_t* cy = ry + base;
  const std::int32_t* cw = rw + base;
  for (std::size_t x = 0; x < kGridWidth; ++x) {
    nx[x] = g[0] * cx[x];
    ny[x] = g[0] * cy[x];
    wt[x] = weights ? static_cast<std::int64_t>(g[0]) * cw[x] : 0;
  }
  if (y >= rr && y + rr < kGridHeight) {
#pragma GCC unroll 10
    for (int j = 1; j <= rr; ++j) {
      const std::int64_t gj = g[j];
      const std::int64_t* ux = cx - j * kGridWidth;
      const std::int64_t* dx = cx + j * kGridWidth;
      const std::int64_t* uy = cy - j * kGridWidth;
      const std::int64_t* dy = cy + j * kGridWidth;
      for (std::size_t x = 0; x < kGridWidth; ++x) {
        nx[x] += gj * (ux[x] + dx[x]);
        ny[x] += gj * (uy[x] + dy[x]);
      }
      if (weights) {
        const std::int32_t* uw = cw - j * kGridWidth;
        const std::int32_t* dw = cw + j * kGridWidth;
        for (std::size_t x = 0; x < kGridWidth; ++x) wt[x] += gj * (uw[x] + dw[x]);
      }
    }
    return;
  }
  for (int j = -rr; j <= rr; ++j) {
    if (j == 0 || y + j < 0 || y + j >= kGridHeight) continue;
    const std::int64_t gj = g[j < 0 ? -j : j];
    for (std::size_t x = 0; x < kGridWidth; ++x) {
      nx[x] += gj * cx[static_cast<std::ptrdiff_t>(x) + j * kGridWidth];
      ny[x] += gj * cy[static_cast<std::ptrdiff_t>(x) + j * kGridWidth];
      if (weights) wt[x] += gj * cw[static_cast<std::ptrdiff_t>(x) + j * kGridWidth];
    }
  }
}

}  // namespace

void FlowSmoother::apply(const VectorField& in, const GridMask& valid, VectorField& out,
                         GridMask& out_valid) noexcept {
  bool all_valid = true;
  for (std::size_t p = 0; p < kGridCount; ++p) all_valid = all_valid && valid.v[p] != 0;
  const bool weights = !all_valid;  // as in apply_scalar
  constexpr int kPad = kMaxRadius;
  for (int y = 0; y < kGridHeight; ++y) {
    for (int x = 0; x < kGridWidth; ++x) {
      const std::size_t p = static_cast<std::size_t>(y * kGridWidth + x);
      const std::size_t q = static_cast<std::size_t>(y * kPadWidth + kPad + x);
      const bool ok = valid.v[p] != 0;
      pad_x_[q] = ok ? in.x.v[p] : 0;
      pad_y_[q] = ok ? in.y.v[p] : 0;
      pad_w_[q] = ok ? 1 : 0;
    }
  }
  detail::SmoothingSums s;
  s.taps = taps_.data();
  s.radius = radius_;
  s.weights = weights;
  s.in_x = pad_x_.data();
  s.in_y = pad_y_.data();
  s.in_w = pad_w_.data();
  s.hi_x = hi_x_.data();
  s.lo_x = lo_x_.data();
  s.hi_y = hi_y_.data();
  s.lo_y = lo_y_.data();
  s.row_w = sum_w_.data();
  s.num_x = row_x_.data();
  s.num_y = row_y_.data();
  s.num_w = row_w_.data();
  detail::smoothing_sums_simd(s);
  for (int y = 0; y < kGridHeight; ++y) {
    for (int x = 0; x < kGridWidth; ++x) {
      const std::size_t p = static_cast<std::size_t>(y * kGridWidth + x);
      const std::int64_t w =
          weights ? row_w_[p]
                  : static_cast<std::int64_t>(edge_wx_[static_cast<std::size_t>(x)]) *
                        edge_wy_[static_cast<std::size_t>(y)];
      normalise(row_x_[p], row_y_[p], w, min_weight_, out, out_valid, p);
    }
  }
}

void FlowSmoother::apply_scalar(const VectorField& in, const GridMask& valid, VectorField& out,
                                GridMask& out_valid) noexcept {
  const int r = radius_;
  const std::int32_t* g = taps_.data();

  bool all_valid = true;
  for (std::size_t p = 0; p < kGridCount; ++p) all_valid = all_valid && valid.v[p] != 0;
  // With every point valid the weights only depend on the distance to the edges: they come from
  // the configure-time tables edge_wx_ / edge_wy_ (the same sums), the weight channel is skipped
  // and the input is read in place. Otherwise masked copies: invalid points contribute neither
  // value nor weight.
  const bool weights = !all_valid;
  const std::int32_t* src_x = in.x.v.data();
  const std::int32_t* src_y = in.y.v.data();
  if (weights) {
    for (std::size_t p = 0; p < kGridCount; ++p) {
      const bool ok = valid.v[p] != 0;
      masked_x_[p] = ok ? in.x.v[p] : 0;
      masked_y_[p] = ok ? in.y.v[p] : 0;
      masked_w_[p] = ok ? 1 : 0;
    }
    src_x = masked_x_.data();
    src_y = masked_y_.data();
  }

  using RowPass = void (*)(const std::int32_t*, int, const std::int32_t*, const std::int32_t*,
                           const std::int32_t*, std::int64_t*, std::int64_t*, std::int32_t*);
  RowPass pass = &row_pass<0, true>;
  if (weights) {
    pass = r == 3 ? &row_pass<3, true> : (r == 2 ? &row_pass<2, true> : &row_pass<0, true>);
  } else {
    pass = r == 3 ? &row_pass<3, false> : (r == 2 ? &row_pass<2, false> : &row_pass<0, false>);
  }
  for (int y = 0; y < kGridHeight; ++y) {
    const std::size_t row = static_cast<std::size_t>(y * kGridWidth);
    pass(g, r, src_x + row, src_y + row, masked_w_.data() + row, row_x_.data() + row,
         row_y_.data() + row, row_w_.data() + row);
  }

  std::array<std::int64_t, kGridWidth> nx{};
  std::array<std::int64_t, kGridWidth> ny{};
  std::array<std::int64_t, kGridWidth> wt{};
  const auto cpass = r == 3 ? &column_pass<3> : (r == 2 ? &column_pass<2> : &column_pass<0>);
  for (int y = 0; y < kGridHeight; ++y) {
    cpass(g, r, y, row_x_.data(), row_y_.data(), row_w_.data(), weights, nx.data(), ny.data(),
          wt.data());
    for (int x = 0; x < kGridWidth; ++x) {
      const std::size_t p = static_cast<std::size_t>(y * kGridWidth + x);
      const std::size_t c = static_cast<std::size_t>(x);
      const std::int64_t w =
          weights ? wt[c]
                  : static_cast<std::int64_t>(edge_wx_[c]) * edge_wy_[static_cast<std::size_t>(y)];
      normalise(nx[c], ny[c], w, min_weight_, out, out_valid, p);
    }
  }
}

}  // namespace tacse3::dsp
