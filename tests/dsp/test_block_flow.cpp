// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: block flow (Eq. (dense_flow)) against analytic warps and the double reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <tuple>
#include <vector>

#include "support/synthetic.hpp"
#include "tacse3/dsp/block_flow.hpp"
#include "tacse3/dsp/luma.hpp"
#include "tacse3/dsp/pyramid.hpp"
#include "tacse3/dsp_ref/block_flow_ref.hpp"

namespace tacse3::dsp {
namespace {

using test::Vec2;
using test::Warp;

constexpr double kQ16 = 65536.0;

// One texture and its undeformed frame for the whole executable.
const test::DotTexture& texture() {
  static const test::DotTexture tex(42);
  return tex;
}
const WorkImage& undeformed() {
  static const WorkImage img = test::render_work_image(texture(), Warp::identity());
  return img;
}

// ~1 MB objects: on the heap in tests (the firmware holds them in static storage).
std::unique_ptr<BlockFlow> make_flow(const BlockFlowConfig& cfg = {}) {
  auto f = std::make_unique<BlockFlow>();
  EXPECT_EQ(f->configure(cfg), Status::kOk);
  return f;
}

struct FlowError {
  double rms = 0;
  double max = 0;
  int valid = 0;
};

// Error of the tracked displacement against the warp's ground truth over the valid points.
FlowError error_against(const Warp& w, const VectorField& d, const GridMask& v) {
  FlowError e;
  double sum = 0;
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      if (!v(gx, gy)) continue;
      const Vec2 t = w.grid_displacement_work(gx, gy);
      const double ex = d.x(gx, gy) / kQ16 - t[0];
      const double ey = d.y(gx, gy) / kQ16 - t[1];
      sum += ex * ex + ey * ey;
      e.max = std::max(e.max, std::hypot(ex, ey));
      ++e.valid;
    }
  }
  e.rms = e.valid > 0 ? std::sqrt(sum / e.valid) : 0.0;
  return e;
}

// Grid points whose 8x8 window (pushed 1 px inside the image) still lies inside the image
// after the warp: the ones that can be tracked at all.
int trackable_points(const Warp& w) {
  int n = 0;
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const double cx = std::clamp(grid_work_x(gx), 4.5, kWorkWidth - 5.5);
      const double cy = std::clamp(grid_work_y(gy), 4.5, kWorkHeight - 5.5);
      const Vec2 t = w.grid_displacement_work(gx, gy);
      const double x = cx + t[0], y = cy + t[1];
      if (x - 3.5 >= 0 && y - 3.5 >= 0 && x + 3.5 <= kWorkWidth - 1 && y + 3.5 <= kWorkHeight - 1)
        ++n;
    }
  }
  return n;
}

// Tare on the undeformed frame, then one frame under `w`.
FlowError track_once(BlockFlow& f, const Warp& w, const test::Photometric& ph = {},
                     const test::Photometric& ph_ref = {}) {
  const bool plain_ref = ph_ref.gain == 1.0 && ph_ref.offset == 0.0 && ph_ref.noise_sigma == 0.0 &&
                         ph_ref.vignetting == 0.0;
  f.tare(plain_ref ? undeformed() : test::render_work_image(texture(), Warp::identity(), ph_ref));
  VectorField d;
  GridMask v;
  f.track(test::render_work_image(texture(), w, ph), d, v);
  return error_against(w, d, v);
}

void report(const char* what, const FlowError& e) {
  std::printf("  %-44s rms %.4f px  max %.4f px  valid %d\n", what, e.rms, e.max, e.valid);
  ::testing::Test::RecordProperty(what, std::to_string(e.rms));
}

// --- Accuracy against analytic warps -------------------------------------------------------

// docs/dsp/flow.md quotes this size: the object holds every frame's scratch (no heap, no large
// stack frames), one per sensor in static storage. The bound is the budget that statement relies
// on.
TEST(BlockFlow, StaticFootprint) {
  std::printf("  sizeof(BlockFlow) = %zu bytes\n", sizeof(BlockFlow));
  EXPECT_LE(sizeof(BlockFlow), std::size_t{1792} * 1024);
}

TEST(BlockFlow, SubPixelShifts) {
  auto f = make_flow();
  // Working px (sensor px / 2); the warp is given in sensor px.
  const Vec2 shifts[] = {{0.25, 0.0}, {0.5, -0.375}, {-0.7, 0.3}, {0.125, 0.9}, {1.3, -1.1}};
  for (const Vec2& s : shifts) {
    const Warp w = Warp::shift(2 * s[0], 2 * s[1]);
    const FlowError e = track_once(*f, w);
    char name[64];
    std::snprintf(name, sizeof name, "shift (%.3f, %.3f)", s[0], s[1]);
    report(name, e);
    EXPECT_LE(e.rms, 0.05) << name;
    EXPECT_LE(e.max, 0.25) << name;
    EXPECT_GE(e.valid, trackable_points(w) * 95 / 100) << name;
  }
}

TEST(BlockFlow, AffineWarps) {
  auto f = make_flow();
  struct Case {
    const char* name;
    Warp w;
  };
  const double c = std::cos(0.015), s = std::sin(0.015);  // 0.86 degree
  const Case cases[] = {
      {"scale 2% + shear 1.5% + shift", Warp::affine(1.02, 0.015, -0.01, 0.985, 1.1, -0.7)},
      {"rotation 0.86 deg + shift", Warp::affine(c, -s, s, c, -0.6, 0.9)},
      {"compression 3%", Warp::affine(0.97, 0.0, 0.0, 0.97, 0.0, 0.0)},
  };
  for (const Case& k : cases) {
    const FlowError e = track_once(*f, k.w);
    report(k.name, e);
    EXPECT_LE(e.rms, 0.05) << k.name;
    EXPECT_GE(e.valid, trackable_points(k.w) * 90 / 100) << k.name;
  }
}

// Sensor noise, LED flicker (gain), offset and vignetting on both frames.
TEST(BlockFlow, RobustToPhotometricDisturbances) {
  auto f = make_flow();
  test::Photometric ref_ph, cur_ph;
  ref_ph.noise_sigma = 1.0;
  ref_ph.noise_seed = 3;
  ref_ph.vignetting = 0.2;
  cur_ph = ref_ph;
  cur_ph.noise_seed = 4;
  cur_ph.gain = 1.02;
  cur_ph.offset = -6.0;
  const Warp w = Warp::shift(0.9, -0.5);
  const FlowError e = track_once(*f, w, cur_ph, ref_ph);
  report("shift + noise 1 + gain 2% + offset + vignette", e);
  EXPECT_LE(e.rms, 0.05);
  EXPECT_GE(e.valid, trackable_points(w) * 95 / 100);
  cur_ph.gain = 0.98;
  cur_ph.offset = 8.0;
  const FlowError e2 = track_once(*f, w, cur_ph, ref_ph);
  report("same, gain -2%", e2);
  EXPECT_LE(e2.rms, 0.05);
}

