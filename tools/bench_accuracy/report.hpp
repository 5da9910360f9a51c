// SPDX-License-Identifier: Apache-2.0
// tacse3-bench-accuracy: the tables of one profile, its goal values and the profile matrix.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "cases.hpp"

namespace tacse3::bench_accuracy {

// The goals (defaults, dual sensor; docs/accuracy.md). Each is a worst-row value to be at most
// `limit`; `stretch` is the tighter target (NaN: none). Checks are reported without a goal verdict
// across profiles where the profile is a stress profile.
struct Goal {
  const char* what;
  double limit;
  double stretch;
};
inline constexpr std::size_t kGoalCount = 10;
extern const std::array<Goal, kGoalCount> kGoals;

struct GoalValues {
  std::array<double, kGoalCount> v{};  // NaN where no row measured the goal
};
GoalValues measure_goals(const std::vector<Row>& rows);

// Markdown: Tables V-B, V-C, V-D, the stick table and the detector's agreement, for one profile.
std::string profile_tables(const std::vector<Row>& rows);

// One profile's outcome, for the matrix.
struct ProfileOutcome {
  std::string name;
  bool stress = false;  // the profile's shear cannot carry the speed: reported, no goal
  std::string error;    // calibration or evaluation failed (the reason); empty if evaluated
  std::size_t calibration_problems = 0;  // what the fit's self-check found (evaluated anyway)
  GoalValues goals;
};

// Markdown: one row per goal, one column per profile, and the worst over the profiles the goals
// apply to. `failed` lists each goal missed on a goal-bearing profile by more than
// `fail_factor` times its limit (fail_factor <= 0: none).
std::string goal_matrix(const std::vector<ProfileOutcome>& outcomes, double fail_factor,
                        std::vector<std::string>* failed);

// Markdown: tracking RMS (worst slide rotation) and stick error when calibrating on the row's
// profile and evaluating on the column's. cells[i][j]: calibrate on i, evaluate on j.
std::string cross_matrix(const std::vector<std::string>& names,
                         const std::vector<std::vector<GoalValues>>& cells);

std::string fmt(double v, int prec = 2);

}  // namespace tacse3::bench_accuracy
