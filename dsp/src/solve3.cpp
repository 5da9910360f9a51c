// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: fixed 3x3 regularised symmetric solve with validity and confidence (double).
#include "tacse3/dsp/solve3.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace tacse3::dsp {
namespace {

bool all_finite(const Eigen::Matrix3d& A, const Eigen::Vector3d& b) noexcept {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(b(i))) return false;
    for (int j = 0; j < 3; ++j) {
      if (!std::isfinite(A(i, j))) return false;
    }
  }
  return true;
}

}  // namespace

Solve3Result solve3(const Eigen::Matrix3d& A_in, const Eigen::Vector3d& b,
                    const Solve3Options& opt) noexcept {
  Solve3Result r;
  if (!all_finite(A_in, b) || !std::isfinite(opt.lambda_rel) || !std::isfinite(opt.lambda_abs) ||
      !std::isfinite(opt.rcond_min)) {
    return r;
  }
  // Normal equations are symmetric by construction; symmetrise so round-off cannot make the
  // eigen-solver or the LDLᵀ see a non-symmetric matrix.
  const Eigen::Matrix3d A = 0.5 * (A_in + A_in.transpose());
  const double scale = A.trace() / 3.0;
  // Entries are sums of squares, so scale ≥ max|A_ii|/3 ≥ 0; a non-positive trace means an empty
  // (or invalid, non-PSD) system.
  if (!(scale > 0.0)) return r;

  // Confidence: eigenvalues of the symmetric 3x3 (fixed-size, no heap). The iterative solver,
  // not computeDirect: the closed form loses ~half the digits on repeated eigenvalues, which is
  // exactly the rank-deficient case whose rank we must count.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.compute(A, Eigen::EigenvaluesOnly);
  const Eigen::Vector3d ev = eig.eigenvalues();  // ascending
  const double ev_max = ev(2);
  if (ev_max > 0.0) {
    const double ev_min = ev(0) > 0.0 ? ev(0) : 0.0;
    r.rcond = ev_min / ev_max;
    for (int i = 0; i < 3; ++i) r.rank += (ev(i) >= opt.rcond_min * ev_max) ? 1 : 0;
  }

  // Tikhonov: (A + λI) is SPD for λ > 0, so LDLᵀ without pivoting is stable.
  const double lambda = std::fmax(opt.lambda_rel, 0.0) * scale + std::fmax(opt.lambda_abs, 0.0);
  r.lambda = lambda;
  const double a00 = A(0, 0) + lambda, a11 = A(1, 1) + lambda, a22 = A(2, 2) + lambda;
  const double a10 = A(1, 0), a20 = A(2, 0), a21 = A(2, 1);
  // Pivots below this floor mean "no information in this direction": the matching component of
  // the solution is set to 0 (pseudo-inverse behaviour) rather than divided by ~0. Only reachable
  // with λ = 0 on a singular A.
  const double floor = 1e-13 * scale;
  const double d0 = a00;
  const bool p0 = d0 > floor;
  const double l10 = p0 ? a10 / d0 : 0.0;
  const double l20 = p0 ? a20 / d0 : 0.0;
  const double d1 = a11 - l10 * l10 * d0;
  const bool p1 = d1 > floor;
  const double l21 = p1 ? (a21 - l20 * l10 * d0) / d1 : 0.0;
  const double d2 = a22 - l20 * l20 * d0 - l21 * l21 * d1;
  const bool p2 = d2 > floor;
  // Forward (L y = b), diagonal, backward (Lᵀ x = z).
  const double y0 = b(0);
  const double y1 = b(1) - l10 * y0;
  const double y2 = b(2) - l20 * y0 - l21 * y1;
  const double z0 = p0 ? y0 / d0 : 0.0;
  const double z1 = p1 ? y1 / d1 : 0.0;
  const double z2 = p2 ? y2 / d2 : 0.0;
  const double x2 = z2;
  const double x1 = z1 - l21 * x2;
  const double x0 = z0 - l10 * x1 - l20 * x2;
  if (!std::isfinite(x0) || !std::isfinite(x1) || !std::isfinite(x2)) {
    r.rcond = 0.0;
    r.rank = 0;
    return r;
  }
  r.x = Eigen::Vector3d(x0, x1, x2);
  r.valid = r.rcond >= opt.rcond_min && p0 && p1 && p2;
  return r;
}

}  // namespace tacse3::dsp