// Large jumps with no warm start (tare, then one frame far away) are recovered by the pyramid;
// the same jumps without the pyramid are not.
TEST(BlockFlow, LargeShiftsRecoveredThroughThePyramid) {
  auto f = make_flow();
  BlockFlowConfig one_level;
  one_level.pyramid_levels = 1;
  auto flat = make_flow(one_level);
  const Vec2 shifts[] = {{8.0, -4.0}, {-10.0, 6.0}, {6.5, 9.25}, {-7.3, -7.6}};
  for (const Vec2& s : shifts) {
    const Warp w = Warp::shift(2 * s[0], 2 * s[1]);
    const FlowError e = track_once(*f, w);
    char name[64];
    std::snprintf(name, sizeof name, "jump (%.2f, %.2f), 3 levels", s[0], s[1]);
    report(name, e);
    EXPECT_LE(e.rms, 0.05) << name;
    EXPECT_LE(e.max, 0.25) << name;
    EXPECT_GE(e.valid, trackable_points(w) * 90 / 100) << name;
    // Level 0 alone lost (nearly) every window; the coarse levels ran and the retry got them.
    const BlockFlow::CoarseFallback& c = f->last_coarse_fallback();
    EXPECT_TRUE(c.ran) << name;
    EXPECT_GE(c.failed, trackable_points(w) * 90 / 100) << name;
    EXPECT_EQ(c.failed_fresh, c.failed) << name << ": the tare had tracked every window";
    EXPECT_GE(c.recovered, trackable_points(w) * 80 / 100) << name;
    EXPECT_LE(c.recovered, e.valid) << name;
    const FlowError flat_e = track_once(*flat, w);
    std::snprintf(name, sizeof name, "jump (%.2f, %.2f), 1 level", s[0], s[1]);
    report(name, flat_e);
    EXPECT_LT(flat_e.valid, trackable_points(w) / 10) << name;
    EXPECT_FALSE(flat->last_coarse_fallback().ran) << name << ": no coarse level to run";
    EXPECT_GE(flat->last_coarse_fallback().failed, trackable_points(w) * 90 / 100) << name;
  }
}

// A jump confined to one patch: the coarse fallback tracks only the coarse windows that the
// failed windows draw on (dsp::CoarseRegion), and the retry recovers them all the same.
TEST(BlockFlow, ALocalJumpIsRecoveredByALocalCoarsePass) {
  auto f = make_flow();
  // A Gaussian bump of 8 sensor px (4 working px, beyond level 0's reach) at (100, 80), sigma
  // 24 px: its largest strain (0.2) keeps the warp invertible.
  const Warp w = Warp::displacement([](double x, double y) {
    const double dx = x - 100.0, dy = y - 80.0;
    const double a = 8.0 * std::exp(-(dx * dx + dy * dy) / (2 * 24.0 * 24.0));
    return Vec2{a, -0.5 * a};
  });
  const FlowError e = track_once(*f, w);
  report("local bump of 4 working px", e);
  EXPECT_LE(e.rms, 0.05);
  EXPECT_GE(e.valid, trackable_points(w) * 95 / 100);
  const BlockFlow::CoarseFallback& c = f->last_coarse_fallback();
  std::printf("  coarse pass: %d failed, %d recovered, %d coarse windows tracked\n", c.failed,
              c.recovered, c.coarse_windows);
  ASSERT_TRUE(c.ran);
  EXPECT_GE(c.failed, 10) << "the bump is beyond level 0's reach";
  EXPECT_GE(c.recovered, c.failed * 8 / 10);
  EXPECT_GT(c.coarse_windows, 0);
  EXPECT_LT(c.coarse_windows, (flow_grid_count(1) + flow_grid_count(2)) / 2)
      << "most of the grid did not move: its coarse windows are not needed";
}

// --- Sequences: warm start, keyframe chaining, tare ----------------------------------------

// A contact-like deformation: a Gaussian shear bump plus a small rotation, expansion and
// translation, all growing linearly with `s` in [0, 1]. At s = 1 the displacement reaches
// ~7 working px; strains stay below ~6 %.
Warp growing_deformation(double s) {
  return Warp::displacement([s](double x, double y) {
    const double mx = x - kPadCentreX, my = y - kPadCentreY;
    const double bx = x - 180.0, by = y - 110.0;
    const double bump = 9.0 * std::exp(-(bx * bx + by * by) / (2.0 * 70.0 * 70.0));
    const double rot = 0.02, grow = 0.012;
    return Vec2{s * (4.0 + bump - rot * my + grow * mx),
                s * (-2.0 + 0.6 * bump + rot * mx + grow * my)};
  });
}

TEST(BlockFlow, GrowingDeformationStaysTrackedAcrossKeyframes) {
  auto f = make_flow();
  f->tare(undeformed());
  VectorField d;
  GridMask v;
  constexpr int kFrames = 24;  // ~0.3 working px per frame at the bump
  FlowError worst;
  for (int k = 1; k <= kFrames; ++k) {
    const Warp w = growing_deformation(static_cast<double>(k) / kFrames);
    test::Photometric ph;
    ph.noise_sigma = 0.5;
    ph.noise_seed = static_cast<std::uint64_t>(100 + k);
    f->track(test::render_work_image(texture(), w, ph), d, v);
    const FlowError e = error_against(w, d, v);
    worst.rms = std::max(worst.rms, e.rms);
    ASSERT_LE(e.rms, 0.06) << "frame " << k;
    ASSERT_GE(e.valid, trackable_points(w) * 85 / 100) << "frame " << k;
  }
  const Warp last = growing_deformation(1.0);
  const FlowError e = error_against(last, d, v);
  report("growing deformation, final frame", e);
  std::printf("  keyframe switches %u, worst per-frame rms %.4f px\n", f->keyframe_switches(),
              worst.rms);
  RecordProperty("keyframe_switches", static_cast<int>(f->keyframe_switches()));
  EXPECT_GE(f->keyframe_switches(), 3u);
  EXPECT_LE(e.rms, 0.05);
  // The drift relative to the undeformed reference is what keyframe chaining must avoid: the
  // same final frame tracked in one jump from the tare frame gives the comparison.
  BlockFlowConfig no_chain;
  no_chain.keyframe_switch_px = 0.0;
  auto direct = make_flow(no_chain);
  const FlowError one_jump = track_once(*direct, last);
  report("same final frame, one jump from tare", one_jump);
}

