// SPDX-License-Identifier: Apache-2.0
// firmware tests: a pad's hand-off of tare, calibration and the viewer's fields (PadStager),
// against a SensorPipeline driven by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "tacse3/firmware/pad_stager.hpp"

using namespace tacse3;
using namespace tacse3::firmware;

namespace {

std::int64_t zero_clock() noexcept {
  return 0;
}

// A textured grey frame whose middle is pushed `shift` pixels right (a shear of the gel).
std::vector<std::uint8_t> textured(int shift) {
  std::vector<std::uint8_t> img(320 * 240);
  for (int y = 0; y < 240; ++y) {
    for (int x = 0; x < 320; ++x) {
      const bool inside = x > 80 && x < 240 && y > 60 && y < 180;
      const double u = x - (inside ? shift : 0);
      const double v = 128.0 + 50.0 * std::sin(u * 0.31) * std::cos(y * 0.23) +
                       30.0 * std::sin(u * 0.07 + y * 0.11);
      img[static_cast<std::size_t>(y * 320 + x)] = static_cast<std::uint8_t>(std::lround(v));
    }
  }
  return img;
}

ArrivedFrame arrived(const std::vector<std::uint8_t>& img, std::int64_t t_ns) {
  ArrivedFrame a;
  a.frame.view = {img.data(), img.size(), 320, 240, 0, dsp::PixelFormat::kGrey};
  a.frame.timestamp_ns = t_ns;
  return a;
}

class PadStagerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int i = 0; i < 6; ++i) frames_.push_back(textured(i));
    ASSERT_EQ(pad_->configure(dsp::PipelineConfig{}, cal_), dsp::Status::kOk);
    ASSERT_EQ(ref_->configure(dsp::PipelineConfig{}, cal_), dsp::Status::kOk);
  }
  // Stages frame i on the stager and on the reference, each followed by its deferred work (as a
  // pad's thread runs it once the frame is handed on); true when their outputs are equal.
  bool stage_both(std::size_t i, bool deferred = true) {
    stager_.stage(arrived(frames_[i], 1000 + static_cast<std::int64_t>(i)), *out_);
    if (deferred) stager_.run_deferred();
    ref_->process_image(arrived(frames_[i], 0).frame.view, *want_);
    ref_->run_deferred();
    return out_->staged && out_->stages.shear.x.v == want_->shear.x.v &&
           out_->stages.shear.y.v == want_->shear.y.v &&
           out_->stages.contact.mask.v == want_->contact.mask.v;
  }

  dsp::Calibration cal_{};
  std::vector<std::vector<std::uint8_t>> frames_;
  std::unique_ptr<dsp::SensorPipeline> pad_ = std::make_unique<dsp::SensorPipeline>();
  std::unique_ptr<dsp::SensorPipeline> ref_ = std::make_unique<dsp::SensorPipeline>();
  PadStager stager_{*pad_, &zero_clock};
  std::unique_ptr<StagedFrame> out_ = std::make_unique<StagedFrame>();
  std::unique_ptr<dsp::PadStages> want_ = std::make_unique<dsp::PadStages>();
};

}  // namespace

TEST_F(PadStagerTest, StagesLikeTheSensorPipelineAndSkipsALateFrame) {
  for (std::size_t i = 0; i < 3; ++i) ASSERT_TRUE(stage_both(i)) << i;
  // Frames not newer than the last sample are late: no stages, the image state untouched.
  const auto work = pad_->fields().work.px;
  stager_.set_last_sample(1000 + 3);
  stager_.stage(arrived(frames_[3], 1000 + 3), *out_);
  EXPECT_FALSE(out_->staged);
  EXPECT_TRUE(pad_->fields().work.px == work);
  EXPECT_TRUE(stage_both(4));
}

