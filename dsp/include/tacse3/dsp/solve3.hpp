// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: fixed 3x3 regularised symmetric solve with validity and confidence (double).
#pragma once

#include <Eigen/Core>

namespace tacse3::dsp {

// Regularisation of solve3(): the system solved is (A + λ I) x = b with
//   λ = lambda_rel · tr(A)/3 + lambda_abs,
// and the result is valid when the reciprocal condition number of A (λ_min/λ_max of its
// eigenvalues, unregularised) is at least rcond_min and A is not (numerically) zero.
struct Solve3Options {
  double lambda_rel = 1e-6;
  double lambda_abs = 0.0;  // in the units of A (the motion stage uses N · lever_floor²)
  double rcond_min = 1e-4;
};

struct Solve3Result {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();  // always finite
  bool valid = false;                           // well-conditioned, finite inputs, non-empty system
  double rcond = 0.0;  // λ_min/λ_max of the symmetrised A, in [0, 1]; 0 for empty/non-finite
  int rank = 0;  // eigenvalues ≥ rcond_min · λ_max (0..3): how many directions are observed
  double lambda = 0.0;  // the Tikhonov λ actually used
};

// Solves the symmetric positive semi-definite 3x3 system A x = b (normal equations AᵀA ω = Aᵀb,
// Eq. twist_ls restricted to ω). Fixed work: symmetrise, closed-form eigenvalues for the
// confidence, LDLᵀ of A + λI with explicit 3x3 formulas and a pivot floor, finite check.
// Rank-deficient directions (tiny/empty contact, collinear points, z ≈ 0) are pulled to 0 by λ
// instead of blowing up. Non-finite inputs, an all-zero A or a non-finite result give x = 0,
// valid = false. Never returns NaN. No heap.
Solve3Result solve3(const Eigen::Matrix3d& A, const Eigen::Vector3d& b,
                    const Solve3Options& opt = {}) noexcept;

}  // namespace tacse3::dsp