// A keyframe's window models are built in pieces over the frames after the switch (tare: the
// coarse levels later; switch: level 0 in its deferred work, the coarse levels after), and the
// switch's own work is deferred. Three flows must report the same displacements bit for bit and
// end with the same models, with the coarse pass on demand and on every frame: one that leaves
// the deferred work to the next track(), one that runs it after each frame (run_deferred(), as
// the daemon's pad threads do), and one that completes every keyframe at once.
TEST(BlockFlow, KeyframeModelsBuiltInPiecesEqualAOneShotBuild) {
  for (const int trigger : {BlockFlowConfig{}.coarse_trigger, 0}) {
    BlockFlowConfig cfg;
    cfg.coarse_trigger = trigger;
    auto pieces = make_flow(cfg);
    auto one_shot = make_flow(cfg);
    auto deferred = make_flow(cfg);
    pieces->tare(undeformed());
    one_shot->tare(undeformed());
    deferred->tare(undeformed());
    one_shot->complete_keyframe();
    VectorField d1, d2, d3;
    GridMask v1, v2, v3;
    constexpr int kFrames = 24;
    for (int k = 1; k <= kFrames; ++k) {
      const WorkImage img =
          test::render_work_image(texture(), growing_deformation(static_cast<double>(k) / kFrames));
      pieces->track(img, d1, v1);
      one_shot->track(img, d2, v2);
      one_shot->complete_keyframe();
      deferred->track(img, d3, v3);
      ASSERT_TRUE(deferred->deferred_pending());
      ASSERT_EQ(deferred->last_frame_was_keyframe(), pieces->last_frame_was_keyframe());
      deferred->run_deferred();
      ASSERT_FALSE(deferred->deferred_pending());
      ASSERT_EQ(d1.x.v, d2.x.v) << "frame " << k << " trigger " << trigger;
      ASSERT_EQ(d1.y.v, d2.y.v) << "frame " << k;
      ASSERT_EQ(v1.v, v2.v) << "frame " << k;
      ASSERT_EQ(d1.x.v, d3.x.v) << "frame " << k;
      ASSERT_EQ(d1.y.v, d3.y.v) << "frame " << k;
      ASSERT_EQ(v1.v, v3.v) << "frame " << k;
      // After its deferred work, the switch's outcome is the one-shot flow's.
      ASSERT_EQ(deferred->reanchored().v, one_shot->reanchored().v) << "frame " << k;
      ASSERT_EQ(deferred->lost().v, one_shot->lost().v) << "frame " << k;
    }
    ASSERT_GE(pieces->keyframe_switches(), 3u);
    ASSERT_EQ(pieces->keyframe_switches(), one_shot->keyframe_switches());
    pieces->complete_keyframe();
    for (int l = 0; l < cfg.pyramid_levels; ++l) {
      for (int i = 0; i < flow_grid_count(l); ++i) {
        ASSERT_EQ(std::memcmp(&pieces->window_model(l, i), &one_shot->window_model(l, i),
                              sizeof(FlowWindowModel)),
                  0)
            << "level " << l << " window " << i;
        ASSERT_EQ(std::memcmp(&pieces->window_template(l, i), &one_shot->window_template(l, i),
                              sizeof(FlowWindowTemplate)),
                  0);
      }
    }
  }
}

TEST(BlockFlow, WarmStartedSequenceNeedsNoKeyframeForSmallMotion) {
  auto f = make_flow();
  f->tare(undeformed());
  VectorField d;
  GridMask v;
  for (int k = 1; k <= 8; ++k) {
    const Warp w = Warp::shift(0.3 * k, -0.2 * k);  // 0.15 working px per frame, 1.2 in total
    f->track(test::render_work_image(texture(), w), d, v);
    const FlowError e = error_against(w, d, v);
    ASSERT_LE(e.rms, 0.05) << "frame " << k;
    // Steady state: level 0 converges from the warm start, the coarse levels stay idle.
    EXPECT_FALSE(f->last_coarse_fallback().ran) << "frame " << k;
    EXPECT_LT(f->last_coarse_fallback().failed, BlockFlowConfig{}.coarse_trigger) << "frame " << k;
  }
  EXPECT_EQ(f->keyframe_switches(), 0u);
  EXPECT_EQ(f->frames_since_keyframe(), 8u);
}

// A region that stops being trackable fails fresh in its first frame and stale after: the
// fallback's counts tell the two apart (dsp::BlockFlow::CoarseFallback).
TEST(BlockFlow, AWindowThatKeepsFailingIsCountedFreshOnce) {
  auto f = make_flow();
  f->tare(undeformed());
  VectorField d;
  GridMask v;
  std::array<int, 3> failed{}, fresh{};
  for (int k = 1; k <= 3; ++k) {
    const Warp w = Warp::shift(0.2 * k, 0.1 * k);
    WorkImage img = test::render_work_image(texture(), w);
    if (k >= 2) {  // a flat patch from the second frame on: its windows lose their texture
      for (int y = 40; y < 80; ++y) {
        for (int x = 50; x < 100; ++x) img.at(x, y) = 128 << 2;
      }
    }
    f->track(img, d, v);
    failed[static_cast<std::size_t>(k - 1)] = f->last_coarse_fallback().failed;
    fresh[static_cast<std::size_t>(k - 1)] = f->last_coarse_fallback().failed_fresh;
  }
  EXPECT_LT(failed[0], BlockFlowConfig{}.coarse_trigger) << "the clean frame";
  EXPECT_GE(failed[1], 10) << "the patch's windows fail";
  EXPECT_EQ(fresh[1], failed[1]) << "all of them tracked in the frame before";
  EXPECT_GE(failed[2], failed[1] * 9 / 10) << "and keep failing";
  EXPECT_LE(fresh[2], failed[2] / 10) << "now stale, not fresh";
}

// The coarse levels run on demand (coarse_trigger failures at level 0). Forcing them on every
// frame must not change the result of a smooth sequence beyond the sub-pixel noise floor.
TEST(BlockFlow, CoarseLevelsOnDemandOrEveryFrameAgree) {
  BlockFlowConfig every;
  every.coarse_trigger = 0;
  auto a = make_flow();
  auto b = make_flow(every);
  a->tare(undeformed());
  b->tare(undeformed());
  VectorField da, db;
  GridMask va, vb;
  for (int k = 1; k <= 6; ++k) {
    const Warp w = growing_deformation(0.05 * k);
    const WorkImage img = test::render_work_image(texture(), w);
    a->track(img, da, va);
    b->track(img, db, vb);
    ASSERT_LE(error_against(w, da, va).rms, 0.05) << "frame " << k;
    ASSERT_LE(error_against(w, db, vb).rms, 0.05) << "frame " << k;
  }
  double sum = 0;
  int n = 0;
  for (int i = 0; i < kGridCount; ++i) {
    const auto u = static_cast<std::size_t>(i);
    if (!va.v[u] || !vb.v[u]) continue;
    const double ex = (da.x.v[u] - db.x.v[u]) / kQ16, ey = (da.y.v[u] - db.y.v[u]) / kQ16;
    sum += ex * ex + ey * ey;
    ++n;
  }
  EXPECT_GT(n, kGridCount * 9 / 10);
  EXPECT_LE(std::sqrt(sum / n), 0.02);
}

