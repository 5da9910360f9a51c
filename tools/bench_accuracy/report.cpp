// SPDX-License-Identifier: Apache-2.0
// tacse3-bench-accuracy: the tables of one profile, its goal values and the profile matrix.
#include "report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "text.hpp"

namespace tacse3::bench_accuracy {

const std::array<Goal, kGoalCount> kGoals = {{
    {"tracking RMS over slide rotations (deg)", 1.5, 1.0},
    {"final rotation error at 30 deg (deg)", 1.5, 1.0},
    {"final rotation error at 60 deg (deg)", 3.5, 2.0},
    {"final rotation error at 90 deg (deg)", 6.0, 4.0},
    {"rotation drift under 10 mm translation (deg)", 1.0, 0.5},
    {"translation error, 10 mm translations (mm)", 0.3, kNaN},
    {"objects at 30 deg: mean error (deg)", 3.0, kNaN},
    {"objects at 30 deg: worst error (deg)", 6.0, kNaN},
    {"stick motions: rotation error (deg)", 0.3, kNaN},
    {"fixed point vs double reference, same decisions (deg)", 0.2, kNaN},
}};

std::string fmt(double v, int prec) {
  if (std::isnan(v)) return "–";
  char b[32];
  std::snprintf(b, sizeof(b), "%.*f", prec, v);
  return b;
}

namespace {

// Worst (largest) value; NaN stays NaN until a value arrives.
void worst(double* w, double v) {
  if (std::isnan(v)) return;
  *w = std::isnan(*w) ? v : std::max(*w, v);
}

std::string ref_cell(const tools::EvalResult& e) {
  if (!e.fixed_vs_reference_deg) return "–";
  char b[80];
  if (e.fixed_vs_locked_reference_deg) {
    std::snprintf(b, sizeof(b), "%.3f / %.3f locked (ref err %.2f)", *e.fixed_vs_reference_deg,
                  *e.fixed_vs_locked_reference_deg, *e.reference_error_deg);
  } else {
    std::snprintf(b, sizeof(b), "%.3f (ref err %.2f)", *e.fixed_vs_reference_deg,
                  *e.reference_error_deg);
  }
  return b;
}

std::string tracking_cell(const tools::TrackingError& t) {
  if (!t.valid) return "–";
  char b[64];
  std::snprintf(b, sizeof(b), "%.2f / %.2f (%.0f ms)", t.rotation_rms_deg, t.rotation_max_deg,
                t.rotation_lag_s * 1e3);
  return b;
}

std::string magnitude_text(const Row& r) {
  return fmt(r.c.magnitude, r.c.magnitude < 1 ? 1 : 0) + (r.rotation() ? " deg" : " mm");
}

void table_vb(const std::vector<Row>& rows, std::string* o) {
  *o += "#### Table V-B: grasped sphere, angular error (deg)\n\n";
  *o +=
      "| axis | angle | paper | ours joint | ours paper | tracking RMS / max (lag) | "
      "fixed−ref (deg) |\n|---|---|---|---|---|---|---|\n";
  char line[512];
  for (const auto& r : rows) {
    if (!r.vb) continue;
    const auto& j = r.res(r.slot.dual_joint);
    std::snprintf(line, sizeof(line), "| %s | %g%s | %s | %s | %s | %s | %s |\n",
                  r.c.motion.c_str(), r.c.magnitude, r.carried ? "" : " (capped)",
                  fmt(r.paper_vb, 1).c_str(), fmt(j.errors.final_rotation_error_deg).c_str(),
                  fmt(r.res(r.slot.dual_paper).errors.final_rotation_error_deg).c_str(),
                  tracking_cell(j.tracking).c_str(), ref_cell(j).c_str());
    *o += line;
  }
}

void table_vc(const std::vector<Row>& rows, std::string* o) {
  *o += "\n#### Table V-C: single vs dual sensor (rotation drift deg / translation error mm)\n\n";
  *o +=
      "| motion | configuration | paper drift | paper trans | ours joint drift | ours joint "
      "trans | ours paper drift | ours paper trans |\n|---|---|---|---|---|---|---|---|\n";
  char line[512];
  for (const char* mo : {"tx", "ty", "rx", "ry", "rz"}) {
    for (const auto& r : rows) {
      if (!r.vc || r.c.motion != mo) continue;
      for (int dual = 0; dual < 2; ++dual) {
        const auto& j = r.res(dual ? r.slot.dual_joint : r.slot.single_joint).errors;
        const auto& p = r.res(dual ? r.slot.dual_paper : r.slot.single_paper).errors;
        std::string name = std::string(1, static_cast<char>(std::toupper(mo[0]))) + mo[1];
        std::snprintf(
            line, sizeof(line), "| %s %s | %s | %s | %s | %s | %s | %s | %s |\n", name.c_str(),
            magnitude_text(r).c_str(), dual ? "Dual" : "Single (left)",
            fmt(dual ? r.paper_vc_dual_drift : r.paper_vc_single_drift).c_str(),
            fmt(dual ? r.paper_vc_dual_trans : r.paper_vc_single_trans).c_str(),
            fmt(j.final_rotation_error_deg).c_str(), fmt(j.final_translation_error_mm).c_str(),
            fmt(p.final_rotation_error_deg).c_str(), fmt(p.final_translation_error_mm).c_str());
        *o += line;
      }
    }
  }
}

void table_vd(const std::vector<Row>& rows, std::string* o) {
  *o += "\n#### Table V-D: objects at 30 deg, angular error (deg)\n\n";
  *o +=
      "| object (paper) | sim object, axis | paper | ours joint | ours paper | tracking RMS / "
      "max (lag) |\n|---|---|---|---|---|---|\n";
  char line[512];
  for (const auto& r : rows) {
    if (!r.vd) continue;
    const auto& j = r.res(r.slot.dual_joint);
    std::snprintf(line, sizeof(line), "| %s | %s %s%s | %s | %s | %s | %s |\n", r.vd_object.c_str(),
                  r.c.object.c_str(), r.c.motion.c_str(), r.carried ? "" : " (capped)",
                  fmt(r.paper_vd, 1).c_str(), fmt(j.errors.final_rotation_error_deg).c_str(),
                  fmt(r.res(r.slot.dual_paper).errors.final_rotation_error_deg).c_str(),
                  tracking_cell(j.tracking).c_str());
    *o += line;
  }
}

void table_stick(const std::vector<Row>& rows, std::string* o) {
  *o += "\n#### Stick motions: rotation error (deg) / translation error (mm)\n\n";
  *o +=
      "| motion | ours joint (auto) | ours paper (auto) | ours joint (--mode displacement) "
      "|\n|---|---|---|---|\n";
  char line[512];
  for (const auto& r : rows) {
    if (!r.stick) continue;
    const auto& j = r.res(r.slot.dual_joint).errors;
    const auto& p = r.res(r.slot.dual_paper).errors;
    const auto& d = r.res(r.slot.dual_joint_disp).errors;
    std::snprintf(
        line, sizeof(line), "| %s %s %s | %s / %s | %s / %s | %s / %s |\n", r.c.object.c_str(),
        r.c.motion.c_str(), magnitude_text(r).c_str(), fmt(j.final_rotation_error_deg).c_str(),
        fmt(j.final_translation_error_mm).c_str(), fmt(p.final_rotation_error_deg).c_str(),
        fmt(p.final_translation_error_mm).c_str(), fmt(d.final_rotation_error_deg).c_str(),
        fmt(d.final_translation_error_mm).c_str());
    *o += line;
  }
}

std::string slip_cells(const tools::SlipScore& s) {
  char b[160];
  std::snprintf(
      b, sizeof(b), "%lld | %.1f %% | %lld/%lld | %lld/%lld", static_cast<long long>(s.scored()),
      100.0 * s.accuracy(), static_cast<long long>(s.true_slip),
      static_cast<long long>(s.true_slip + s.false_stick), static_cast<long long>(s.true_stick),
      static_cast<long long>(s.true_stick + s.false_slip));
  return b;
}

void table_detector(const std::vector<Row>& rows, std::string* o) {
  *o += "\n#### Stick/slip detector: per-frame agreement with the simulator's label\n\n";
  *o += "| recordings | frames | accuracy | slip found | stick found |\n|---|---|---|---|---|\n";
  tools::SlipScore stick_all, slide_all;
  for (const auto& r : rows) {
    const tools::EvalResult& e = r.res(r.slot.dual_joint);
    if (!e.slip_scored) continue;
    const bool slide = e.slip.true_slip + e.slip.false_stick > 0;
    (slide ? slide_all : stick_all).merge(e.slip);
  }
  append(o, {"| slide | ", slip_cells(slide_all), " |\n"});
  append(o, {"| stick | ", slip_cells(stick_all), " |\n"});
}

}  // namespace

GoalValues measure_goals(const std::vector<Row>& rows) {
  GoalValues g;
  g.v.fill(kNaN);
  double vd_sum = 0.0;
  int vd_n = 0;
  for (const auto& r : rows) {
    const tools::EvalResult& e = r.res(r.slot.dual_joint);
    const double rot = e.errors.final_rotation_error_deg;
    if (r.vb && r.carried && e.tracking.valid) worst(&g.v[0], e.tracking.rotation_rms_deg);
    if (r.vb && r.carried)
      worst(&g.v[r.c.magnitude <= 30 ? 1 : (r.c.magnitude <= 60 ? 2 : 3)], rot);
    if (r.vc && !r.rotation()) {
      worst(&g.v[4], rot);
      worst(&g.v[5], e.errors.final_translation_error_mm);
    }
    if (r.vd && r.carried) {
      vd_sum += rot;
      ++vd_n;
      worst(&g.v[7], rot);
    }
    if (r.stick) worst(&g.v[8], rot);
    for (const auto& x : r.results) {
      if (x.fixed_vs_locked_reference_deg) worst(&g.v[9], *x.fixed_vs_locked_reference_deg);
    }
  }
  if (vd_n > 0) g.v[6] = vd_sum / vd_n;
  return g;
}

std::string profile_tables(const std::vector<Row>& rows) {
  std::string o;
  table_vb(rows, &o);
  table_vc(rows, &o);
  table_vd(rows, &o);
  table_stick(rows, &o);
  table_detector(rows, &o);
  return o;
}

std::string goal_matrix(const std::vector<ProfileOutcome>& outcomes, double fail_factor,
                        std::vector<std::string>* failed) {
  std::string o = "| goal | limit (stretch) |";
  std::string rule = "|---|---|";
  for (const auto& p : outcomes) {
    append(&o, {" ", p.name, p.stress ? " (stress)" : "", " |"});
    rule += "---|";
  }
  append(&o, {" worst | met |\n", rule, "---|---|\n"});
  for (const auto& p : outcomes) {
    if (!p.error.empty()) failed->push_back(cat({p.name, ": ", p.error}));
  }
  for (std::size_t k = 0; k < kGoalCount; ++k) {
    const Goal& goal = kGoals[k];
    append(&o, {"| ", goal.what, " | ≤ ", fmt(goal.limit, 1),
                std::isnan(goal.stretch) ? std::string() : cat({" (", fmt(goal.stretch, 1), ")"}),
                " |"});
    double w = kNaN;
    for (const auto& p : outcomes) {
      const double v = p.error.empty() ? p.goals.v[k] : kNaN;
      append(&o, {" ", p.error.empty() ? fmt(v) : std::string("failed"), " |"});
      if (p.stress) continue;
      worst(&w, v);
      if (fail_factor > 0.0 && !std::isnan(v) && v > fail_factor * goal.limit) {
        failed->push_back(cat({p.name, ": ", goal.what, " ", fmt(v), " > ", fmt(fail_factor, 1),
                               " × ", fmt(goal.limit, 1)}));
      }
    }
    const char* met = std::isnan(w) ? "–" : (w <= goal.limit ? "yes" : "**no**");
    append(&o, {" ", fmt(w), " | ", met, " |\n"});
  }
  o += "| problems the calibration self-check reports | 0 |";
  for (const auto& p : outcomes) append(&o, {" ", std::to_string(p.calibration_problems), " |"});
  o += " | |\n";
  return o;
}

std::string cross_matrix(const std::vector<std::string>& names,
                         const std::vector<std::vector<GoalValues>>& cells) {
  std::string o = "| calibrated on ↓ / evaluated on → |";
  std::string rule = "|---|";
  for (const auto& n : names) {
    append(&o, {" ", n, " |"});
    rule += "---|";
  }
  append(&o, {"\n", rule, "\n"});
  for (std::size_t i = 0; i < names.size(); ++i) {
    append(&o, {"| ", names[i], " |"});
    for (std::size_t j = 0; j < names.size(); ++j) {
      const GoalValues& g = cells[i][j];
      append(&o, {" ", fmt(g.v[0]), " / ", fmt(g.v[8]), i == j ? " (own)" : "", " |"});
    }
    o += "\n";
  }
  return o;
}

}  // namespace tacse3::bench_accuracy
