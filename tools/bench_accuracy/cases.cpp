// SPDX-License-Identifier: Apache-2.0
// tacse3-bench-accuracy: the calibration set and the test rows (paper Tables V-B, V-C, V-D).
#include "cases.hpp"

namespace tacse3::bench_accuracy {
namespace {

using dsp::FusionMethod;
using tools::ProxyMode;
using tools::SensorChoice;
using tools::SimCase;

void add_configs(Row& r, bool reference) {
  auto add = [&](FusionMethod m, ProxyMode mode, SensorChoice s, bool ref) {
    r.configs.push_back({m, mode, s, ref});
    return static_cast<int>(r.configs.size()) - 1;
  };
  r.slot.dual_joint = add(FusionMethod::kJoint, ProxyMode::kAuto, SensorChoice::kBoth, reference);
  r.slot.dual_paper = add(FusionMethod::kPaper, ProxyMode::kAuto, SensorChoice::kBoth, false);
  if (r.vc) {  // single-sensor rows: the same recording with the left pad only
    r.slot.single_joint = add(FusionMethod::kJoint, ProxyMode::kAuto, SensorChoice::kLeft, false);
    r.slot.single_paper = add(FusionMethod::kPaper, ProxyMode::kAuto, SensorChoice::kLeft, false);
  }
  if (r.stick) {  // the stick-regime proxy on its own, for comparison with auto
    r.slot.dual_joint_disp =
        add(FusionMethod::kJoint, ProxyMode::kDisplacement, SensorChoice::kBoth, false);
  }
}

void add_rotation_rows(bool quick, std::vector<Row>* rows) {
  // Table V-B (paper: mean error, deg) and the rotation rows of Table V-C.
  const double vb[3][3] = {{3.0, 7.1, 11.9}, {3.2, 7.5, 12.2}, {2.9, 6.8, 11.7}};
  const double vc_rot[3][4] = {
      {7.90, 1.58, 2.90, 0.55}, {8.40, 1.67, 3.20, 0.57}, {4.90, 0.74, 3.50, 0.59}};
  const char* axes[3] = {"rx", "ry", "rz"};
  const double angles[3] = {30, 60, 90};
  for (int a = 0; a < 3; ++a) {
    for (int k = 0; k < (quick ? 1 : 3); ++k) {
      Row r;
      r.c = tools::make_sim_case("sphere", axes[a], angles[k]);
      r.vb = true;
      r.paper_vb = vb[a][k];
      if (k == 0) {
        r.vc = true;
        r.paper_vc_single_drift = vc_rot[a][0];
        r.paper_vc_single_trans = vc_rot[a][1];
        r.paper_vc_dual_drift = vc_rot[a][2];
        r.paper_vc_dual_trans = vc_rot[a][3];
      }
      rows->push_back(r);
    }
  }
}

void add_translation_rows(std::vector<Row>* rows) {
  // Table V-C translations.
  const double vc_tr[2][4] = {{9.80, 1.52, 1.10, 0.64}, {10.60, 1.72, 1.50, 0.68}};
  const char* taxes[2] = {"tx", "ty"};
  for (int a = 0; a < 2; ++a) {
    Row r;
    r.c = tools::make_sim_case("sphere", taxes[a], 10);
    r.vc = true;
    r.paper_vc_single_drift = vc_tr[a][0];
    r.paper_vc_single_trans = vc_tr[a][1];
    r.paper_vc_dual_drift = vc_tr[a][2];
    r.paper_vc_dual_trans = vc_tr[a][3];
    rows->push_back(r);
  }
}

void add_object_rows(bool quick, std::vector<Row>* rows) {
  // Table V-D: the paper's objects at 30 degrees (two-axis objects on both axes).
  struct Vd {
    const char* object;
    const char* motion;
    const char* name;
    double paper;
    bool quick;
  };
  const Vd vd[] = {{"large-sphere", "rz", "Large Sphere", 2.9, true},
                   {"ellipsoid", "rx", "Ellipsoidal Object", 3.6, true},
                   {"ellipsoid", "rz", "Ellipsoidal Object", 3.6, false},
                   {"irregular", "ry", "Irregular-Shaped Object", 4.0, false},
                   {"irregular", "rz", "Irregular-Shaped Object", 4.0, false},
                   {"cylinder", "ry", "Cylindrical Object (Two-Axis)", 2.8, false},
                   {"cylinder", "rz", "Cylindrical Object (Two-Axis)", 2.8, false},
                   {"plastic-cube", "rz", "Plastic Cube (Single-Axis)", 3.8, true},
                   {"wooden-cube", "rz", "Wooden Cube (Single-Axis)", 3.2, false},
                   {"textured-cube", "rz", "Textured Cube (Single-Axis)", 2.6, false},
                   {"screwdriver", "ry", "Screwdriver Handle (Two-Axis)", 3.5, true},
                   {"screwdriver", "rz", "Screwdriver Handle (Two-Axis)", 3.5, false}};
  for (const auto& v : vd) {
    if (quick && !v.quick) continue;
    Row r;
    r.c = tools::make_sim_case(v.object, v.motion, 30);
    r.vd = true;
    r.vd_object = v.name;
    r.paper_vd = v.paper;
    rows->push_back(r);
  }
}

void add_stick_rows(bool quick, std::vector<Row>* rows) {
  // Small motions on several objects: the contact sticks.
  struct St {
    const char* object;
    const char* motion;
    double magnitude;
    bool quick;
  };
  const St st[] = {{"sphere", "rx", 2, true},     {"sphere", "ry", 3, false},
                   {"sphere", "rz", 4, true},     {"sphere", "tx", 0.4, true},
                   {"sphere", "ty", 0.6, false},  {"cube", "rz", 2, true},
                   {"cube", "tx", 0.3, false},    {"cylinder", "ry", 2, false},
                   {"ellipsoid", "rz", 3, false}, {"screwdriver", "rz", 1, false}};
  for (const auto& s : st) {
    if (quick && !s.quick) continue;
    Row r;
    r.c = tools::make_sim_case(s.object, s.motion, s.magnitude);
    r.stick = true;
    rows->push_back(r);
  }
}

void finish_rows(const std::string& profile, bool reference, std::vector<Row>* rows) {
  for (auto& r : *rows) {
    r.c.profile = profile;
    add_configs(r, reference);
  }
}

}  // namespace

std::vector<SimCase> calibration_set(bool quick, const std::string& profile) {
  // Different seeds, radii and indentations from the test rows.
  std::vector<SimCase> c = {tools::make_sim_case("sphere", "rx", 30, 7, 18, 0.8),
                            tools::make_sim_case("sphere", "rz", 30, 7, 18, 0.8),
                            tools::make_sim_case("sphere", "tx", 10, 7, 18, 0.8),
                            tools::make_sim_case("sphere", "rz", 3, 7, 18, 0.8),
                            tools::make_sim_case("sphere", "ry", 2, 7, 18, 0.8),
                            tools::make_sim_case("sphere", "tx", 0.3, 7, 18, 0.8),
                            tools::make_sim_case("sphere", "ty", 10, 7, 18, 0.8)};
  if (!quick) {
    for (const auto& x : {tools::make_sim_case("sphere", "ry", 30, 8, 22, 1.2),
                          tools::make_sim_case("sphere", "rz", 60, 8, 22, 1.2),
                          tools::make_sim_case("sphere", "ty", 10, 8, 22, 1.2),
                          tools::make_sim_case("sphere", "rx", 3, 8, 22, 1.2),
                          tools::make_sim_case("sphere", "rx", 30, 8, 22, 1.2),
                          tools::make_sim_case("sphere", "tx", 10, 8, 22, 1.2),
                          tools::make_sim_case("sphere", "ry", 30, 7, 18, 0.8),
                          tools::make_sim_case("sphere", "rx", 3, 7, 18, 0.8),
                          tools::make_sim_case("sphere", "ty", 0.5, 7, 18, 0.8),
                          tools::make_sim_case("sphere", "ry", 2, 8, 22, 1.2),
                          tools::make_sim_case("sphere", "tx", 0.3, 8, 22, 1.2),
                          tools::make_sim_case("sphere", "ty", 0.5, 8, 22, 1.2),
                          tools::make_sim_case("ellipsoid", "rz", 30, 9),
                          tools::make_sim_case("cube", "rz", 2, 9)}) {
      c.push_back(x);
    }
  }
  for (auto& x : c) x.profile = profile;
  return c;
}

std::vector<Row> test_rows(bool quick, const std::string& profile, bool reference) {
  std::vector<Row> rows;
  add_rotation_rows(quick, &rows);
  add_translation_rows(&rows);
  add_object_rows(quick, &rows);
  add_stick_rows(quick, &rows);
  finish_rows(profile, reference, &rows);
  return rows;
}

std::vector<Row> cross_rows(const std::string& profile) {
  std::vector<Row> rows;
  add_rotation_rows(true, &rows);
  add_stick_rows(true, &rows);
  for (auto& r : rows) r.vc = false;  // no single-sensor configurations
  finish_rows(profile, false, &rows);
  return rows;
}

}  // namespace tacse3::bench_accuracy