TEST(BlockFlow, TareResetsTheReference) {
  auto f = make_flow();
  f->tare(undeformed());
  VectorField d;
  GridMask v;
  const Warp moved = Warp::shift(7.0, 3.0);
  const WorkImage moved_img = test::render_work_image(texture(), moved);
  f->track(test::render_work_image(texture(), Warp::shift(3.0, 1.0)), d, v);
  f->track(moved_img, d, v);
  ASSERT_GT(f->keyframe_switches(), 0u);
  ASSERT_NEAR(d.x(20, 15) / kQ16, 3.5, 0.05);
  f->tare(moved_img);
  EXPECT_EQ(f->keyframe_switches(), 0u);
  f->track(moved_img, d, v);
  for (int i = 0; i < kGridCount; ++i) {
    ASSERT_EQ(d.x.v[static_cast<std::size_t>(i)], 0);
    ASSERT_EQ(d.y.v[static_cast<std::size_t>(i)], 0);
  }
  EXPECT_EQ(f->valid_count(), f->keyframe_valid_count());
  // Motion is now measured from the new reference.
  const Warp more = Warp::shift(7.0 + 1.0, 3.0 - 0.5);
  f->track(test::render_work_image(texture(), more), d, v);
  EXPECT_NEAR(d.x(20, 15) / kQ16, 0.5, 0.05);
  EXPECT_NEAR(d.y(20, 15) / kQ16, -0.25, 0.05);
}

// The first frame becomes the reference in the deferred work, as a tare's frame does: it reports
// zeros and no valid point, and the reference it leaves is the one tare() builds from it.
TEST(BlockFlow, FirstCallIsAnImplicitTareDeferred) {
  auto f = make_flow();
  EXPECT_FALSE(f->has_reference());
  VectorField d;
  d.x.fill(123);
  GridMask v;
  v.v.fill(1);
  f->track(undeformed(), d, v);
  EXPECT_TRUE(f->has_reference());
  EXPECT_TRUE(f->deferred_pending()) << "the models are built after the frame";
  EXPECT_TRUE(f->last_frame_was_keyframe());
  for (int i = 0; i < kGridCount; ++i) {
    ASSERT_EQ(d.x.v[static_cast<std::size_t>(i)], 0);
    ASSERT_EQ(v.v[static_cast<std::size_t>(i)], 0);
  }
  EXPECT_EQ(f->valid_count(), 0);
  f->run_deferred();
  auto tared = make_flow();
  tared->tare(undeformed());
  f->complete_keyframe();
  tared->complete_keyframe();
  // Nearly every window of a random-dot texture is trackable (a few fall in a gap between dots).
  EXPECT_GE(f->keyframe_valid_count(), kGridCount * 99 / 100);
  EXPECT_EQ(f->keyframe_valid_count(), tared->keyframe_valid_count());
  for (int l = 0; l < BlockFlowConfig{}.pyramid_levels; ++l) {
    for (int i = 0; i < flow_grid_count(l); ++i) {
      const FlowWindowModel& a = f->window_model(l, i);
      const FlowWindowModel& b = tared->window_model(l, i);
      const auto key = [](const FlowWindowModel& m) {
        return std::make_tuple(m.valid, m.ox, m.oy, m.shift, m.inv_a, m.inv_b, m.inv_c, m.gsum_x,
                               m.gsum_y, m.tsum, m.gain_qx, m.gain_qy, m.template_energy,
                               m.curvature, m.moment_x, m.moment_y);
      };
      ASSERT_EQ(key(a), key(b)) << "level " << l << " window " << i;
    }
  }
  // The next frame is measured against it.
  const Warp w = Warp::shift(1.0, -0.6);
  f->track(test::render_work_image(texture(), w), d, v);
  EXPECT_LE(error_against(w, d, v).rms, 0.05);
  EXPECT_GE(error_against(w, d, v).valid, trackable_points(w) * 95 / 100);
}

// A tare while the first frame's reference is still pending replaces it; a frame tracked before
// the deferred work ran builds it first.
TEST(BlockFlow, APendingFirstReferenceIsReplacedByATareOrBuiltByTheNextFrame) {
  const Warp moved = Warp::shift(3.0, 2.0);
  const WorkImage moved_img = test::render_work_image(texture(), moved);
  VectorField d;
  GridMask v;
  auto f = make_flow();
  f->track(moved_img, d, v);
  f->tare(undeformed());  // the reference is the undeformed frame, not the moved one
  f->track(moved_img, d, v);
  EXPECT_LE(error_against(moved, d, v).rms, 0.05);
  EXPECT_GE(error_against(moved, d, v).valid, trackable_points(moved) * 95 / 100);

  auto g = make_flow();
  g->track(undeformed(), d, v);
  g->track(moved_img, d, v);  // no run_deferred() in between
  EXPECT_LE(error_against(moved, d, v).rms, 0.05);
  EXPECT_GE(error_against(moved, d, v).valid, trackable_points(moved) * 95 / 100);
}

// --- Bad frames -----------------------------------------------------------------------------

TEST(BlockFlow, EmptyAndSaturatedFramesAreFlaggedAndHeld) {
  auto f = make_flow();
  f->tare(undeformed());
  VectorField d;
  GridMask v;
  const Warp w = Warp::shift(1.0, 0.5);
  f->track(test::render_work_image(texture(), w), d, v);
  const VectorField before = d;
  ASSERT_GT(f->valid_count(), kGridCount * 9 / 10);
  for (const std::uint8_t level : {std::uint8_t{0}, std::uint8_t{255}}) {
    const auto bytes = test::constant_frame(level, PixelFormat::kGrey);
    WorkImage blank;
    ASSERT_EQ(frame_to_work_image(test::frame_view(bytes, PixelFormat::kGrey), blank), Status::kOk);
    f->track(blank, d, v);
    int valid = 0;
    for (const auto m : v.v) valid += m;
    EXPECT_EQ(valid, 0) << "level " << int{level};
    EXPECT_EQ(d.x.v, before.x.v);
    EXPECT_EQ(d.y.v, before.y.v);
    EXPECT_EQ(f->keyframe_switches(), 0u);
  }
  // A blank patch in an otherwise good frame: only the points that see it are flagged.
  WorkImage patched = test::render_work_image(texture(), w);
  for (int y = 40; y < 80; ++y) {
    for (int x = 60; x < 100; ++x) patched.at(x, y) = 1020;
  }
  f->track(patched, d, v);
  EXPECT_FALSE(v(20, 15));
  EXPECT_TRUE(v(5, 5));
  EXPECT_NEAR(d.x(5, 5) / kQ16, 0.5, 0.05);
  EXPECT_EQ(d.x(20, 15), before.x(20, 15));  // held
  // And the tracker recovers on the next good frame.
  f->track(test::render_work_image(texture(), w), d, v);
  EXPECT_GT(f->valid_count(), kGridCount * 9 / 10);
  EXPECT_LE(error_against(w, d, v).rms, 0.05);
}

