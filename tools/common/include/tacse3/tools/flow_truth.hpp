// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the simulator's true displacement on the block-flow grid, and the RMS end-point
// error of any flow against it (tacse3_bench_vs_dis scores every flow with it).
#pragma once

#include <array>
#include <cstdint>

#include "tacse3/dsp/types.hpp"
#include "tacse3/sim/pad.hpp"

namespace tacse3::tools {

// One displacement per flow-grid point (dsp/geometry.hpp), in working px (160x120), as doubles
// so that every flow, fixed point or not, is scored the same way.
struct GridFlow {
  std::array<double, dsp::kGridCount> x{};
  std::array<double, dsp::kGridCount> y{};
};

// The block flow's output (Q16 working px).
GridFlow grid_flow(const dsp::VectorField& q16) noexcept;

// A dense flow of the working image, interleaved (x, y) floats per pixel in working px (the
// layout of OpenCV's CV_32FC2), sampled bilinearly at the grid points.
GridFlow grid_flow(const float* xy, int width, int height) noexcept;

// The true displacement of the gel material seen at each grid point of the reference frame, to
// where it is seen in the current frame (working px), and the contact region: the points whose
// material now lies on a contact cell of the simulator.
struct GridTruth {
  GridFlow flow;
  std::array<std::uint8_t, dsp::kGridCount> contact{};
  int contact_count() const noexcept;
};

// ref, cur: one pad's simulator fields at the reference (tare) frame and at the current frame.
// The fields are Eulerian (pad.hpp): the material seen at x came from x - U(x). A grid point's
// material m = p - U_ref(p) is now at x = m + U_cur(x), solved by fixed-point iteration with the
// renderer's bilinear interpolation of U between cell centres.
GridTruth grid_truth(const sim::PadFields& ref, const sim::PadFields& cur) noexcept;

// Accumulates squared end-point errors over the contact region of each frame added.
class FlowError {
 public:
  void add(const GridTruth& truth, const GridFlow& estimate) noexcept;
  void merge(const FlowError& other) noexcept;
  // sqrt(mean squared end-point error), working px; 0 with no points.
  double rms_px() const noexcept;
  std::int64_t points() const noexcept { return points_; }

 private:
  double sum_sq_ = 0.0;
  std::int64_t points_ = 0;
};

}  // namespace tacse3::tools
