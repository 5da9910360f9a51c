// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: double-precision pyramid, window models and block flow (Eq. (dense_flow)).
#include "tacse3/dsp_ref/block_flow_ref.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "tacse3/dsp/coarse_region.hpp"
#include "tacse3/dsp/geometry.hpp"
#include "tacse3/dsp/pyramid.hpp"

namespace tacse3::dsp_ref {
namespace {

constexpr int kWin = dsp::kFlowWindow;
constexpr double kN = dsp::kFlowWindowPixels;
constexpr double kCentre = (kWin - 1) / 2.0;
constexpr int kJacobianPasses = 3;  // same as dsp::BlockFlow

PlaneRef make_plane(int w, int h) {
  PlaneRef p;
  p.width = w;
  p.height = h;
  p.px.assign(static_cast<std::size_t>(w * h), 0.0);
  return p;
}

// Bilinear sample; (x, y) with 0 <= x <= w - 1, 0 <= y <= h - 1.
double bilinear(const PlaneRef& p, double x, double y) {
  const int ix = std::min(static_cast<int>(std::floor(x)), p.width - 1);
  const int iy = std::min(static_cast<int>(std::floor(y)), p.height - 1);
  const double fx = x - ix;
  const double fy = y - iy;
  const int ix1 = std::min(ix + 1, p.width - 1);
  const int iy1 = std::min(iy + 1, p.height - 1);
  return (1 - fx) * (1 - fy) * p.at(ix, iy) + fx * (1 - fy) * p.at(ix1, iy) +
         (1 - fx) * fy * p.at(ix, iy1) + fx * fy * p.at(ix1, iy1);
}

void upsample_taps(int k, int n, int& near, int& far) {
  const int m = k >> 1;
  near = std::min(m, n - 1);
  far = std::clamp((k & 1) ? m + 1 : m - 1, 0, n - 1);
}

// Same neighbour-consensus test and gap filling as the fixed-point path (block_flow.cpp).
void reject_outliers_ref(int gw, int gh, const std::vector<double>& fx,
                         const std::vector<double>& fy, std::vector<std::uint8_t>& ok, double tol) {
  const std::vector<std::uint8_t> was = ok;
  for (int y = 0; y < gh; ++y) {
    for (int x = 0; x < gw; ++x) {
      const auto i = static_cast<std::size_t>(y * gw + x);
      if (!was[i]) continue;
      int tracked = 0, agree = 0;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= gw || ny >= gh) continue;
          const auto j = static_cast<std::size_t>(ny * gw + nx);
          if (!was[j]) continue;
          ++tracked;
          if (std::abs(fx[j] - fx[i]) <= tol && std::abs(fy[j] - fy[i]) <= tol) ++agree;
        }
      }
      if (agree < 2 || 2 * agree < tracked) ok[i] = 0;
    }
  }
}

void fill_missing_ref(int gw, int gh, std::vector<double>& fx, std::vector<double>& fy,
                      std::vector<std::uint8_t>& ok, int passes) {
  for (int pass = 0; pass < passes; ++pass) {
    const std::vector<std::uint8_t> was = ok;
    bool changed = false;
    for (int y = 0; y < gh; ++y) {
      for (int x = 0; x < gw; ++x) {
        const auto i = static_cast<std::size_t>(y * gw + x);
        if (was[i]) continue;
        double sx = 0, sy = 0;
        int count = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= gw || ny >= gh) continue;
            const auto j = static_cast<std::size_t>(ny * gw + nx);
            if (!was[j]) continue;
            sx += fx[j];
            sy += fy[j];
            ++count;
          }
        }
        if (count == 0) continue;
        fx[i] = sx / count;
        fy[i] = sy / count;
        ok[i] = 1;
        changed = true;
      }
    }
    if (!changed) break;
  }
}

}  // namespace

std::vector<PlaneRef> build_pyramid_ref(const dsp::WorkImage& in, int levels) {
  levels = std::clamp(levels, 1, dsp::kMaxPyramidLevels);
  std::vector<PlaneRef> pyr;
  PlaneRef l0 = make_plane(dsp::kWorkWidth, dsp::kWorkHeight);
  for (int i = 0; i < dsp::kWorkPixels; ++i) {
    l0.px[static_cast<std::size_t>(i)] = in.px[static_cast<std::size_t>(i)];
  }
  pyr.push_back(l0);
  static constexpr double kTap[4] = {1.0 / 8, 3.0 / 8, 3.0 / 8, 1.0 / 8};
  for (int l = 1; l < levels; ++l) {
    const PlaneRef& s = pyr.back();
    PlaneRef d = make_plane(s.width / 2, s.height / 2);
    for (int y = 0; y < d.height; ++y) {
      for (int x = 0; x < d.width; ++x) {
        double acc = 0.0;
        for (int a = 0; a < 4; ++a) {
          const int sy = std::clamp(2 * y - 1 + a, 0, s.height - 1);
          for (int b = 0; b < 4; ++b) {
            const int sx = std::clamp(2 * x - 1 + b, 0, s.width - 1);
            acc += kTap[a] * kTap[b] * s.at(sx, sy);
          }
        }
        d.at(x, y) = acc;
      }
    }
    pyr.push_back(d);
  }
  return pyr;
}