// The other side of max_residual_ratio: a frame of a different random-dot pattern (a swapped
// sensor, a wrong tare) must not be "tracked". The bound is 0.30 so that strained, shaded gel
// under contact stays tracked (tools_test_accuracy TheFlowTracksThePressedGelEverywhere); an
// unrelated window leaves ~1 of its template energy, and the rare chance match below 0.30 has no
// two neighbours agreeing with it (neighbour consensus: a single agreeing neighbour would let
// chance matches through).
TEST(BlockFlow, AnUnrelatedPatternIsNotTracked) {
  auto f = make_flow();
  for (const std::uint64_t seed : {7u, 8u, 9u}) {
    const test::DotTexture other(seed);
    f->tare(undeformed());
    VectorField d;
    GridMask v;
    f->track(test::render_work_image(other, Warp::identity()), d, v);
    std::printf("  pattern seed %d against the tare of seed 42: %d of %d points called tracked\n",
                static_cast<int>(seed), f->valid_count(), kGridCount);
    EXPECT_EQ(f->valid_count(), 0) << "seed " << seed;
  }
}

TEST(BlockFlow, BlankReferenceHasNoTrackablePoints) {
  auto f = make_flow();
  const auto bytes = test::constant_frame(0, PixelFormat::kGrey);
  WorkImage blank;
  ASSERT_EQ(frame_to_work_image(test::frame_view(bytes, PixelFormat::kGrey), blank), Status::kOk);
  VectorField d;
  GridMask v;
  f->track(blank, d, v);
  EXPECT_EQ(f->keyframe_valid_count(), 0);
  f->track(undeformed(), d, v);
  for (int i = 0; i < kGridCount; ++i) {
    ASSERT_EQ(v.v[static_cast<std::size_t>(i)], 0);
    ASSERT_EQ(d.x.v[static_cast<std::size_t>(i)], 0);
  }
}

TEST(BlockFlow, ConfigValidation) {
  BlockFlowConfig good;
  EXPECT_EQ(validate(good), Status::kOk);
  const auto bad = [](auto mutate) {
    BlockFlowConfig c;
    mutate(c);
    return validate(c);
  };
  EXPECT_EQ(bad([](BlockFlowConfig& c) { c.pyramid_levels = 0; }), Status::kBadArgument);
  EXPECT_EQ(bad([](BlockFlowConfig& c) { c.pyramid_levels = kMaxPyramidLevels + 1; }),
            Status::kBadArgument);
  EXPECT_EQ(bad([](BlockFlowConfig& c) { c.fine_iterations = 0; }), Status::kBadArgument);
  EXPECT_EQ(bad([](BlockFlowConfig& c) { c.coarse_iterations = 17; }), Status::kBadArgument);
  EXPECT_EQ(bad([](BlockFlowConfig& c) { c.keyframe_switch_px = std::nan(""); }),
            Status::kBadArgument);
  EXPECT_EQ(bad([](BlockFlowConfig& c) { c.min_texture = -1.0; }), Status::kBadArgument);
  EXPECT_EQ(bad([](BlockFlowConfig& c) { c.max_residual_ratio = INFINITY; }), Status::kBadArgument);
  EXPECT_EQ(bad([](BlockFlowConfig& c) { c.max_step_px = 0.0; }), Status::kBadArgument);
  auto f = make_flow();
  BlockFlowConfig c;
  c.keyframe_switch_px = 3.0;
  ASSERT_EQ(f->configure(c), Status::kOk);
  c.min_eigen_ratio = std::nan("");
  EXPECT_EQ(f->configure(c), Status::kBadArgument);
  EXPECT_EQ(f->config().keyframe_switch_px, 3.0);  // unchanged on error
  EXPECT_EQ(f->config().min_eigen_ratio, BlockFlowConfig{}.min_eigen_ratio);
}

// --- Per-stage agreement with the double reference -----------------------------------------

double snr_db(double signal_energy, double error_energy) {
  return error_energy > 0 ? 10.0 * std::log10(signal_energy / error_energy) : 300.0;
}

// Pyramid: each level rounds once (<= 0.5 LSB against its exact input); level 2 is built from
// the rounded level 1, so it may differ from the unrounded reference by up to 0.5 + 0.5 LSB.
TEST(BlockFlowReference, PyramidLevels) {
  static ImagePyramid pyr;
  build_pyramid(undeformed(), kMaxPyramidLevels, pyr);
  const auto ref = dsp_ref::build_pyramid_ref(undeformed(), kMaxPyramidLevels);
  for (int l = 0; l < kMaxPyramidLevels; ++l) {
    double sig = 0, err = 0, max_err = 0;
    for (int y = 0; y < pyramid_height(l); ++y) {
      for (int x = 0; x < pyramid_width(l); ++x) {
        const double r = ref[static_cast<std::size_t>(l)].at(x, y);
        const double e = pyr.at(l, x, y) - r;
        sig += r * r;
        err += e * e;
        max_err = std::max(max_err, std::abs(e));
      }
    }
    std::printf("  pyramid level %d: SNR %.1f dB, max %.3f LSB\n", l, snr_db(sig, err), max_err);
    EXPECT_LE(max_err, 0.5 * l + 1e-9) << "level " << l;
    EXPECT_GE(snr_db(sig, err), l == 0 ? 300.0 : 60.0) << "level " << l;
  }
}

