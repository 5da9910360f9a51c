// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: double-precision contact mask (filter, hysteresis, area) and 3D points.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "tacse3/dsp/calibration.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp_ref {

struct ContactSetRef {
  std::vector<std::uint8_t> mask;   // Ω
  std::vector<double> fz_filtered;  // filter(f^z)
  std::vector<Eigen::Vector3d> q;   // contact points (m), sensor frame; zero outside Ω
  int count = 0;
  int components = 0;
};

// Same rules as dsp::ContactDetector, in double, metres.
class ContactDetectorRef {
 public:
  explicit ContactDetectorRef(const dsp::Calibration& cal = {});
  void reset();
  // follow (may be null): Ω as the fixed-point path reported it (dsp::ContactSet::mask, after
  // hysteresis and the minimum area) instead of this stage's own thresholds, for the
  // "decision-locked" comparison only; the filter and the 3D points are still computed here.
  ContactSetRef detect(const std::vector<double>& fz, const dsp::VectorField& w,
                       const dsp::GridMask& valid, const dsp::GridMask* follow = nullptr);

 private:
  dsp::Calibration cal_;
  std::vector<std::uint8_t> prev_;
};

}  // namespace tacse3::dsp_ref