void gradients_ref(const PlaneRef& img, PlaneRef& gx, PlaneRef& gy) {
  gx = make_plane(img.width, img.height);
  gy = make_plane(img.width, img.height);
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      gx.at(x, y) = img.at(std::min(x + 1, img.width - 1), y) - img.at(std::max(x - 1, 0), y);
      gy.at(x, y) = img.at(x, std::min(y + 1, img.height - 1)) - img.at(x, std::max(y - 1, 0));
    }
  }
}

BlockFlowRef::BlockFlowRef(const dsp::BlockFlowConfig& config) : cfg_(config) {
  const auto n = static_cast<std::size_t>(dsp::kGridCount);
  dkx_.assign(n, 0.0);
  dky_.assign(n, 0.0);
  tx_.assign(n, 0.0);
  ty_.assign(n, 0.0);
  outx_.assign(n, 0.0);
  outy_.assign(n, 0.0);
  valid_.assign(n, 0);
  lost_.assign(n, 0);
  reanchored_.assign(n, 0);
}

void BlockFlowRef::tare(const dsp::WorkImage& frame) {
  tare_ = build_pyramid_ref(frame, cfg_.pyramid_levels);
  key_ = tare_;
  std::fill(dkx_.begin(), dkx_.end(), 0.0);
  std::fill(dky_.begin(), dky_.end(), 0.0);
  std::fill(tx_.begin(), tx_.end(), 0.0);
  std::fill(ty_.begin(), ty_.end(), 0.0);
  std::fill(outx_.begin(), outx_.end(), 0.0);
  std::fill(outy_.begin(), outy_.end(), 0.0);
  std::fill(lost_.begin(), lost_.end(), std::uint8_t{0});
  std::fill(reanchored_.begin(), reanchored_.end(), std::uint8_t{0});
  take_keyframe();
  for (int i = 0; i < dsp::kGridCount; ++i) {
    valid_[static_cast<std::size_t>(i)] = models_[0][static_cast<std::size_t>(i)].valid ? 1 : 0;
  }
  has_reference_ = true;
  switches_ = 0;
}

void BlockFlowRef::take_keyframe() {
  const int levels = cfg_.pyramid_levels;
  gx_.assign(static_cast<std::size_t>(levels), {});
  gy_.assign(static_cast<std::size_t>(levels), {});
  models_.assign(static_cast<std::size_t>(levels), {});
  for (int l = 0; l < levels; ++l) build_level(l);
  key_valid_count_ = 0;
  for (const WindowRef& m : models_[0]) key_valid_count_ += m.valid ? 1 : 0;
}