// Window models: template, gradients, inverse structure tensor and measurement moments of every
// level against the reference. The block-floating-point inverse keeps >= 20 significant bits
// (2^-20); the gain elimination rounds q = k / e to Q16 first, so the Schur complement carries
// a relative error of up to ~2^-16: >= 90 dB at level 0, where both use the same integer input.
// The moments are rounded to Q16 and inherit that error: <= 1e-3 px per unit strain.
TEST(BlockFlowReference, WindowModels) {
  auto f = make_flow();
  f->tare(undeformed());
  f->complete_keyframe();
  dsp_ref::BlockFlowRef ref;
  ref.tare(undeformed());
  for (int l = 0; l < kMaxPyramidLevels; ++l) {
    double sig = 0, err = 0, moment_err = 0;
    int compared = 0;
    for (int i = 0; i < flow_grid_count(l); ++i) {
      const FlowWindowModel& m = f->window_model(l, i);
      const dsp_ref::WindowRef& r = ref.window(l, i);
      ASSERT_EQ(m.ox, r.ox);
      ASSERT_EQ(m.oy, r.oy);
      ASSERT_EQ(m.valid != 0, r.valid) << "level " << l << " window " << i;
      if (!m.valid) continue;
      const FlowWindowTemplate& t = f->window_template(l, i);
      // Packed template = the keyframe plane; gradients = central differences of it.
      const ImagePyramid& kp = f->keyframe_pyramid();
      for (int k = 0; k < kFlowWindowPixels; ++k) {
        const int x = m.ox + k % kFlowWindow, y = m.oy + k / kFlowWindow;
        const auto u = static_cast<std::size_t>(k);
        ASSERT_EQ(t.t[u], kp.at(l, x, y));
        ASSERT_EQ(t.gx[u], kp.at(l, x + 1, y) - kp.at(l, x - 1, y));
        ASSERT_EQ(t.gy[u], kp.at(l, x, y + 1) - kp.at(l, x, y - 1));
      }
      const double scale = std::ldexp(1.0, -(m.shift + 12));
      const Eigen::Matrix2d inv =
          (Eigen::Matrix2d() << m.inv_a, m.inv_b, m.inv_b, m.inv_c).finished() * scale;
      sig += r.h64_inv.squaredNorm();
      err += (inv - r.h64_inv).squaredNorm();
      if (l == 0) {
        for (int k = 0; k < 4; ++k) {
          moment_err = std::max(
              moment_err,
              std::abs(m.moment_x[static_cast<std::size_t>(k)] / kQ16 - r.p_x(k / 2, k % 2)));
          moment_err = std::max(
              moment_err,
              std::abs(m.moment_y[static_cast<std::size_t>(k)] / kQ16 - r.p_y(k / 2, k % 2)));
        }
      }
      ++compared;
    }
    std::printf("  level %d: %d windows, inverse SNR %.1f dB, max moment error %.2e px\n", l,
                compared, snr_db(sig, err), moment_err);
    EXPECT_GT(compared, flow_grid_count(l) * 9 / 10);
    // Level > 0 templates come from the rounded fixed-point pyramid; the reference uses the
    // unrounded one, so its statistics differ by the pyramid rounding (~0.3 LSB on ~100 LSB
    // texture): ~50 dB. Level 0 uses identical integer input: only the inverse's rounding.
    EXPECT_GE(snr_db(sig, err), l == 0 ? 90.0 : 35.0) << "level " << l;
    if (l == 0) {
      EXPECT_LE(moment_err, 1e-3);
    }
  }
}

// Whole-frame flow against the reference on the same integer input: the fixed-point path
// samples at 1/32 px positions (and rounds its arithmetic), the reference samples at the exact
// position; both converge to within ~0.002 px RMS of each other (> 45 dB on a ~0.6 px field),
// max 0.03 px (1966 LSB of Q16). Validity decisions may differ for the few windows that
// sit exactly on a threshold (image border after a jump, residual ratio): <= 2 % of the grid.
TEST(BlockFlowReference, FlowAgreesWithDoubleReference) {
  struct Case {
    const char* name;
    Warp w;
  };
  const Case cases[] = {
      {"sub-pixel shift", Warp::shift(1.1, -0.7)},
      {"affine", Warp::affine(1.02, 0.015, -0.01, 0.985, 1.1, -0.7)},
      {"jump (6, 4) px", Warp::shift(12.0, 8.0)},
  };
  for (const Case& k : cases) {
    auto f = make_flow();
    dsp_ref::BlockFlowRef ref;
    f->tare(undeformed());
    ref.tare(undeformed());
    const WorkImage img = test::render_work_image(texture(), k.w);
    VectorField d;
    GridMask v;
    std::vector<double> rx, ry;
    std::vector<std::uint8_t> rv;
    f->track(img, d, v);
    ref.track(img, rx, ry, rv);
    double sig = 0, err = 0, max_err = 0;
    int both = 0, mismatch = 0;
    for (int i = 0; i < kGridCount; ++i) {
      const auto u = static_cast<std::size_t>(i);
      if (v.v[u] != rv[u]) ++mismatch;
      if (!v.v[u] || !rv[u]) continue;
      const double ex = d.x.v[u] / kQ16 - rx[u], ey = d.y.v[u] / kQ16 - ry[u];
      sig += rx[u] * rx[u] + ry[u] * ry[u];
      err += ex * ex + ey * ey;
      max_err = std::max(max_err, std::max(std::abs(ex), std::abs(ey)));
      ++both;
    }
    std::printf("  %-16s SNR %.1f dB, max %.4f px, both valid %d, validity mismatches %d\n", k.name,
                snr_db(sig, err), max_err, both, mismatch);
    EXPECT_GE(snr_db(sig, err), 45.0) << k.name;
    EXPECT_LE(max_err, 0.03) << k.name;
    EXPECT_LE(mismatch, kGridCount / 50) << k.name;
  }
}

// With the reference sampling on the fixed-point grid (1/32 px positions, same stopping rule),
// only the arithmetic differs: the floor-rounded vertical bilinear pass (<= 1/64 luma per
// sample), U8.7 residuals, the Q16 gain coupling and steps. Tighter agreement: >= 60 dB, max
// 0.01 px.
TEST(BlockFlowReference, FlowAgreesOnTheFixedPointSamplingGrid) {
  const Warp warps[] = {Warp::shift(1.1, -0.7), Warp::affine(1.02, 0.015, -0.01, 0.985, 1.1, -0.7)};
  for (const Warp& w : warps) {
    auto f = make_flow();
    dsp_ref::BlockFlowRef ref;
    ref.set_fixed_point_sampling(true);
    f->tare(undeformed());
    ref.tare(undeformed());
    const WorkImage img = test::render_work_image(texture(), w);
    VectorField d;
    GridMask v;
    std::vector<double> rx, ry;
    std::vector<std::uint8_t> rv;
    f->track(img, d, v);
    ref.track(img, rx, ry, rv);
    double sig = 0, err = 0, max_err = 0;
    for (int i = 0; i < kGridCount; ++i) {
      const auto u = static_cast<std::size_t>(i);
      if (!v.v[u] || !rv[u]) continue;
      const double ex = d.x.v[u] / kQ16 - rx[u], ey = d.y.v[u] / kQ16 - ry[u];
      sig += rx[u] * rx[u] + ry[u] * ry[u];
      err += ex * ex + ey * ey;
      max_err = std::max(max_err, std::max(std::abs(ex), std::abs(ey)));
    }
    std::printf("  fixed-point sampling grid: SNR %.1f dB, max %.5f px\n", snr_db(sig, err),
                max_err);
    EXPECT_GE(snr_db(sig, err), 60.0);
    EXPECT_LE(max_err, 0.01);
  }
}

