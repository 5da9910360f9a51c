// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: analytic grid vector fields, discrete operators and error metrics (mid stages).
#pragma once

#include <cstdint>
#include <functional>

#include "tacse3/dsp/types.hpp"
#include "tacse3/dsp_ref/smoothing_ref.hpp"

namespace tacse3::test::fields {

// A displacement field in working px as a function of the position in grid cells relative to
// the grid centre (19.5, 14.5): f(x, y, u, v).
using FieldFn = std::function<void(double x, double y, double& u, double& v)>;

dsp_ref::GridVectorD sample(const FieldFn& f);
dsp_ref::GridVectorD add(const dsp_ref::GridVectorD& a, const dsp_ref::GridVectorD& b);
dsp_ref::GridVectorD scale(const dsp_ref::GridVectorD& a, double s);

// Analytic fields (x, y, cx, cy in cells; displacements in px).
FieldFn uniform(double ux, double uy);
FieldFn rigid_rotation(double omega, double cx = 0.0, double cy = 0.0);  // omega (-y, x)
FieldFn rigid_expansion(double eps, double cx = 0.0, double cy = 0.0);   // eps (x, y)
FieldFn pure_shear(double a);                                            // a (x, -y)
// Free-space fields with Gaussian sources of width s cells (all sources inside the grid when the
// centre is > 4 s from the edges): curl w = 2 amp exp(-r^2 / 2 s^2) for the vortex, div w = the
// same for the source; w = amp s^2 (1 - exp(-r^2 / 2 s^2)) / r^2 * (-y, x) resp. (x, y).
FieldFn gaussian_vortex(double amp, double s, double cx = 0.0, double cy = 0.0);
FieldFn gaussian_source(double amp, double s, double cx = 0.0, double cy = 0.0);

// Deterministic pseudo-random numbers (xorshift64*), uniform in [-1, 1).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed * 2654435761ULL + 1) {}
  double uniform();

 private:
  std::uint64_t state_;
};

// A smooth random field: a few random Gaussian vortices/sources plus a uniform part, amplitude
// about `amp` px, plus optional white noise of RMS `noise` px.
dsp_ref::GridVectorD random_smooth(Rng& rng, double amp, double noise = 0.0);
dsp_ref::GridMaskD random_mask(Rng& rng, double invalid_fraction);

// Metrics over all points (or over points with mask != 0).
double rms(const dsp_ref::GridVectorD& a, const dsp_ref::GridMaskD* mask = nullptr);
double rms_diff(const dsp_ref::GridVectorD& a, const dsp_ref::GridVectorD& b,
                const dsp_ref::GridMaskD* mask = nullptr);
double rms(const dsp_ref::GridScalarD& a, const dsp_ref::GridMaskD* mask = nullptr);
double rms_diff(const dsp_ref::GridScalarD& a, const dsp_ref::GridScalarD& b,
                const dsp_ref::GridMaskD* mask = nullptr);
// SNR in dB of `test` against `ref`: 20 log10(rms(ref) / rms(test - ref)).
double snr_db(const dsp_ref::GridVectorD& ref, const dsp_ref::GridVectorD& test,
              const dsp_ref::GridMaskD* mask = nullptr);
double snr_db(const dsp_ref::GridScalarD& ref, const dsp_ref::GridScalarD& test,
              const dsp_ref::GridMaskD* mask = nullptr);
// Largest |test - ref| in Q16 LSB (ref in double px, test the Q16 field).
double max_lsb(const dsp_ref::GridVectorD& ref, const dsp::VectorField& test,
               const dsp_ref::GridMaskD* mask = nullptr);
double max_lsb(const dsp_ref::GridScalarD& ref, const dsp::ScalarField& test,
               const dsp_ref::GridMaskD* mask = nullptr);

// Exact integer central differences of a Q16 field at an interior point (1 <= gx <= 38,
// 1 <= gy <= 28), returned doubled (no division): 2 div = (vx[+1] - vx[-1]) + (vy[+W] - vy[-W]),
// 2 curl = (vy[+1] - vy[-1]) - (vx[+W] - vx[-W]).
std::int64_t twice_div(const dsp::VectorField& f, int gx, int gy);
std::int64_t twice_curl(const dsp::VectorField& f, int gx, int gy);
// The same in double on a double field.
double central_div(const dsp_ref::GridVectorD& f, int gx, int gy);
double central_curl(const dsp_ref::GridVectorD& f, int gx, int gy);

}  // namespace tacse3::test::fields