// Gradients and window models of one level of key_, placed by dkx_/dky_ (see
// dsp::BlockFlow::build_models()).
void BlockFlowRef::build_level(int l) {
  const double mt = cfg_.min_texture;
  const double tau = 4096.0 * 64.0 * mt * mt;
  const double rho = cfg_.min_eigen_ratio;
  const double kappa = rho / ((1 + rho) * (1 + rho));
  {
    const auto ls = static_cast<std::size_t>(l);
    gradients_ref(key_[ls], gx_[ls], gy_[ls]);
    const int gw = dsp::flow_grid_width(l);
    const int gh = dsp::flow_grid_height(l);
    const int w = key_[ls].width;
    const int h = key_[ls].height;
    const int block = 1 << l;
    const double max_off = l == 0 ? 3.5 : 4.0;
    models_[ls].assign(static_cast<std::size_t>(gw * gh), WindowRef{});
    for (int jy = 0; jy < gh; ++jy) {
      for (int jx = 0; jx < gw; ++jx) {
        WindowRef& m = models_[ls][static_cast<std::size_t>(jy * gw + jx)];
        double dx = 0, dy = 0;
        for (int by = 0; by < block; ++by) {
          for (int bx = 0; bx < block; ++bx) {
            const auto i =
                static_cast<std::size_t>((jy * block + by) * dsp::kGridWidth + jx * block + bx);
            dx += dkx_[i];
            dy += dky_[i];
          }
        }
        dx /= block * block * block;
        dy /= block * block * block;
        const double px = dsp::kGridStride * jx + 1.5 + dx;
        const double py = dsp::kGridStride * jy + 1.5 + dy;
        m.ox = std::clamp(static_cast<int>(std::floor(px - kCentre + 0.5)), 1, w - kWin - 1);
        m.oy = std::clamp(static_cast<int>(std::floor(py - kCentre + 0.5)), 1, h - kWin - 1);
        if (l == 0 && given_origins_ != nullptr) {
          const auto g = static_cast<std::size_t>(jy * gw + jx);
          m.ox = (*given_origins_->origin_x)[g];
          m.oy = (*given_origins_->origin_y)[g];
        }
        m.offset_x = px - (m.ox + kCentre);
        m.offset_y = py - (m.oy + kCentre);
        if (std::abs(m.offset_x) > max_off || std::abs(m.offset_y) > max_off) continue;
        const bool lost = l == 0 && lost_[static_cast<std::size_t>(jy * gw + jx)] != 0;
        double sgx = 0, sgy = 0, sxx = 0, sxy = 0, syy = 0, st = 0, stt = 0;
        double s_xx = 0, s_yy = 0;
        Eigen::Matrix<double, 3, 2> gc = Eigen::Matrix<double, 3, 2>::Zero();
        double sgxt = 0, sgyt = 0;
        const PlaneRef& kp = key_[ls];
        for (int r = 0; r < kWin; ++r) {
          for (int c = 0; c < kWin; ++c) {
            const int x = m.ox + c, y = m.oy + r;
            const double a = gx_[ls].at(x, y);
            const double b = gy_[ls].at(x, y);
            const double t = kp.at(x, y);
            const double txx =
                kp.at(std::min(x + 1, w - 1), y) + kp.at(std::max(x - 1, 0), y) - 2 * t;
            const double tyy =
                kp.at(x, std::min(y + 1, h - 1)) + kp.at(x, std::max(y - 1, 0)) - 2 * t;
            s_xx += txx;
            s_yy += tyy;
            gc(0, 0) += a * txx;
            gc(1, 0) += b * txx;
            gc(0, 1) += a * tyy;
            gc(1, 1) += b * tyy;
            gc(2, 0) += t * txx;
            gc(2, 1) += t * tyy;
            sgxt += a * t;
            sgyt += b * t;
            sgx += a;
            sgy += b;
            sxx += a * a;
            sxy += a * b;
            syy += b * b;
            st += t;
            stt += t * t;
          }
        }
        m.gsum_x = sgx;
        m.gsum_y = sgy;
        m.template_energy = kN * stt - st * st;
        m.tsum = st;
        const Eigen::Vector3d sums(sgx, sgy, st);
        const Eigen::Vector2d s2(s_xx, s_yy);
        m.curvature = kN * gc - sums * s2.transpose();
        m.gain_e = kN * stt - st * st;
        if (m.gain_e <= 0) continue;
        m.gain_k = Eigen::Vector2d(kN * sgxt - sgx * st, kN * sgyt - sgy * st);
        if (std::abs(m.gain_k.x()) > 64 * m.gain_e || std::abs(m.gain_k.y()) > 64 * m.gain_e)
          continue;
        m.h64 << kN * sxx - sgx * sgx, kN * sxy - sgx * sgy, kN * sxy - sgx * sgy,
            kN * syy - sgy * sgy;
        m.h64 -= m.gain_k * m.gain_k.transpose() / m.gain_e;
        const double a = m.h64(0, 0), b = m.h64(0, 1), c = m.h64(1, 1);
        const double det = a * c - b * b;
        if (a <= 0 || c <= 0 || det <= 0) continue;
        // The texture and conditioning tests decide validity; a window that fails them (or is
        // lost) still gets its inverse and moments, so that a decision-locked run can track it
        // where the fixed-point path's tests passed (FlowDecision).
        const bool textured = a >= tau && c >= tau && (a - tau) * (c - tau) >= b * b &&
                              det >= kappa * (a + c) * (a + c);
        m.h64_inv = m.h64.inverse();
        {
          const Eigen::Vector2d gbar(sgx / kN, sgy / kN);
          const double tbar = st / kN;
          const Eigen::Vector2d q = m.gain_k / m.gain_e;
          Eigen::Matrix2d mx = Eigen::Matrix2d::Zero(), my = Eigen::Matrix2d::Zero();
          for (int r = 0; r < kWin; ++r) {
            for (int cc = 0; cc < kWin; ++cc) {
              const int x = m.ox + cc, y = m.oy + r;
              const Eigen::Vector2d gt = Eigen::Vector2d(gx_[ls].at(x, y), gy_[ls].at(x, y)) - gbar;
              const Eigen::Vector2d ge = gt - q * (kp.at(x, y) - tbar);
              mx += ge * (gt + gbar).transpose() * (cc - kCentre);
              my += ge * (gt + gbar).transpose() * (r - kCentre);
            }
          }
          m.p_x = m.h64_inv * (kN * mx);
          m.p_y = m.h64_inv * (kN * my);
        }
        m.solvable = true;
        m.valid = textured && !lost;
      }
    }
  }
}