// A sequence with keyframe switches: fixed point and reference take the same switches and end
// within the same bounds.
TEST(BlockFlowReference, KeyframeSequenceAgreesWithDoubleReference) {
  auto f = make_flow();
  dsp_ref::BlockFlowRef ref;
  f->tare(undeformed());
  ref.tare(undeformed());
  VectorField d;
  GridMask v;
  std::vector<double> rx, ry;
  std::vector<std::uint8_t> rv;
  constexpr int kFrames = 10;
  for (int k = 1; k <= kFrames; ++k) {
    const WorkImage img =
        test::render_work_image(texture(), growing_deformation(static_cast<double>(k) / kFrames));
    f->track(img, d, v);
    ref.track(img, rx, ry, rv);
  }
  EXPECT_EQ(static_cast<int>(f->keyframe_switches()), ref.keyframe_switches());
  EXPECT_GE(ref.keyframe_switches(), 3);
  double sig = 0, err = 0, max_err = 0;
  for (int i = 0; i < kGridCount; ++i) {
    const auto u = static_cast<std::size_t>(i);
    if (!v.v[u] || !rv[u]) continue;
    const double ex = d.x.v[u] / kQ16 - rx[u], ey = d.y.v[u] / kQ16 - ry[u];
    sig += rx[u] * rx[u] + ry[u] * ry[u];
    err += ex * ex + ey * ey;
    max_err = std::max(max_err, std::max(std::abs(ex), std::abs(ey)));
  }
  std::printf("  after %d frames, %d switches: SNR %.1f dB, max %.4f px\n", kFrames,
              ref.keyframe_switches(), snr_db(sig, err), max_err);
  EXPECT_GE(snr_db(sig, err), 45.0);
  EXPECT_LE(max_err, 0.03);
}

// The decision-locked reference (dsp_ref::FlowDecision, used only to report the
// "decision-locked" fixed−ref figure): it reports exactly the given valid set, holds the reported
// value of a point it is told was not tracked, tracks a point it is told was tracked even where
// its own window model fails a test, and switches keyframes exactly when told.
TEST(BlockFlowReference, FollowsTheGivenDecisions) {
  // Level 0 only (the motion per frame is within its range), so that the strict reference below
  // differs from the others in its level-0 window models alone, not in its coarse levels'.
  BlockFlowConfig cfg;
  cfg.pyramid_levels = 1;
  auto f = make_flow(cfg);
  dsp_ref::BlockFlowRef ref(cfg);     // told the fixed path's switches
  dsp_ref::BlockFlowRef frozen(cfg);  // told never to switch
  dsp_ref::BlockFlowRef eager(cfg);   // told to switch on every frame
  // Its own texture test rejects about a sixth of the windows; told the fixed path's valid set.
  BlockFlowConfig strict_cfg = cfg;
  strict_cfg.min_texture = 3.0;
  dsp_ref::BlockFlowRef strict(strict_cfg);
  for (auto* r : {&ref, &frozen, &eager, &strict}) r->tare(undeformed());
  f->tare(undeformed());
  VectorField d;
  GridMask v;
  std::vector<double> rx, ry, prev_x, prev_y, zx, zy, ex, ey, sx, sy;
  std::vector<std::uint8_t> rv, zv, ev, sv;
  constexpr int kFrames = 10;
  // A block of points the fixed path tracks but the reference is told it did not, from frame 4.
  const auto dropped = [](int gx, int gy) { return gx >= 18 && gx <= 20 && gy >= 13 && gy <= 15; };
  int fixed_switches = 0;
  int reanchored_points = 0;
  double strict_worst_rms = 0.0;
  int strict_overruled = 0;
  for (int k = 1; k <= kFrames; ++k) {
    const Warp w = growing_deformation(static_cast<double>(k) / kFrames);
    const WorkImage img = test::render_work_image(texture(), w);
    f->track(img, d, v);
    fixed_switches += f->last_frame_was_keyframe() ? 1 : 0;
    GridMask told = v;
    for (int gy = 0; gy < kGridHeight; ++gy) {
      for (int gx = 0; gx < kGridWidth; ++gx) {
        if (k >= 4 && dropped(gx, gy)) told(gx, gy) = 0;
      }
    }
    prev_x = rx;
    prev_y = ry;
    const dsp_ref::FlowDecision follow{&told, f->last_frame_was_keyframe(), &f->reanchored(),
                                       &f->lost()};
    ref.track(img, rx, ry, rv, &follow);
    if (f->last_frame_was_keyframe()) {
      // At a switch it re-anchors and loses exactly the fixed path's points. The frozen
      // reference below never switches, so its re-anchored set stays empty.
      int re = 0;
      for (int i = 0; i < kGridCount; ++i) {
        const auto u = static_cast<std::size_t>(i);
        ASSERT_EQ(ref.reanchored()[u], f->reanchored().v[u]) << "frame " << k << " point " << i;
        ASSERT_EQ(ref.lost()[u], f->lost().v[u]) << "frame " << k << " point " << i;
        re += f->reanchored().v[u];
      }
      reanchored_points += re;
    }
    const dsp_ref::FlowDecision never{&told, false};
    frozen.track(img, zx, zy, zv, &never);
    const dsp_ref::FlowDecision always{&told, true};
    eager.track(img, ex, ey, ev, &always);
    const dsp_ref::FlowDecision fixed_own{&v, f->last_frame_was_keyframe()};
    strict.track(img, sx, sy, sv, &fixed_own);
    for (int i = 0; i < kGridCount; ++i) {
      const auto u = static_cast<std::size_t>(i);
      ASSERT_EQ(rv[u], told.v[u]) << "frame " << k << " point " << i;
      ASSERT_EQ(zv[u], told.v[u]) << "frame " << k << " point " << i;
      ASSERT_EQ(ev[u], told.v[u]) << "frame " << k << " point " << i;
      ASSERT_EQ(sv[u], v.v[u]) << "frame " << k << " point " << i;
    }
    if (k >= 4) {
      // Held from frame 3 on: the reported value of the previous frame, exactly.
      for (int gy = 13; gy <= 15; ++gy) {
        for (int gx = 18; gx <= 20; ++gx) {
          const auto u = static_cast<std::size_t>(gy * kGridWidth + gx);
          ASSERT_EQ(rx[u], prev_x[u]) << "frame " << k;
          ASSERT_EQ(ry[u], prev_y[u]) << "frame " << k;
        }
      }
    }
    // The strict reference tracks the points whose model its own test rejected (held at their
    // tare value they would be off by the whole displacement, up to 7 px). Its estimates there
    // are its own, not the fixed path's, so they are looser than the fixed path's 0.06 px,
    // worst at the top border after a keyframe switch.
    double sum = 0.0;
    int n = 0;
    for (int gy = 0; gy < kGridHeight; ++gy) {
      for (int gx = 0; gx < kGridWidth; ++gx) {
        const auto u = static_cast<std::size_t>(gy * kGridWidth + gx);
        if (!v.v[u] || strict.window(0, static_cast<int>(u)).valid) continue;
        const Vec2 t = w.grid_displacement_work(gx, gy);
        sum += (sx[u] - t[0]) * (sx[u] - t[0]) + (sy[u] - t[1]) * (sy[u] - t[1]);
        ++n;
      }
    }
    strict_overruled = n;
    strict_worst_rms = std::max(strict_worst_rms, std::sqrt(sum / std::max(n, 1)));
  }
  std::printf(
      "  strict reference: %d of the fixed path's points overrule its own texture test, "
      "their worst rms %.4f px\n",
      strict_overruled, strict_worst_rms);
  EXPECT_GT(strict_overruled, kGridCount / 8);
  EXPECT_LE(strict_worst_rms, 0.25);
  EXPECT_GE(fixed_switches, 3);
  std::printf("  re-anchored at the fixed path's switches: %d points\n", reanchored_points);
  EXPECT_GT(reanchored_points, kGridCount / 2);
  EXPECT_EQ(std::count(frozen.reanchored().begin(), frozen.reanchored().end(), 1), 0);
  EXPECT_EQ(ref.keyframe_switches(), fixed_switches);
  EXPECT_EQ(frozen.keyframe_switches(), 0);
  EXPECT_EQ(eager.keyframe_switches(), kFrames);
  // Where both report a point, the values agree as in the free-running comparison above.
  double sig = 0, err = 0;
  int compared = 0;
  for (int i = 0; i < kGridCount; ++i) {
    const auto u = static_cast<std::size_t>(i);
    if (!rv[u]) continue;
    const double dx = d.x.v[u] / kQ16 - rx[u], dy = d.y.v[u] / kQ16 - ry[u];
    sig += rx[u] * rx[u] + ry[u] * ry[u];
    err += dx * dx + dy * dy;
    ++compared;
  }
  std::printf("  locked: %d points compared, SNR %.1f dB\n", compared, snr_db(sig, err));
  EXPECT_GT(compared, kGridCount / 2);
  EXPECT_GE(snr_db(sig, err), 45.0);
}