// The frame whose stages take the request still runs on the old reference and becomes the new
// one once handed on; the frames staged after it carry the new epoch. A request made while a
// frame's stages run waits for the next frame.
TEST_F(PadStagerTest, ATareTakesTheNextFrameAsReferenceAndStampsTheFramesAfter) {
  ASSERT_TRUE(stage_both(0));
  ASSERT_TRUE(stage_both(1));
  EXPECT_EQ(out_->tare_epoch, 0u);
  EXPECT_EQ(stager_.request_tare(), 1u);
  ASSERT_TRUE(stage_both(2));
  EXPECT_EQ(out_->tare_epoch, 0u) << "frame 2 ran on the old reference";
  ref_->tare_image();  // the reference becomes frame 2
  ASSERT_TRUE(stage_both(3));
  EXPECT_EQ(out_->tare_epoch, 1u);
  ASSERT_TRUE(stage_both(4, false));
  EXPECT_EQ(out_->tare_epoch, 1u) << "applied once";
  EXPECT_EQ(stager_.request_tare(), 2u);  // during frame 4, after its stages took the requests
  stager_.run_deferred();
  ASSERT_TRUE(stage_both(5));
  EXPECT_EQ(out_->tare_epoch, 1u) << "frame 5 took the request";
  ref_->tare_image();  // the reference becomes frame 5
  ASSERT_TRUE(stage_both(0));
  EXPECT_EQ(out_->tare_epoch, 2u);
}

TEST_F(PadStagerTest, AnUntakenCalibrationIsReplacedATakenOneWaitsForItsMotionHalf) {
  dsp::Calibration first = cal_, second = cal_;
  first.shear_gain_d = 1.5;
  second.shear_gain_d = 2.0;
  ASSERT_TRUE(stage_both(0));
  ASSERT_TRUE(stage_both(1));
  const std::uint32_t e1 = stager_.request_calibration(first, true);
  const std::uint32_t e2 = stager_.request_calibration(second, false);  // not taken: replaced
  EXPECT_EQ(e1, 1u);
  EXPECT_EQ(e2, 2u);
  ASSERT_EQ(ref_->set_image_calibration(second), dsp::Status::kOk);
  ASSERT_TRUE(stage_both(2)) << "the frame runs on the second calibration";
  EXPECT_EQ(out_->calibration_epoch, 2u);
  // Taken: a further request waits until the DSP thread has seen a frame of epoch 2.
  EXPECT_EQ(stager_.request_calibration(first, false), 0u);
  ASSERT_TRUE(stage_both(3));
  EXPECT_EQ(stager_.request_calibration(first, true), 3u);
  ASSERT_EQ(ref_->set_image_calibration(first), dsp::Status::kOk);
  ASSERT_TRUE(stage_both(4));
  EXPECT_EQ(out_->calibration_epoch, 3u);
  // The shear differs between the calibrations: the comparisons above could fail.
  ASSERT_EQ(ref_->set_image_calibration(second), dsp::Status::kOk);
  EXPECT_FALSE(stage_both(5));
}

TEST_F(PadStagerTest, TheViewersFieldsComeFromTheFirstFrameAfterTheyAreAsked) {
  viewer::ViewPad view;
  auto copy = std::make_unique<viewer::ViewPad>();  // the pad's copy (Engine::set_view's)
  int cells = -1;
  ASSERT_TRUE(stage_both(0));
  EXPECT_FALSE(stager_.take_view_fields(&view, &cells)) << "no buffer (no viewer): no copy";
  stager_.set_view_buffer(copy.get());
  ASSERT_TRUE(stage_both(1));  // asked for from the start
  ASSERT_TRUE(stager_.take_view_fields(&view, &cells));
  EXPECT_EQ(cells, ref_->fields().contact.count);
  EXPECT_EQ(view.luma[0], static_cast<std::uint8_t>(ref_->fields().work.px[0] >> 2));
  EXPECT_FALSE(stager_.take_view_fields(&view, &cells)) << "taken once";
  ASSERT_TRUE(stage_both(2));
  EXPECT_FALSE(stager_.take_view_fields(&view, &cells)) << "not asked again";
  stager_.want_view_fields();
  ASSERT_TRUE(stage_both(3));
  ASSERT_TRUE(stager_.take_view_fields(&view, &cells));
  for (std::size_t i = 0; i < view.shear_x.size(); ++i) {
    ASSERT_EQ(view.shear_x[i], static_cast<float>(ref_->fields().shear.x.v[i]) /
                                   static_cast<float>(1 << dsp::kFieldFrac))
        << i;
  }
}