BlockFlowRef::Result BlockFlowRef::track_window(int level, const WindowRef& m, double ux, double uy,
                                                int iterations, bool inside) const {
  const auto ls = static_cast<std::size_t>(level);
  const PlaneRef& cur = cur_[ls];
  const PlaneRef& key = key_[ls];
  const double max_x = cur.width - kWin;
  const double max_y = cur.height - kWin;
  double step_x = 0, step_y = 0;
  bool converged = false;
  double s_r = 0, s_rr = 0;
  // Optional sampling grid of the fixed-point path: positions rounded to 1/32 px, the step
  // added to the rounded position, stop when the rounded position repeats.
  const auto grid = [&](double v) {
    return fixed_point_sampling_ ? std::floor(v * 32 + 0.5) / 32 : v;
  };
  for (int it = 0; it < iterations; ++it) {
    if (inside) {
      ux = std::clamp(ux, static_cast<double>(-m.ox), max_x - m.ox);
      uy = std::clamp(uy, static_cast<double>(-m.oy), max_y - m.oy);
    }
    ux = grid(ux);
    uy = grid(uy);
    const double sx = m.ox + ux;
    const double sy = m.oy + uy;
    if (sx < 0 || sy < 0 || sx > max_x || sy > max_y) return {ux, uy, false, true};
    double s_gx = 0, s_gy = 0, s_t = 0;
    s_r = 0;
    s_rr = 0;
    for (int r = 0; r < kWin; ++r) {
      for (int c = 0; c < kWin; ++c) {
        const double res = bilinear(cur, sx + c, sy + r) - key.at(m.ox + c, m.oy + r);
        s_gx += gx_[ls].at(m.ox + c, m.oy + r) * res;
        s_gy += gy_[ls].at(m.ox + c, m.oy + r) * res;
        s_t += key.at(m.ox + c, m.oy + r) * res;
        s_r += res;
        s_rr += res * res;
      }
    }
    // Bilinear smoothing compensation: the sample is T + f(1-f)/2 (Txx, Tyy) to second order.
    const double fx = sx - std::floor(sx), fy = sy - std::floor(sy);
    const Eigen::Vector2d smooth(fx * (1 - fx) / 2, fy * (1 - fy) / 2);
    const Eigen::Vector3d b = Eigen::Vector3d(kN * s_gx - m.gsum_x * s_r,
                                              kN * s_gy - m.gsum_y * s_r, kN * s_t - m.tsum * s_r) -
                              m.curvature * smooth;
    // Local gain eliminated (Schur complement): b_eff = b_g - k b_T / e.
    const Eigen::Vector2d b64 = b.head<2>() - m.gain_k * (b.z() / m.gain_e);
    // Gradient g is twice the derivative: (g / 2) . du = -(r - mean r)  =>  du = -2 H64^-1 b64.
    const Eigen::Vector2d du = -2.0 * m.h64_inv * b64;
    step_x = std::clamp(du.x(), -cfg_.max_step_px, cfg_.max_step_px);
    step_y = std::clamp(du.y(), -cfg_.max_step_px, cfg_.max_step_px);
    const double px = ux, py = uy;
    ux += step_x;
    uy += step_y;
    const bool done = fixed_point_sampling_
                          ? (grid(ux) == px && grid(uy) == py)
                          : (std::abs(step_x) < 1.0 / 64 && std::abs(step_y) < 1.0 / 64);
    if (done) {
      converged = true;
      break;
    }
  }
  if (!converged) {
    converged =
        std::abs(step_x) <= cfg_.converged_step_px && std::abs(step_y) <= cfg_.converged_step_px;
  }
  const double e_r = std::max(0.0, kN * s_rr - s_r * s_r);
  const bool matched = e_r <= cfg_.max_residual_ratio * m.template_energy;
  return {ux, uy, converged && matched, false};
}

// Same local affine fit as dsp::BlockFlow::fit_from_neighbours(), in double.
bool BlockFlowRef::fit_from_neighbours(int gx, int gy, double& ux, double& uy) const {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Matrix<double, 3, 2> b = Eigen::Matrix<double, 3, 2>::Zero();
  int n = 0;
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) {
      const int x = gx + dx, y = gy + dy;
      if ((dx == 0 && dy == 0) || x < 0 || y < 0 || x >= dsp::kGridWidth || y >= dsp::kGridHeight) {
        continue;
      }
      const auto j = static_cast<std::size_t>(y * dsp::kGridWidth + x);
      if (!valid_[j]) continue;
      const Eigen::Vector3d r(1.0, dx, dy);
      a += r * r.transpose();
      b.col(0) += r * outx_[j];
      b.col(1) += r * outy_[j];
      ++n;
    }
  }
  if (n < 6 || a.determinant() <= 0.5) return false;
  const Eigen::Matrix<double, 3, 2> coef = a.inverse() * b;
  ux = coef(0, 0);
  uy = coef(0, 1);
  return true;
}

