// SPDX-License-Identifier: Apache-2.0
// tacse3-bench-accuracy: the calibration set and the test rows of one sensor profile.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "tacse3/tools/bench.hpp"

namespace tacse3::bench_accuracy {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A test row: a case, which tables it feeds and the paper's numbers for it.
struct Row {
  tools::SimCase c;
  bool vb = false, vc = false, vd = false, stick = false;
  double paper_vb = kNaN;  // Table V-B mean error (deg)
  double paper_vc_single_drift = kNaN, paper_vc_single_trans = kNaN;
  double paper_vc_dual_drift = kNaN, paper_vc_dual_trans = kNaN;
  std::string vd_object;  // Table V-D row name
  // The shear can show the motion at every instant (tools::shear_carries_speed); rows where it
  // cannot are reported without counting towards the rotation goals.
  bool carried = true;
  double paper_vd = kNaN;
  std::vector<tools::EvalConfig> configs;
  std::vector<tools::EvalResult> results;
  // Index into configs / results of each configuration the row runs (-1 = not run).
  struct {
    int dual_joint = -1, dual_paper = -1, single_joint = -1, single_paper = -1,
        dual_joint_disp = -1;
  } slot;
  const tools::EvalResult& res(int i) const { return results[static_cast<std::size_t>(i)]; }
  bool rotation() const { return c.motion[0] == 'r'; }
};

// The recordings calibrate fits on: sphere slides and stick motions with other seeds, sizes and
// indentations than the test rows.
std::vector<tools::SimCase> calibration_set(bool quick, const std::string& profile);

// Tables V-B, V-C, V-D and the stick rows, with the configurations each row runs. `reference`
// also runs the double reference in lock step on the default configuration.
std::vector<Row> test_rows(bool quick, const std::string& profile, bool reference);

// Only the rows a cross-calibration evaluates: the quick slides and stick motions.
std::vector<Row> cross_rows(const std::string& profile);

}  // namespace tacse3::bench_accuracy