// A window on the image's edge that the fixed path tracked: the decision-locked reference tracks
// it too, although its own unrounded position leaves the image by less than the fixed path's
// 1/32 px sampling step (the free-running reference reports it outside, and a followed point
// that held its old value would drift from the fixed path's for as long as the shift lasts).
TEST(BlockFlowReference, FollowsATrackedWindowOnTheImageEdge) {
  BlockFlowConfig cfg;
  cfg.pyramid_levels = 1;
  int edge_cases = 0;
  double worst = 0.0;
  // About one working px towards the edge: the edge windows' origins are 1 px inside the image.
  for (const double shift : {-1.97, -1.98, -1.99, -2.0, -2.01, -2.02}) {  // sensor px
    auto f = make_flow(cfg);
    dsp_ref::BlockFlowRef own(cfg), locked(cfg);
    f->tare(undeformed());
    own.tare(undeformed());
    locked.tare(undeformed());
    const WorkImage img = test::render_work_image(texture(), Warp::shift(shift, shift));
    VectorField d;
    GridMask v;
    std::vector<double> ox, oy, lx, ly;
    std::vector<std::uint8_t> ov, lv;
    f->track(img, d, v);
    own.track(img, ox, oy, ov);
    const dsp_ref::FlowDecision follow{&v, false};
    locked.track(img, lx, ly, lv, &follow);
    for (int i = 0; i < kGridCount; ++i) {
      const auto u = static_cast<std::size_t>(i);
      const dsp_ref::WindowRef& m = own.window(0, i);
      if (!v.v[u] || ov[u] || (m.ox != 1 && m.oy != 1)) continue;
      ++edge_cases;  // tracked by the fixed path, outside for the free-running reference
      ASSERT_TRUE(lv[u]);
      worst =
          std::max({worst, std::abs(d.x.v[u] / kQ16 - lx[u]), std::abs(d.y.v[u] / kQ16 - ly[u])});
    }
  }
  std::printf(
      "  edge windows tracked by the fixed path only: %d, locked reference within %.4f px\n",
      edge_cases, worst);
  EXPECT_GT(edge_cases, 0);
  EXPECT_LE(worst, 1.0 / 32);
}

// The decision-locked reference places its level-0 windows at the fixed path's origins: here
// origins moved by one pixel against its own rounding. The material point is the same, so the
// window's offset takes up the move and the displacement still matches the fixed path's. Origins
// that were never built (0: windows sit 1 px inside the image) are ignored.
TEST(BlockFlowReference, FollowsTheFixedPathsWindowOrigins) {
  BlockFlowConfig cfg;
  cfg.pyramid_levels = 1;
  auto f = make_flow(cfg);
  dsp_ref::BlockFlowRef ref(cfg), unbuilt(cfg);
  f->tare(undeformed());
  ref.tare(undeformed());
  unbuilt.tare(undeformed());
  const WorkImage img = test::render_work_image(texture(), Warp::shift(0.8, -0.6));
  VectorField d;
  GridMask v;
  f->track(img, d, v);
  BlockFlow::WindowOrigins ox = f->window_origin_x(), oy = f->window_origin_y();
  std::vector<int> moved;
  for (int i = 0; i < kGridCount; ++i) {
    const auto u = static_cast<std::size_t>(i);
    const int gx = i % kGridWidth, gy = i / kGridWidth;
    if (gx < 2 || gy < 2 || gx > kGridWidth - 3 || gy > kGridHeight - 3 || (gx + gy) % 7 != 0)
      continue;
    ox[u] = static_cast<std::int16_t>(ox[u] + 1);
    oy[u] = static_cast<std::int16_t>(oy[u] - 1);
    moved.push_back(i);
  }
  dsp_ref::FlowDecision follow{&v, false};
  follow.origin_x = &ox;
  follow.origin_y = &oy;
  std::vector<double> rx, ry, ux, uy;
  std::vector<std::uint8_t> rv, uv;
  ref.track(img, rx, ry, rv, &follow);
  const BlockFlow::WindowOrigins zero{};
  dsp_ref::FlowDecision none{&v, false};
  none.origin_x = &zero;
  none.origin_y = &zero;
  unbuilt.track(img, ux, uy, uv, &none);
  double worst = 0.0;
  int compared = 0;
  for (int i = 0; i < kGridCount; ++i) {
    const auto u = static_cast<std::size_t>(i);
    ASSERT_EQ(ref.window(0, i).ox, ox[u]) << i;
    ASSERT_EQ(ref.window(0, i).oy, oy[u]) << i;
    ASSERT_EQ(unbuilt.window(0, i).ox, f->window_origin_x()[u]) << i;
    ASSERT_EQ(unbuilt.window(0, i).oy, f->window_origin_y()[u]) << i;
    if (!v.v[u] || !ref.window(0, i).valid) continue;
    worst = std::max({worst, std::abs(d.x.v[u] / kQ16 - rx[u]), std::abs(d.y.v[u] / kQ16 - ry[u])});
    ++compared;
  }
  std::printf("  %zu windows moved by a pixel; %d points within %.4f px of the fixed path\n",
              moved.size(), compared, worst);
  EXPECT_GT(moved.size(), 50u);
  EXPECT_GT(compared, kGridCount / 2);
  EXPECT_LE(worst, 0.05);
}

}  // namespace
}  // namespace tacse3::dsp