// Warm starts (block means of the level-0 window flow) and the coarse levels, top down, as in
// dsp::BlockFlow::coarse_to_fine(): only the coarse windows that the retried level-0 windows
// draw on are tracked (dsp::CoarseRegion). Leaves the level-1 correction in cx_[1], cy_[1].
void BlockFlowRef::coarse_levels(const dsp::GridMask* follow_valid) {
  const int levels = cfg_.pyramid_levels;
  std::vector<std::uint8_t> retry(static_cast<std::size_t>(dsp::kGridCount), 0);
  for (std::size_t i = 0; i < retry.size(); ++i) {
    const WindowRef& m = models_[0][i];
    const bool followed = follow_valid != nullptr && follow_valid->v[i] != 0 && m.solvable;
    retry[i] = static_cast<std::uint8_t>(!ok_[i] && (m.valid || followed));
  }
  dsp::CoarseRegion region;
  region.build(retry.data(), levels);
  std::vector<std::vector<double>>& cx = cx_;
  std::vector<std::vector<double>>& cy = cy_;
  cx.assign(static_cast<std::size_t>(levels), {});
  cy.assign(static_cast<std::size_t>(levels), {});
  // Warm starts (block means of the level-0 window flow) and coarse-to-fine corrections.
  std::vector<std::vector<double>> wx(static_cast<std::size_t>(levels)),
      wy(static_cast<std::size_t>(levels));
  for (int l = 1; l < levels; ++l) {
    const int gw = dsp::flow_grid_width(l), gh = dsp::flow_grid_height(l), block = 1 << l;
    const auto ls = static_cast<std::size_t>(l);
    wx[ls].assign(static_cast<std::size_t>(gw * gh), 0.0);
    wy[ls].assign(static_cast<std::size_t>(gw * gh), 0.0);
    cx[ls].assign(static_cast<std::size_t>(gw * gh), 0.0);
    cy[ls].assign(static_cast<std::size_t>(gw * gh), 0.0);
    for (int jy = 0; jy < gh; ++jy) {
      for (int jx = 0; jx < gw; ++jx) {
        double sx = 0, sy = 0;
        for (int by = 0; by < block; ++by) {
          for (int bx = 0; bx < block; ++bx) {
            const auto i =
                static_cast<std::size_t>((jy * block + by) * dsp::kGridWidth + jx * block + bx);
            sx += tx_[i];
            sy += ty_[i];
          }
        }
        wx[ls][static_cast<std::size_t>(jy * gw + jx)] = sx / (block * block);
        wy[ls][static_cast<std::size_t>(jy * gw + jx)] = sy / (block * block);
      }
    }
  }
  auto upsampled = [&](int l, int jx, int jy, double& ox, double& oy) {
    ox = 0;
    oy = 0;
    if (l + 1 >= levels) return;
    const int cw = dsp::flow_grid_width(l + 1), ch = dsp::flow_grid_height(l + 1);
    int x0, x1, y0, y1;
    upsample_taps(jx, cw, x0, x1);
    upsample_taps(jy, ch, y0, y1);
    const auto& ax = cx[static_cast<std::size_t>(l + 1)];
    const auto& ay = cy[static_cast<std::size_t>(l + 1)];
    auto at = [&](const std::vector<double>& a, int x, int y) {
      return a[static_cast<std::size_t>(y * cw + x)];
    };
    ox = (9 * at(ax, x0, y0) + 3 * at(ax, x1, y0) + 3 * at(ax, x0, y1) + at(ax, x1, y1)) / 16;
    oy = (9 * at(ay, x0, y0) + 3 * at(ay, x1, y0) + 3 * at(ay, x0, y1) + at(ay, x1, y1)) / 16;
  };
  for (int l = levels - 1; l >= 1; --l) {
    const int gw = dsp::flow_grid_width(l), gh = dsp::flow_grid_height(l);
    const auto ls = static_cast<std::size_t>(l);
    const double scale = 1 << l;
    std::vector<double> fx(static_cast<std::size_t>(gw * gh)), fy(fx.size());
    std::vector<std::uint8_t> ok(fx.size(), 0);
    for (int jy = 0; jy < gh; ++jy) {
      for (int jx = 0; jx < gw; ++jx) {
        const auto i = static_cast<std::size_t>(jy * gw + jx);
        double ux, uy;
        upsampled(l, jx, jy, ux, uy);
        fx[i] = wx[ls][i] + ux;
        fy[i] = wy[ls][i] + uy;
        const WindowRef& m = models_[ls][i];
        if (!m.valid || !region.tracked(l, static_cast<int>(i))) continue;
        const Result r = track_window(l, m, fx[i] / scale, fy[i] / scale, cfg_.coarse_iterations);
        if (!r.valid) continue;
        fx[i] = r.ux * scale;
        fy[i] = r.uy * scale;
        ok[i] = 1;
      }
    }
    reject_outliers_ref(gw, gh, fx, fy, ok, scale);
    fill_missing_ref(gw, gh, fx, fy, ok, gw);
    for (std::size_t i = 0; i < fx.size(); ++i) {
      cx[ls][i] = fx[i] - wx[ls][i];
      cy[ls][i] = fy[i] - wy[ls][i];
    }
  }
}

