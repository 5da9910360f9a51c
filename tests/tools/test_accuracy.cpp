// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: reduced accuracy regression: calibrate on short simulated grasps, evaluate others.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "tacse3/config/calibration_file.hpp"
#include "tacse3/dsp/block_flow.hpp"
#include "tacse3/dsp/luma.hpp"
#include "tacse3/tools/bench.hpp"
#include "tacse3/tools/metrics.hpp"
#include "tacse3/tools/replay.hpp"
#include "tacse3/tools/sim_source.hpp"

namespace {

namespace tt = tacse3::tools;

// The simulator calibration committed beside tacse3-replay (what a user replays with).
tacse3::config::CalibrationSet committed_calibration() {
  tacse3::config::CalibrationSet cal;
  const tacse3::config::Status st = tacse3::config::load_calibration(TACSE3_SIM_CALIBRATION, &cal);
  EXPECT_TRUE(st.ok()) << st.message();
  return cal;
}

// Changes the case's simulator configuration before rendering (settings tacse3-sim has and
// SimCase does not carry, such as the motion's duration).
using SimAlteration = std::function<void(tacse3::sim::SimConfig&)>;

// The case rendered in memory, frame by frame (grey, like the benchmark); nullptr and *err set
// on a bad case.
std::unique_ptr<tt::SimSource> open_sim(const tt::SimCase& c, std::string* err,
                                        const SimAlteration& alter = {}) {
  tacse3::sim::SimConfig sc;
  *err = tt::make_sim_config(c, &sc);
  if (!err->empty()) return nullptr;
  if (alter) alter(sc);
  return tt::SimSource::create(sc, c.label(), 1, err);
}

// The same with a shorter timeline, for the calibrate-and-evaluate regression.
tt::SimCase short_case(const char* object, const char* motion, double magnitude, std::uint64_t seed,
                       double radius) {
  tt::SimCase c = tt::make_sim_case(object, motion, magnitude, seed, radius);
  c.approach_s = 0.05;
  c.grasp_s = 0.25;
  c.settle_s = 0.05;
  c.hold_s = 0.2;
  return c;
}

// The case replayed with the defaults (joint, both pads) and `mode` (auto by default): the
// final-pose errors.
tt::PoseErrors replay_errors(const tt::SimCase& c, const tacse3::config::CalibrationSet& cal,
                             tt::ProxyMode mode = tt::ProxyMode::kAuto,
                             const SimAlteration& alter = {}) {
  std::string err;
  const auto src = open_sim(c, &err, alter);
  EXPECT_TRUE(src) << err;
  if (!src) return {};
  const tt::SourceInfo& info = src->info();
  tt::ReplayOptions o;
  o.calibration = cal;
  o.mode = mode;
  tt::Replayer replayer;
  EXPECT_EQ(replayer.init(info, o), "");
  std::vector<tacse3::dsp::Pose> poses;
  tt::FrameResult row;
  for (std::size_t i = 0; i < info.frame_count(); ++i) {
    std::array<const tacse3::dsp::FrameView*, 2> views{};
    EXPECT_EQ(src->read(i, &views), "");
    EXPECT_EQ(replayer.step_views(views, info.t_ns[i], i, &row), "");
    poses.push_back(row.pose);
  }
  return tt::pose_errors(poses, info.truth, info.t_ns);
}

// Replays a case twice in lock step with the defaults: as rendered, and altered frame by frame
// by `alter` (which may withhold a pad's view or move the frame's time; it returns whether it
// changed frame i). Final-pose errors of both, how far apart they end, and how many altered
// frames were fused from a single pad.
struct WholeAndAltered {
  tt::PoseErrors whole, altered;
  double apart_deg = 0.0;
  int single_altered = 0;
};
using Alteration =
    std::function<bool(std::size_t, std::array<const tacse3::dsp::FrameView*, 2>&, std::int64_t&)>;
WholeAndAltered replay_whole_and_altered(const tt::SimCase& c,
                                         const tacse3::config::CalibrationSet& cal,
                                         const Alteration& alter) {
  WholeAndAltered r;
  std::string err;
  const auto src = open_sim(c, &err);
  EXPECT_TRUE(src) << err;
  if (!src) return r;
  const tt::SourceInfo& info = src->info();
  tt::ReplayOptions o;
  o.calibration = cal;
  tt::Replayer whole, altered;
  const std::string init_whole = whole.init(info, o), init_altered = altered.init(info, o);
  EXPECT_EQ(init_whole, "");
  EXPECT_EQ(init_altered, "");
  EXPECT_GT(info.frame_count(), 0u);
  if (!init_whole.empty() || !init_altered.empty() || info.frame_count() == 0) return r;
  std::vector<tacse3::dsp::Pose> poses[2];
  tt::FrameResult row;
  for (std::size_t i = 0; i < info.frame_count(); ++i) {
    std::array<const tacse3::dsp::FrameView*, 2> views{};
    const std::string read = src->read(i, &views);
    EXPECT_EQ(read, "") << "frame " << i;
    if (!read.empty()) return r;
    EXPECT_EQ(whole.step_views(views, info.t_ns[i], i, &row), "");
    poses[0].push_back(row.pose);
    std::int64_t t_ns = info.t_ns[i];
    const bool changed = alter(i, views, t_ns);
    EXPECT_EQ(altered.step_views(views, t_ns, i, &row), "");
    poses[1].push_back(row.pose);
    r.single_altered += changed && row.single_sensor ? 1 : 0;
  }
  // Against the truth at the rendered times: the poses are those of the same frames.
  r.whole = tt::pose_errors(poses[0], info.truth, info.t_ns);
  r.altered = tt::pose_errors(poses[1], info.truth, info.t_ns);
  r.apart_deg = tt::rotation_error_deg(poses[0].back().q, poses[1].back().q);
  return r;
}

// Loose bounds: they catch a broken stage, a sign or frame error, a calibration that stops
// fitting, not a few tenths of a degree (docs/accuracy.md has the real numbers). Measured values
// are printed so a failing run shows how far off it is.
TEST(Accuracy, CalibratedPipelineTracksShortSimulatedGrasps) {
  const std::vector<tt::SimCase> cal = {short_case("sphere", "rx", 30, 7, 18),
                                        short_case("sphere", "rz", 30, 7, 18),
                                        short_case("sphere", "rz", 3, 7, 18)};
  tt::CalibrateOptions co;
  co.jobs = 2;
  tt::CalibrateReport rep;
  const std::string e = tt::calibrate_cases(cal, co, &rep);
  ASSERT_TRUE(e.empty()) << e;
  std::printf("%s", tt::format_report(rep).c_str());
  // The two regimes are told apart without labels.
  ASSERT_EQ(rep.recordings.size(), 3u);
  EXPECT_EQ(rep.recordings[0].explained_by, tt::ProxyMode::kVelocity);
  EXPECT_EQ(rep.recordings[1].explained_by, tt::ProxyMode::kVelocity);
  EXPECT_EQ(rep.recordings[2].explained_by, tt::ProxyMode::kDisplacement);
  EXPECT_GT(rep.calibration.sensor[0].contact_tau_on, 0.0);

  struct Check {
    tt::SimCase c;
    tt::ProxyMode mode;
    double max_rotation_error_deg;
    double max_translation_error_mm;
  };
  const std::vector<Check> checks = {
      {short_case("sphere", "rx", 30, 1, 20), tt::ProxyMode::kVelocity, 10.0, 3.0},
      {short_case("sphere", "rz", 30, 1, 20), tt::ProxyMode::kVelocity, 12.0, 3.0},
      {short_case("sphere", "rz", 3, 1, 20), tt::ProxyMode::kDisplacement, 2.0, 1.0},
  };
  for (const auto& ch : checks) {
    std::vector<tt::EvalResult> res;
    // The proxy the fit attributes to the recording, and the default: the per-frame stick/slip
    // detector (--mode auto), which must do as well without being told the regime.
    const std::vector<tt::EvalConfig> cfg = {
        {tacse3::dsp::FusionMethod::kJoint, ch.mode, tt::SensorChoice::kBoth, false},
        {tacse3::dsp::FusionMethod::kJoint, tt::ProxyMode::kAuto, tt::SensorChoice::kBoth, true}};
    const std::string err = tt::evaluate_case(ch.c, rep.calibration, cfg, &res);
    ASSERT_TRUE(err.empty()) << err;
    const auto& er = res[0].errors;
    std::printf(
        "%-16s %-12s rotation error %.2f deg (estimated %.2f of %.2f), translation error "
        "%.2f mm\n",
        ch.c.label().c_str(), tt::to_string(ch.mode), er.final_rotation_error_deg,
        er.estimated_rotation_deg, er.true_rotation_deg, er.final_translation_error_mm);
    EXPECT_LT(er.final_rotation_error_deg, ch.max_rotation_error_deg) << ch.c.label();
    EXPECT_LT(er.final_translation_error_mm, ch.max_translation_error_mm) << ch.c.label();
    const auto& ea = res[1].errors;
    const tt::SlipScore& sl = res[1].slip;
    std::printf(
        "%-16s auto         rotation error %.2f deg, translation error %.2f mm; detector: "
        "%lld/%lld slipping frames found, %lld/%lld sticking frames found\n",
        ch.c.label().c_str(), ea.final_rotation_error_deg, ea.final_translation_error_mm,
        static_cast<long long>(sl.true_slip), static_cast<long long>(sl.true_slip + sl.false_stick),
        static_cast<long long>(sl.true_stick),
        static_cast<long long>(sl.true_stick + sl.false_slip));
    EXPECT_LT(ea.final_rotation_error_deg, ch.max_rotation_error_deg) << ch.c.label() << " auto";
    EXPECT_LT(ea.final_translation_error_mm, ch.max_translation_error_mm)
        << ch.c.label() << " auto";
    ASSERT_TRUE(res[1].slip_scored) << ch.c.label();
    // The fixed-point arithmetic against the double reference taking the same discrete
    // decisions: a 0.2 deg bound. The free-running figure is printed, not bounded: a threshold
    // crossing on one side only (a point tracked, a slip onset) can part the two by degrees
    // (docs/dsp/reference.md).
    ASSERT_TRUE(res[1].fixed_vs_locked_reference_deg && res[1].fixed_vs_reference_deg);
    std::printf("%-16s auto         fixed-ref %.3f deg free-running, %.3f deg same decisions\n",
                ch.c.label().c_str(), *res[1].fixed_vs_reference_deg,
                *res[1].fixed_vs_locked_reference_deg);
    EXPECT_LT(*res[1].fixed_vs_locked_reference_deg, 0.2) << ch.c.label();
    if (ch.mode == tt::ProxyMode::kDisplacement) {
      // A sticking grasp is never called slipping (a false slip would repay the velocity
      // proxy's deficit of a held shear: tens of degrees).
      EXPECT_EQ(sl.false_slip, 0) << ch.c.label();
    } else {
      // The slide is recognised (from its deceleration or the gel relaxing after it; the
      // simulator labels the relaxation phase as sticking, so count every slipping decision).
      EXPECT_GT(sl.true_slip + sl.false_slip, 0) << ch.c.label();
    }
  }
}

// A pad that disappears for a few frames of a dual grasp (a camera hiccup; on a small object its
// contact mask can also flicker out at the rim) leaves the fused estimate to the other pad. The
// joint fusion then reads only the rotation about that pad's normal (docs/dsp/solve-fusion-se3.md):
// the in-plane components would rest on the indentation's sub-millimetre heights alone, where
// the shear noise of a pad at rest would become rad/s and turn the object by degrees per dropout.
TEST(Accuracy, APadMissingForFramesOfTheHoldDoesNotTurnTheObject) {
  const tacse3::config::CalibrationSet cal = committed_calibration();
  ASSERT_FALSE(::testing::Test::HasFailure());
  // A stick torsion of a small sphere (small contacts, short levers). The hold starts 1.17 s in
  // (frame 140 of 188): the right pad misses 140-149 and 165-174.
  const WholeAndAltered r = replay_whole_and_altered(
      tt::make_sim_case("sphere", "rz", 4.0, 1, 15.0), cal,
      [](std::size_t i, std::array<const tacse3::dsp::FrameView*, 2>& views, std::int64_t&) {
        if ((i >= 140 && i < 150) || (i >= 165 && i < 175)) {
          views[1] = nullptr;
          return true;
        }
        return false;
      });
  std::printf(
      "sphere rz 4, radius 15 mm: error %.2f deg with both pads, %.2f deg with the right pad "
      "missing "
      "for 20 frames of the hold (%d of them single-pad); the two end %.3f deg apart\n",
      r.whole.final_rotation_error_deg, r.altered.final_rotation_error_deg, r.single_altered,
      r.apart_deg);
  EXPECT_EQ(r.single_altered, 20);
  EXPECT_LT(r.whole.final_rotation_error_deg, 1.0);  // its right mask also flickers out by itself
  EXPECT_LT(r.altered.final_rotation_error_deg, 1.0);
  EXPECT_LT(r.apart_deg, 0.3);
}

// Stick grasps on objects where a false slip is easy to call: a small sphere, a sphere pressed
// 1.5 mm deep, the fluted screwdriver handle. There Ω's rim flickers (or collapses for a few
// frames of the grasp), and the rigid content of the shear over Ω drops with no slide; a false
// slip would pay back the velocity proxy's reading of the held shear, many times the motion.
// With the committed calibration and the default --mode auto, as a user would replay them.
TEST(Accuracy, SticksOnSmallOrDeeplyPressedObjectsAreNotCalledSlips) {
  const tacse3::config::CalibrationSet cal = committed_calibration();
  ASSERT_FALSE(::testing::Test::HasFailure());
  const std::vector<tt::SimCase> cases = {tt::make_sim_case("sphere", "rz", 3, 3, 15),
                                          tt::make_sim_case("sphere", "ry", 2, 3, 12),
                                          tt::make_sim_case("sphere", "rz", 3, 4, 0, 1.5),
                                          tt::make_sim_case("screwdriver", "rx", 2, 2, 0)};
  const std::vector<tt::EvalConfig> cfg = {
      {tacse3::dsp::FusionMethod::kJoint, tt::ProxyMode::kAuto, tt::SensorChoice::kBoth, false}};
  for (const tt::SimCase& c : cases) {
    std::vector<tt::EvalResult> res;
    const std::string err = tt::evaluate_case(c, cal, cfg, &res);
    ASSERT_TRUE(err.empty()) << err;
    const auto& e = res[0].errors;
    const tt::SlipScore& sl = res[0].slip;
    std::printf(
        "%-40s rotation error %.2f deg (estimated %.2f), %lld sensor-frames called "
        "slipping\n",
        c.sim_arguments().c_str(), e.final_rotation_error_deg, e.estimated_rotation_deg,
        static_cast<long long>(sl.false_slip + sl.true_slip));
    ASSERT_TRUE(res[0].slip_scored);
    // A false onset keeps the contact "slipping" for the rest of the run (hundreds of
    // sensor-frames); a few frames would be a near miss of the thresholds, not that failure.
    EXPECT_LE(sl.false_slip + sl.true_slip, 6) << c.sim_arguments();
    EXPECT_LT(e.final_rotation_error_deg, 1.0) << c.sim_arguments();
  }
}

// A translation starts off the pad's centre (tacse3-sim places the object at −magnitude/2), so
// the grasp forms there. While the mask grows, its weighted centroid moves with nothing moving.
// Two rules keep that out of the estimate:
//  - the area-ratio bound (max_mask_area_ratio, 1.5): the frames where the mask grows by more
//    than half read the material points, so the velocity reading hardly moves in the grasp;
//  - the unloaded-stick rule: `auto` reads the grasp from the material points, and would pay
//    the velocity reading back from the contact's first frame at the slide's onset if no stick
//    were confirmed before the slide (stick_confirm_s is 1 s, the grasp and settle 0.5 s). An
//    unloaded contact at rest is confirmed stuck after slip_on_frames frames, which drops that
//    reading. With the area bound switched off the velocity reading drifts in the grasp, and
//    this rule alone must keep `auto` clear of it. (The bound's own effect on `auto` is
//    AFlatFaceFirstSeenAtACornerIsNotReadAsATranslation's.)
TEST(Accuracy, TheGraspOfAnOffCentreContactIsNotPaidBackAsASlide) {
  const tacse3::config::CalibrationSet committed = committed_calibration();
  ASSERT_FALSE(::testing::Test::HasFailure());
  for (const bool area_bound : {true, false}) {
    tacse3::config::CalibrationSet cal = committed;
    if (!area_bound) {
      for (auto& s : cal.sensor) s.max_mask_area_ratio = 1e4;
    }
    for (const char* axis : {"tx", "ty"}) {
      const tt::SimCase c = tt::make_sim_case("sphere", axis, 10.0, 3, 0.0);
      std::string err;
      const auto src = open_sim(c, &err);
      ASSERT_TRUE(src) << err;
      const tt::SourceInfo& info = src->info();
      tt::ReplayOptions o;
      o.calibration = cal;
      tt::Replayer automatic, velocity;
      ASSERT_EQ(automatic.init(info, o), "");
      o.mode = tt::ProxyMode::kVelocity;
      ASSERT_EQ(velocity.init(info, o), "");
      std::vector<tacse3::dsp::Pose> poses, velocity_poses;
      double grasp_drift_mm = -1.0;  // the velocity reading's travel before the object moves
      tt::FrameResult ra, rv;
      for (std::size_t i = 0; i < info.frame_count(); ++i) {
        std::array<const tacse3::dsp::FrameView*, 2> views{};
        ASSERT_EQ(src->read(i, &views), "");
        ASSERT_EQ(automatic.step_views(views, info.t_ns[i], i, &ra), "");
        ASSERT_EQ(velocity.step_views(views, info.t_ns[i], i, &rv), "");
        poses.push_back(ra.pose);
        velocity_poses.push_back(rv.pose);
        const double moved = tt::truth_pose_at(info.truth, info.t_ns[i]).p.norm();
        if (grasp_drift_mm < 0.0 && moved > 1e-6) grasp_drift_mm = rv.pose.p.norm() * 1e3;
      }
      const tt::PoseErrors e = tt::pose_errors(poses, info.truth, info.t_ns);
      const tt::PoseErrors ev = tt::pose_errors(velocity_poses, info.truth, info.t_ns);
      std::printf(
          "sphere %s 10 mm, seed 3, area bound %s: the velocity reading moved %.3f mm "
          "during the grasp and ends %.3f mm off; auto ends %.3f mm off (%.2f deg)\n",
          axis, area_bound ? "on" : "off", grasp_drift_mm, ev.final_translation_error_mm,
          e.final_translation_error_mm, e.final_rotation_error_deg);
      if (area_bound) {
        // The forming mask's centroid jumps are read from the material points.
        EXPECT_LT(grasp_drift_mm, 0.05) << axis;
      } else {
        // The case still shows the grasp's centroid motion, or it would test nothing.
        EXPECT_GT(grasp_drift_mm, 0.1) << axis;
        // auto pays the slide back but not the grasp, so it ends clearly closer to the truth
        // than the velocity reading; paying the grasp back, it would end where velocity does.
        EXPECT_LT(e.final_translation_error_mm, ev.final_translation_error_mm - 0.05) << axis;
      }
      // The translation goal of docs/accuracy.md.
      EXPECT_LT(e.final_translation_error_mm, 0.2) << axis;
    }
  }
}

// The block flow on the simulator's pressed, shaded, noisy gel: the pattern at the patch is
// strained (the bulge, the shear) and shaded, so a correct match leaves more residual than on a
// shifted frame. A tight residual bound (0.15 of the template energy) leaves points around and
// inside the patch untracked, and the smoothed field, 𝒢 and the mask lean away from them.
TEST(Accuracy, TheFlowTracksThePressedGelEverywhere) {
  const tt::SimCase c = tt::make_sim_case("sphere", "rz", 30, 1, 0);
  std::string err;
  const auto src = open_sim(c, &err);
  ASSERT_TRUE(src) << err;
  const tt::SourceInfo& info = src->info();
  // Per pad, the default flow and beside it one with the tight bound (0.15). The tight bound
  // must lose points here: otherwise the simulator does not strain the gel enough for this test
  // to show anything.
  tacse3::dsp::BlockFlowConfig old_bound;
  old_bound.max_residual_ratio = 0.15;
  constexpr int kPads = 2;
  std::array<std::unique_ptr<tacse3::dsp::BlockFlow>, 2 * kPads> flows;  // ~1 MB each: heap
  for (int pad = 0; pad < kPads; ++pad) {
    flows[2 * pad] = std::make_unique<tacse3::dsp::BlockFlow>();
    flows[2 * pad + 1] = std::make_unique<tacse3::dsp::BlockFlow>(old_bound);
  }
  tacse3::dsp::WorkImage img;
  tacse3::dsp::VectorField d;
  tacse3::dsp::GridMask v;
  // Default timeline: the grasp ends at 0.5 s, the motion runs 0.6-1.6 s, the hold to the end.
  std::array<int, 2 * kPads> worst_rest{}, worst_moving{};
  for (std::size_t i = 0; i < info.frame_count(); ++i) {
    std::array<const tacse3::dsp::FrameView*, 2> views{};
    ASSERT_EQ(src->read(i, &views), "");
    const double t = static_cast<double>(info.t_ns[i] - info.t_ns[0]) * 1e-9;
    for (int pad = 0; pad < kPads; ++pad) {
      ASSERT_NE(views[static_cast<std::size_t>(pad)], nullptr);
      ASSERT_EQ(tacse3::dsp::frame_to_work_image(*views[static_cast<std::size_t>(pad)], img),
                tacse3::dsp::Status::kOk);
      for (int k = 2 * pad; k < 2 * pad + 2; ++k) {
        const auto u = static_cast<std::size_t>(k);
        flows[u]->track(img, d, v);
        const int untracked = tacse3::dsp::kGridCount - flows[u]->valid_count();
        if (t >= 0.5 && t < 0.6) worst_rest[u] = std::max(worst_rest[u], untracked);
        if (t >= 0.6) worst_moving[u] = std::max(worst_moving[u], untracked);
      }
    }
  }
  for (std::size_t k = 0; k < flows.size(); ++k) {
    std::printf(
        "sphere rz 30, %s pad, max_residual_ratio %.2f: at most %d of %d flow points "
        "untracked at rest after the grasp, %d during the torsion and the hold\n",
        k < 2 ? "left" : "right", flows[k]->config().max_residual_ratio, worst_rest[k],
        tacse3::dsp::kGridCount, worst_moving[k]);
  }
  for (std::size_t k = 0; k < flows.size(); k += 2) {
    EXPECT_LE(worst_rest[k], tacse3::dsp::kGridCount / 100) << "pad " << k / 2;
    EXPECT_LE(worst_moving[k], tacse3::dsp::kGridCount * 3 / 100) << "pad " << k / 2;
    EXPECT_GT(worst_rest[k + 1], tacse3::dsp::kGridCount * 5 / 100) << "pad " << k / 2;
  }
}

// The area bound's own effect on `auto` (the sphere above is handled by the unloaded-stick rule
// as well): the textured cube's flat face is first seen at one corner, so its mask grows many
// times over in the grasp and the velocity reading jumps by millimetres; the grasp is loaded,
// so no stick is confirmed before the slide and without the bound `auto` would pay the jump
// back. The grasp's planar shear content sits close to slip_min_shift_m, where the
// unloaded-stick rule may cover it too: the test pins the minimum shift at 10 µm so that the
// bound alone is what it measures.
TEST(Accuracy, AFlatFaceFirstSeenAtACornerIsNotReadAsATranslation) {
  tacse3::config::CalibrationSet committed = committed_calibration();
  ASSERT_FALSE(::testing::Test::HasFailure());
  for (auto& s : committed.sensor) s.slip_min_shift_m = 10e-6;
  const tt::SimCase c = tt::make_sim_case("textured-cube", "tx", 10.0, 2, 0.0);
  tacse3::config::CalibrationSet off = committed;
  for (auto& s : off.sensor) s.max_mask_area_ratio = 1e4;
  const tt::PoseErrors on_e = replay_errors(c, committed);
  const tt::PoseErrors off_e = replay_errors(c, off);
  std::printf("%s: error %.2f mm with the area bound, %.2f mm without\n", c.sim_arguments().c_str(),
              on_e.final_translation_error_mm, off_e.final_translation_error_mm);
  EXPECT_LT(on_e.final_translation_error_mm, 1.0);
  EXPECT_GT(off_e.final_translation_error_mm, 5.0);
}

// 10 mm slides where the block flow's chain can take a wrong match while the gel springs back
// behind the patch: at a keyframe switch the direct match against the tare is valid but
// disagrees with the chain by more than a tight re-anchoring tolerance accepts. A wrong chain,
// kept, makes the gel left at rest read as deformed, f^z stays above the contact threshold
// there and a phantom contact holds the weighted centroid back. Every valid direct match
// replaces the chain (docs/dsp/flow.md, re-anchoring). Defaults, committed calibration, as a
// user would replay them.
TEST(Accuracy, AChainThatTookAWrongMatchIsReanchoredToTheTare) {
  const tacse3::config::CalibrationSet cal = committed_calibration();
  ASSERT_FALSE(::testing::Test::HasFailure());
  for (const tt::SimCase& c : {tt::make_sim_case("screwdriver", "tx", 10.0, 2, 0.0),
                               tt::make_sim_case("sphere", "tx", 10.0, 4, 0.0, 2.0)}) {
    const tt::PoseErrors e = replay_errors(c, cal);
    std::printf("%s: translation %.2f mm for 10 mm, error %.2f mm (rotation drift %.2f deg)\n",
                c.sim_arguments().c_str(), e.estimated_translation_mm, e.final_translation_error_mm,
                e.final_rotation_error_deg);
    EXPECT_LT(e.final_translation_error_mm, 0.5) << c.sim_arguments();
    EXPECT_LT(e.final_rotation_error_deg, 1.0) << c.sim_arguments();
  }
}

// A grasp released at the end: after the hold the pads open over 0.3 s and the contact vanishes;
// the object stays where the motion left it. The stuck gel springs back as it is let go, which
// the displacement proxy would read as the object moving back, and its relaxation would start a
// slip whose payback adds the velocity proxy's reading of the held shear. The detector counts
// only relaxation beyond the load's own fall, and frames whose load Σ z falls faster than
// release_load_rate drop the displacement reading (docs/dsp/motion.md, release). Defaults,
// committed calibration.
TEST(Accuracy, AReleasedGraspKeepsThePoseItHeld) {
  const tacse3::config::CalibrationSet committed = committed_calibration();
  ASSERT_FALSE(::testing::Test::HasFailure());
  tacse3::config::CalibrationSet no_gate = committed;
  for (auto& s : no_gate.sensor) s.release_load_rate = 1e4;
  tt::SimCase rx = tt::make_sim_case("sphere", "rx", 2.0, 3, 0.0);
  rx.release_s = 0.3;
  tt::SimCase ty = tt::make_sim_case("sphere", "ty", 0.5, 3, 0.0);
  ty.release_s = 0.3;
  const tt::PoseErrors rx_on = replay_errors(rx, committed);
  const tt::PoseErrors rx_off = replay_errors(rx, no_gate);
  const tt::PoseErrors ty_on = replay_errors(ty, committed);
  std::printf("%s: rotation %.2f deg for 2, error %.2f deg (%.2f without the release rule)\n",
              rx.sim_arguments().c_str(), rx_on.estimated_rotation_deg,
              rx_on.final_rotation_error_deg, rx_off.final_rotation_error_deg);
  std::printf("%s: translation %.2f mm for 0.5, error %.2f mm\n", ty.sim_arguments().c_str(),
              ty_on.estimated_translation_mm, ty_on.final_translation_error_mm);
  EXPECT_LT(rx_on.final_rotation_error_deg, 0.5);
  EXPECT_GT(rx_off.final_rotation_error_deg, 1.0);
  EXPECT_LT(ty_on.final_translation_error_mm, 0.2);
  EXPECT_LT(ty_on.final_rotation_error_deg, 0.5);
}

// A gap in the stream in the middle of a stick motion (the clock moves on by 0.2 s, longer than
// max_frame_gap_s, while the frames continue where they were, so only the one increment across
// it is not read) restarts the motion differencing, but the gel is still stretched by the
// tangential load: the displacement proxy keeps reading over the patch anchored before the
// load (docs/dsp/motion.md, patch anchor). Re-anchored to the stretched Ω, the increments after
// the gap would be diluted and the motion would read short.
TEST(Accuracy, AFrameGapDuringAStickMotionKeepsThePatchAnchor) {
  const tacse3::config::CalibrationSet cal = committed_calibration();
  ASSERT_FALSE(::testing::Test::HasFailure());
  const tt::SimCase c = tt::make_sim_case("sphere", "rx", 4.0, 1, 0.0);
  // The motion runs 0.6-1.17 s; from 0.9 s (frame 108, a little past the middle) the clock
  // jumps by 0.2 s.
  const WholeAndAltered r = replay_whole_and_altered(
      c, cal, [](std::size_t i, std::array<const tacse3::dsp::FrameView*, 2>&, std::int64_t& t) {
        if (i < 108) return false;
        t += 200'000'000;
        return true;
      });
  std::printf("%s: %.2f deg (error %.2f), with a 0.2 s gap half-way %.2f deg (error %.2f)\n",
              c.sim_arguments().c_str(), r.whole.estimated_rotation_deg,
              r.whole.final_rotation_error_deg, r.altered.estimated_rotation_deg,
              r.altered.final_rotation_error_deg);
  EXPECT_LT(r.whole.final_rotation_error_deg, 0.2);
  // The gap loses the one increment across it (the fastest frame of the motion: 0.1°).
  EXPECT_LT(r.altered.final_rotation_error_deg, 0.25);
  EXPECT_LT(r.whole.estimated_rotation_deg - r.altered.estimated_rotation_deg, 0.2);
}

// Every axis a recording turns about is fitted for the proxy that explains it, from 1 deg of
// rotation (tacse3-calibrate, docs/calibration.md stage 2). A higher floor would skip the only
// stick recording about y (2 deg) and leave the displacement proxy's y scale to the velocity
// proxy's fit on the slide (the report's note would say so), and a stick about y would read over.
TEST(Accuracy, ATwoDegreeStickRotationFitsItsAxisForTheDisplacementProxy) {
  const std::vector<tt::SimCase> cal = {short_case("sphere", "ry", 30, 7, 18),
                                        short_case("sphere", "rx", 3, 7, 18),
                                        short_case("sphere", "ry", 2, 7, 18)};
  tt::CalibrateOptions co;
  co.jobs = 2;
  tt::CalibrateReport rep;
  const std::string e = tt::calibrate_cases(cal, co, &rep);
  ASSERT_TRUE(e.empty()) << e;
  std::printf("%s", tt::format_report(rep).c_str());
  ASSERT_EQ(rep.recordings.size(), 3u);
  EXPECT_EQ(rep.recordings[0].explained_by, tt::ProxyMode::kVelocity);
  EXPECT_EQ(rep.recordings[2].explained_by, tt::ProxyMode::kDisplacement);
  for (const std::string& n : rep.notes)
    EXPECT_EQ(n.find("proxy's y scale is the other proxy's"), std::string::npos) << n;
  // A borrowed scale shows as a ratio of exactly 1.
  EXPECT_NE(rep.calibration.sensor[0].displacement_rotation_ratio[1], 1.0);
  // A stick about y on another seed and size, with the defaults (joint, auto).
  const tt::PoseErrors ry = replay_errors(short_case("sphere", "ry", 2, 1, 20), rep.calibration);
  std::printf("sphere ry 2 deg (seed 1, radius 20 mm): %.2f deg, error %.2f deg\n",
              ry.estimated_rotation_deg, ry.final_rotation_error_deg);
  // With a higher floor the note check above fails. The displacement proxy reads the anchored
  // patch (docs/dsp/motion.md), so even a borrowed y scale reads this stick closely: this bound
  // alone does not tell the floors apart.
  EXPECT_LT(ry.final_rotation_error_deg, 0.10);
}

// The velocity proxy reads a slide about an in-plane axis at any speed with the same gain
// (docs/dsp/motion.md, drag region). Without the friction cap (--friction 5: the gel's shear is
// c·v at every speed but on a thin rim of the patch, and its integral over the motion is c times
// the angle), the same 30° about x in 0.5 s and in 2 s must read the same. Read over all of Ω,
// the faster slide would read less: Ω leaves the patch for the stretched gel behind it the more
// the faster the slide.
TEST(Accuracy, TheVelocityProxyReadsAnInPlaneSlideAtAnySpeed) {
  const tacse3::config::CalibrationSet cal = committed_calibration();
  double read[2] = {0.0, 0.0};
  const double motion_s[2] = {0.5, 2.0};
  for (int k = 0; k < 2; ++k) {
    tt::SimCase c = tt::make_sim_case("sphere", "rx", 30, 1, 0);
    c.friction = 5.0;
    const tt::PoseErrors e =
        replay_errors(c, cal, tt::ProxyMode::kVelocity,
                      [&](tacse3::sim::SimConfig& sc) { sc.scenario.motion_s = motion_s[k]; });
    read[k] = e.estimated_rotation_deg;
    std::printf("sphere rx 30 deg in %.1f s, friction 5, --mode velocity: %.2f deg\n", motion_s[k],
                read[k]);
  }
  ASSERT_GT(read[1], 15.0);
  EXPECT_NEAR(read[0] / read[1], 1.0, 0.03);
}

// Without the friction cap the pipeline reads an in-plane rotation with one gain at any angle,
// so the benchmark's 60° and 90° shortfall is the cap's (docs/accuracy.md): the same sphere
// turned 30° (in 1 s) and 90° (in 2 s, 1.5 times the peak speed) about x with --friction 5,
// defaults (joint, auto), must read the same per degree. The committed calibration was fitted
// with the cap, so without it both read above the angle; only their ratio is bounded.
TEST(Accuracy, WithoutTheFrictionCapThirtyAndNinetyDegreesReadWithOneGain) {
  const tacse3::config::CalibrationSet cal = committed_calibration();
  double per_degree[2] = {0.0, 0.0};
  const double angle[2] = {30.0, 90.0};
  for (int k = 0; k < 2; ++k) {
    tt::SimCase c = tt::make_sim_case("sphere", "rx", angle[k], 1, 0);
    c.friction = 5.0;
    const tt::PoseErrors e = replay_errors(c, cal);
    per_degree[k] = e.estimated_rotation_deg / angle[k];
    std::printf("%s: %.2f deg, %.3f per degree\n", c.sim_arguments().c_str(),
                e.estimated_rotation_deg, per_degree[k]);
  }
  ASSERT_GT(per_degree[0], 0.5);
  EXPECT_NEAR(per_degree[1] / per_degree[0], 1.0, 0.03);
}

}  // namespace
