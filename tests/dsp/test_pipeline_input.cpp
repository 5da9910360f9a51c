// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: bad input to the pipeline — wrong sizes, empty/saturated frames, bad calibration.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "support/scenes.hpp"
#include "tacse3/dsp/pipeline.hpp"

namespace tacse3::dsp {
namespace {

class PipelineInput : public ::testing::Test {
 protected:
  void SetUp() override {
    pipeline = std::make_unique<DualPipeline>();
    scene.motion << 0, 0, 0.05, 0, 0, 0;
    scene.grasp_frames = 4;
    scene.motion_frames = 6;
    scene.hold_frames = 0;
    const test::DotTexture lt(3), rt(4);
    for (int f = 0; f < test::scene_frames(scene); ++f) {
      frames[0].push_back(test::render_scene_frame(scene, lt, 0, f));
      frames[1].push_back(test::render_scene_frame(scene, rt, 1, f));
    }
  }
  DualResult step(int f, const FrameView* override_right = nullptr) {
    const FrameView l =
        test::frame_view(frames[0][static_cast<std::size_t>(f)], PixelFormat::kRgb888);
    const FrameView r =
        test::frame_view(frames[1][static_cast<std::size_t>(f)], PixelFormat::kRgb888);
    DualResult out;
    pipeline->process(&l, override_right ? override_right : &r, t_ns, out);
    t_ns += 8'333'333;
    return out;
  }
  std::unique_ptr<DualPipeline> pipeline;
  test::GraspScene scene;
  std::vector<std::vector<std::uint8_t>> frames[2];
  std::int64_t t_ns = 0;
};

TEST_F(PipelineInput, WrongFrameSizeIsAClearErrorAndChangesNothing) {
  for (int f = 0; f < 6; ++f) step(f);
  const Pose before = pipeline->pose();
  std::vector<std::uint8_t> small(160 * 120 * 3, 128);
  FrameView bad{small.data(), small.size(), 160, 120, 0, PixelFormat::kRgb888};
  const DualResult r = step(6, &bad);
  EXPECT_EQ(r.sensors[1].status, Status::kBadFrameSize);
  EXPECT_FALSE(r.sensors[1].processed);
  EXPECT_TRUE(r.sensors[0].processed);
  EXPECT_TRUE(r.single_sensor || !r.fused.contact[1]);
  // A truncated buffer of the right nominal size is rejected too.
  FrameView truncated{frames[1][0].data(), frames[1][0].size() - 1, 320, 240, 0,
                      PixelFormat::kRgb888};
  EXPECT_EQ(step(7, &truncated).sensors[1].status, Status::kBadFrameSize);
  FrameView null_data{nullptr, 0, 320, 240, 0, PixelFormat::kRgb888};
  EXPECT_EQ(step(8, &null_data).sensors[1].status, Status::kNullFrame);
  FrameView bad_format{frames[1][0].data(),        frames[1][0].size(), 320, 240, 0,
                       static_cast<PixelFormat>(9)};
  EXPECT_EQ(step(9, &bad_format).sensors[1].status, Status::kBadPixelFormat);
  EXPECT_TRUE(pipeline->pose().q.coeffs().allFinite());
  (void)before;
}

TEST_F(PipelineInput, EmptyAndSaturatedFramesAreFlaggedAndStateSurvives) {
  for (int f = 0; f < 6; ++f) step(f);
  for (std::uint8_t level : {std::uint8_t{0}, std::uint8_t{255}}) {
    const auto flat = test::constant_frame(level, PixelFormat::kRgb888);
    const FrameView v = test::frame_view(flat, PixelFormat::kRgb888);
    const DualResult r = step(6, &v);
    EXPECT_EQ(r.sensors[1].status, Status::kOk);
    EXPECT_TRUE(r.sensors[1].processed);
    EXPECT_TRUE(r.sensors[1].degraded) << "a flat frame has no texture to track";
    EXPECT_TRUE(r.twist.allFinite());
    EXPECT_TRUE(r.pose.q.coeffs().allFinite());
  }
  // The reference survived: the next real frame is tracked again on both sensors.
  const DualResult r = step(7);
  EXPECT_FALSE(r.sensors[1].degraded);
  EXPECT_GT(r.sensors[1].tracked_points, kGridCount / 2);
}

TEST_F(PipelineInput, NanCalibrationIsRejectedAndTheOldOneKept) {
  for (int f = 0; f < 4; ++f) step(f);
  std::array<Calibration, 2> cal{};
  cal[0].c_velocity = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(pipeline->set_calibration(cal), Status::kBadCalibration);
  cal[0] = Calibration{};
  cal[1].contact_tau_on = -1.0;
  EXPECT_EQ(pipeline->set_calibration(cal), Status::kBadCalibration);
  DualConfig cfg;
  cfg.finger_separation_m = std::numeric_limits<double>::infinity();
  EXPECT_EQ(pipeline->configure(cfg, {Calibration{}, Calibration{}}), Status::kBadArgument);
  EXPECT_EQ(pipeline->set_finger_separation(-0.01), Status::kBadArgument);
  // Still running on the previous configuration, producing finite output.
  for (int f = 4; f < 10; ++f) {
    const DualResult r = step(f);
    EXPECT_TRUE(r.sensors[0].processed);
    EXPECT_TRUE(r.twist.allFinite());
  }
  EXPECT_EQ(pipeline->config().finger_separation_m, DualConfig{}.finger_separation_m);
}

TEST_F(PipelineInput, MissingSensorGivesFlaggedSingleSensorOutput) {
  for (int f = 0; f < 6; ++f) step(f);
  const FrameView l = test::frame_view(frames[0][6], PixelFormat::kRgb888);
  DualResult r;
  pipeline->process(&l, nullptr, t_ns, r);
  EXPECT_FALSE(r.present[1]);
  EXPECT_TRUE(r.sensors[0].processed);
  if (r.fused.rotation_sensors != 0 || r.fused.translation_sensors != 0) {
    EXPECT_TRUE(r.single_sensor);
  }
}

}  // namespace
}  // namespace tacse3::dsp