// Correction of level l + 1 upsampled to point (jx, jy) of level l (zero above the top).
void BlockFlowRef::coarse_correction(int l, int jx, int jy, double& ox, double& oy) const {
  ox = 0;
  oy = 0;
  if (l + 1 >= cfg_.pyramid_levels) return;
  const int cw = dsp::flow_grid_width(l + 1), ch = dsp::flow_grid_height(l + 1);
  int x0, x1, y0, y1;
  upsample_taps(jx, cw, x0, x1);
  upsample_taps(jy, ch, y0, y1);
  const auto& ax = cx_[static_cast<std::size_t>(l + 1)];
  const auto& ay = cy_[static_cast<std::size_t>(l + 1)];
  auto at = [&](const std::vector<double>& a, int x, int y) {
    return a[static_cast<std::size_t>(y * cw + x)];
  };
  ox = (9 * at(ax, x0, y0) + 3 * at(ax, x1, y0) + 3 * at(ax, x0, y1) + at(ax, x1, y1)) / 16;
  oy = (9 * at(ay, x0, y0) + 3 * at(ay, x1, y0) + 3 * at(ay, x0, y1) + at(ay, x1, y1)) / 16;
}

// Level 0 (see dsp::BlockFlow::track_fine()): first pass from the warm start, or a retry of
// the failed windows with the coarse correction; consensus; returns the failure count.
int BlockFlowRef::track_fine(bool retry, const dsp::GridMask* follow_valid) {
  const auto n = static_cast<std::size_t>(dsp::kGridCount);
  fx_.resize(n);
  fy_.resize(n);
  ok_.resize(n);
  est_x_.resize(n);
  est_y_.resize(n);
  est_ok_.resize(n);
  int failed = 0;
  for (int gy = 0; gy < dsp::kGridHeight; ++gy) {
    for (int gx = 0; gx < dsp::kGridWidth; ++gx) {
      const auto i = static_cast<std::size_t>(gy * dsp::kGridWidth + gx);
      if (retry && ok_[i]) continue;
      ok_[i] = 0;
      if (!retry) est_ok_[i] = 0;  // a retry that leaves the image keeps the first estimate
      fx_[i] = tx_[i];
      fy_[i] = ty_[i];
      const WindowRef& m = models_[0][i];
      // Decision-locked: a window the fixed-point path tracked has a valid model there, so it is
      // tracked here like one (retry, consensus test) even where this model failed a texture
      // test or was lost at the last switch.
      const bool followed = follow_valid != nullptr && follow_valid->v[i] != 0 && m.solvable;
      if (!m.valid && !followed) continue;
      double ux = 0, uy = 0;
      if (retry) coarse_correction(0, gx, gy, ux, uy);
      const Result r = track_window(0, m, tx_[i] + ux, ty_[i] + uy, cfg_.fine_iterations, followed);
      if (!r.outside) {
        est_x_[i] = r.ux;
        est_y_[i] = r.uy;
        est_ok_[i] = 1;
      }
      if (!r.valid) {
        failed += r.outside ? 0 : 1;
        continue;
      }
      fx_[i] = r.ux;
      fy_[i] = r.uy;
      ok_[i] = 1;
    }
  }
  const std::vector<std::uint8_t> before = ok_;
  reject_outliers_ref(dsp::kGridWidth, dsp::kGridHeight, fx_, fy_, ok_, 1.0);
  for (std::size_t i = 0; i < n; ++i) {
    valid_[i] = ok_[i];
    failed += (before[i] && !ok_[i]) ? 1 : 0;
    if (!ok_[i]) continue;
    tx_[i] = fx_[i];
    ty_[i] = fy_[i];
  }
  return failed;
}

