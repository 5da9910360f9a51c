// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: the full dual-sensor pipeline makes zero heap allocations after initialisation.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <memory>

#include "alloc/alloc_hooks.hpp"
#include "support/scenes.hpp"
#include "tacse3/dsp/pipeline.hpp"

namespace tacse3::dsp {
namespace {

TEST(ZeroAllocation, ThousandDualFramesAfterInit) {
  // A grasp with a rotation about z, rendered once; the loop replays its frames back and forth so
  // the pipeline sees contact onset, motion, keyframe switches, loss of contact and re-grasp.
  test::GraspScene scene;
  scene.motion << 0.02, -0.01, 0.05, 0.0, 0.2e-3, 0.0;
  scene.grasp_frames = 4;
  scene.motion_frames = 8;
  scene.hold_frames = 4;
  const test::DotTexture left_tex(11), right_tex(12);
  std::vector<std::vector<std::uint8_t>> frames[2];
  for (int f = 0; f < test::scene_frames(scene); ++f) {
    frames[0].push_back(test::render_scene_frame(scene, left_tex, 0, f));
    frames[1].push_back(test::render_scene_frame(scene, right_tex, 1, f));
  }
  const auto dark = test::constant_frame(0, PixelFormat::kRgb888);
  const auto yuyv = test::constant_frame(200, PixelFormat::kYuyv);

  auto pipeline = std::make_unique<DualPipeline>();
  DualConfig cfg;
  std::array<Calibration, 2> cal{};
  cal[1].velocity_proxy = VelocityProxy::kDisplacement;
  ASSERT_EQ(pipeline->configure(cfg, cal), Status::kOk);
  DualResult result;

  // Everything below must run from the object's own storage.
  test::reset_allocation_count();
  Eigen::internal::set_is_malloc_allowed(false);
  const int n = static_cast<int>(frames[0].size());
  int processed = 0;
  for (int i = 0; i < 1000; ++i) {
    const int cycle = i % (2 * n);
    const int f = cycle < n ? cycle : 2 * n - 1 - cycle;  // forwards, then backwards
    const FrameView l =
        test::frame_view(frames[0][static_cast<std::size_t>(f)], PixelFormat::kRgb888);
    FrameView r = test::frame_view(frames[1][static_cast<std::size_t>(f)], PixelFormat::kRgb888);
    if (i % 97 == 50) r = test::frame_view(dark, PixelFormat::kRgb888);  // dark frame
    if (i % 131 == 70) r = test::frame_view(yuyv, PixelFormat::kYuyv);   // format change
    const bool drop_right = i % 173 == 100;                              // missed cycle
    pipeline->process(&l, drop_right ? nullptr : &r, std::int64_t{i} * 8'333'333, result);
    if (i == 400) pipeline->tare();
    if (i == 600) pipeline->reset_pose();
    if (i == 700) (void)pipeline->set_fusion_method(FusionMethod::kPaper);
    if (i == 800) (void)pipeline->set_finger_separation(0.05);
    processed += result.sensors[0].processed ? 1 : 0;
  }
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(test::allocation_count(), 0u);
  EXPECT_EQ(processed, 1000);
  EXPECT_TRUE(result.pose.q.coeffs().allFinite());
}

TEST(ZeroAllocation, CounterSeesAllocations) {
  // The hook itself must count, or the test above could pass vacuously.
  test::reset_allocation_count();
  auto p = std::make_unique<int>(3);
  void* m = std::malloc(16);
  std::free(m);
  EXPECT_GE(test::allocation_count(), 2u);
  EXPECT_EQ(*p, 3);
}

}  // namespace
}  // namespace tacse3::dsp