// Output with the first-order corrections (see dsp::BlockFlow::write_output()).
void BlockFlowRef::write_output() {
  const auto n = static_cast<std::size_t>(dsp::kGridCount);
  // J from the
  // neighbours' window-centre flows, refined once (the raw window flows carry their own
  // measurement-point bias P J, which would otherwise leak into J).
  std::vector<double> fcx(tx_), fcy(ty_);
  auto derivative = [&](int gx, int gy, bool along_x, double& dtx, double& dty) {
    const int sx = along_x ? 1 : 0, sy = along_x ? 0 : 1;
    const int lx = gx - sx, ly = gy - sy, rx = gx + sx, ry = gy + sy;
    auto usable = [&](int x, int y) {
      return x >= 0 && y >= 0 && x < dsp::kGridWidth && y < dsp::kGridHeight &&
             valid_[static_cast<std::size_t>(y * dsp::kGridWidth + x)];
    };
    auto origin = [&](int x, int y) {
      const WindowRef& m = models_[0][static_cast<std::size_t>(y * dsp::kGridWidth + x)];
      return along_x ? m.ox : m.oy;
    };
    const bool has_l = usable(lx, ly), has_r = usable(rx, ry);
    dtx = 0;
    dty = 0;
    if (!has_l && !has_r) return;
    int ax = has_l ? lx : gx, ay = has_l ? ly : gy, bx = has_r ? rx : gx, by = has_r ? ry : gy;
    int spacing = origin(bx, by) - origin(ax, ay);
    if (spacing < 3) {  // widened stencil at the border, as in dsp::BlockFlow
      if (usable(bx + sx, by + sy)) {
        bx += sx;
        by += sy;
      } else if (usable(ax - sx, ay - sy)) {
        ax -= sx;
        ay -= sy;
      }
      spacing = origin(bx, by) - origin(ax, ay);
    }
    if (spacing < 3 || spacing > 32) return;
    const auto ia = static_cast<std::size_t>(ay * dsp::kGridWidth + ax);
    const auto ib = static_cast<std::size_t>(by * dsp::kGridWidth + bx);
    dtx = std::clamp((fcx[ib] - fcx[ia]) / spacing, -0.5, 0.5);
    dty = std::clamp((fcy[ib] - fcy[ia]) / spacing, -0.5, 0.5);
  };
  std::vector<Eigen::Matrix2d> jac(n, Eigen::Matrix2d::Zero());
  for (int pass = 0; pass < kJacobianPasses; ++pass) {
    for (int gy = 0; gy < dsp::kGridHeight; ++gy) {
      for (int gx = 0; gx < dsp::kGridWidth; ++gx) {
        const auto i = static_cast<std::size_t>(gy * dsp::kGridWidth + gx);
        if (!valid_[i]) continue;
        double jxx, jyx, jxy, jyy;
        derivative(gx, gy, true, jxx, jyx);
        derivative(gx, gy, false, jxy, jyy);
        jac[i] << jxx, jxy, jyx, jyy;
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (!valid_[i]) continue;
      const WindowRef& m = models_[0][i];
      const Eigen::Vector2d c =
          Eigen::Vector2d(tx_[i], ty_[i]) - m.p_x * jac[i].col(0) - m.p_y * jac[i].col(1);
      fcx[i] = c.x();
      fcy[i] = c.y();
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!valid_[i]) continue;
    const WindowRef& m = models_[0][i];
    outx_[i] = dkx_[i] + fcx[i] + jac[i](0, 0) * m.offset_x + jac[i](0, 1) * m.offset_y;
    outy_[i] = dky_[i] + fcy[i] + jac[i](1, 0) * m.offset_x + jac[i](1, 1) * m.offset_y;
  }
}

// Direct match of the current frame against the tare frame (see dsp::BlockFlow::re_anchor()).
// follow (may be null): replace exactly the points the fixed path re-anchored.
void BlockFlowRef::re_anchor(const FlowDecision* follow) {
  const dsp::GridMask* follow_re = follow != nullptr ? follow->reanchored : nullptr;
  const std::vector<double> reported_x = outx_, reported_y = outy_;
  const std::vector<std::uint8_t> reported_valid = valid_;
  const std::vector<double> chained_x = dkx_, chained_y = dky_;
  const std::vector<std::uint8_t> chained_lost = lost_;
  const std::vector<PlaneRef> keyframe = key_;
  key_ = tare_;
  std::fill(dkx_.begin(), dkx_.end(), 0.0);
  std::fill(dky_.begin(), dky_.end(), 0.0);
  std::fill(lost_.begin(), lost_.end(), std::uint8_t{0});
  build_level(0);
  tx_ = chained_x;
  ty_ = chained_y;
  track_fine(false, follow_re);
  if (follow_re != nullptr) follow_validity(*follow_re, chained_x, chained_y);
  outx_ = chained_x;
  outy_ = chained_y;
  write_output();
  const double tol = cfg_.reanchor_tolerance_px;
  dkx_ = chained_x;
  dky_ = chained_y;
  lost_ = chained_lost;
  for (std::size_t i = 0; i < dkx_.size(); ++i) {
    if (!valid_[i]) continue;  // followed: valid_ is exactly the fixed path's re-anchored set
    if (follow_re == nullptr && !chained_lost[i]) {
      const bool agrees =
          std::abs(outx_[i] - chained_x[i]) <= tol && std::abs(outy_[i] - chained_y[i]) <= tol;
      if (!agrees) continue;
    }
    dkx_[i] = outx_[i];
    dky_[i] = outy_[i];
    lost_[i] = 0;
    reanchored_[i] = 1;
  }
  key_ = keyframe;
  outx_ = reported_x;
  outy_ = reported_y;
  valid_ = reported_valid;
}

// Decision-locked mode: the keyframe's level-0 windows sit where the fixed path placed its own
// (only the windows' models change; the keyframe displacements and window flows are the same).
void BlockFlowRef::follow_origins(const FlowDecision& follow) {
  if (follow.origin_x == nullptr || follow.origin_y == nullptr) return;
  bool same = true;
  for (std::size_t i = 0; i < models_[0].size(); ++i) {
    const int ox = (*follow.origin_x)[i], oy = (*follow.origin_y)[i];
    if (ox < 1 || oy < 1) return;  // windows sit 1 px inside the image: not built yet
    same = same && models_[0][i].ox == ox && models_[0][i].oy == oy;
  }
  if (same) return;
  given_origins_ = &follow;
  build_level(0);
  given_origins_ = nullptr;
  key_valid_count_ = 0;
  for (const WindowRef& m : models_[0]) key_valid_count_ += m.valid ? 1 : 0;
}

// Decision-locked mode: the fixed-point path's valid set replaces this frame's own. A point the
// fixed path tracked takes the reference's own estimate even where its own tests failed (it
// holds its previous value only if its window left the image or has no model); a point the
// fixed path did not track holds its previous value, as it would have there.
void BlockFlowRef::follow_validity(const dsp::GridMask& valid, const std::vector<double>& held_x,
                                   const std::vector<double>& held_y) {
  for (std::size_t i = 0; i < valid_.size(); ++i) {
    const std::uint8_t want = valid.v[i] != 0 ? 1 : 0;
    if (want == valid_[i]) continue;
    valid_[i] = want;
    if (want != 0) {
      if (est_ok_[i] == 0) continue;
      tx_[i] = est_x_[i];
      ty_[i] = est_y_[i];
    } else {
      tx_[i] = held_x[i];
      ty_[i] = held_y[i];
    }
  }
}

void BlockFlowRef::track(const dsp::WorkImage& frame, std::vector<double>& dx,
                         std::vector<double>& dy, std::vector<std::uint8_t>& valid,
                         const FlowDecision* follow) {
  const auto n = static_cast<std::size_t>(dsp::kGridCount);
  if (!has_reference_) {  // the implicit tare: nothing tracked (dsp::BlockFlow::track())
    tare(frame);
    dx.assign(n, 0.0);
    dy.assign(n, 0.0);
    valid.assign(n, 0);
    return;
  }
  cur_ = build_pyramid_ref(frame, cfg_.pyramid_levels);
  const dsp::GridMask* follow_valid = follow != nullptr ? follow->valid : nullptr;
  // Not in a switch frame: the fixed path's origins may already be its new keyframe's there.
  if (follow_valid != nullptr && !follow->keyframe_switch) follow_origins(*follow);
  std::vector<double> held_x, held_y;
  if (follow_valid != nullptr) {
    held_x = tx_;
    held_y = ty_;
  }
  int failed = track_fine(false, follow_valid);
  if (cfg_.pyramid_levels > 1 && failed >= cfg_.coarse_trigger) {
    coarse_levels(follow_valid);
    track_fine(true, follow_valid);
  }
  if (follow_valid != nullptr) follow_validity(*follow_valid, held_x, held_y);
  int count = 0;
  for (const std::uint8_t v : valid_) count += v;
  write_output();
  dx = outx_;
  dy = outy_;
  valid = valid_;

  // Keyframe policy (see dsp::BlockFlow::maybe_switch_keyframe()).
  if (cfg_.keyframe_switch_px <= 0) return;
  if (follow_valid != nullptr) {
    if (!follow->keyframe_switch) return;
  } else {
    double max_sq = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (valid_[i]) max_sq = std::max(max_sq, tx_[i] * tx_[i] + ty_[i] * ty_[i]);
    }
    if (max_sq <= cfg_.keyframe_switch_px * cfg_.keyframe_switch_px) return;
    if (count < cfg_.keyframe_min_valid_fraction * key_valid_count_) return;
  }
  dkx_ = outx_;
  dky_ = outy_;
  std::fill(reanchored_.begin(), reanchored_.end(), std::uint8_t{0});
  for (int gy = 0; gy < dsp::kGridHeight; ++gy) {
    for (int gx = 0; gx < dsp::kGridWidth; ++gx) {
      const auto i = static_cast<std::size_t>(gy * dsp::kGridWidth + gx);
      lost_[i] = 0;
      if (valid_[i]) continue;
      if (!fit_from_neighbours(gx, gy, dkx_[i], dky_[i])) lost_[i] = 1;
    }
  }
  const FlowDecision* follow_switch = follow_valid != nullptr ? follow : nullptr;
  if (cfg_.reanchor_tolerance_px > 0) re_anchor(follow_switch);
  if (follow_switch != nullptr && follow_switch->lost != nullptr) {
    for (std::size_t i = 0; i < n; ++i) lost_[i] = follow_switch->lost->v[i] != 0 ? 1 : 0;
  }
  key_ = cur_;
  std::fill(tx_.begin(), tx_.end(), 0.0);
  std::fill(ty_.begin(), ty_.end(), 0.0);
  take_keyframe();
  ++switches_;
}

}  // namespace tacse3::dsp_ref
