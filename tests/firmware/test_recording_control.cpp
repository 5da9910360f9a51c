// SPDX-License-Identifier: Apache-2.0
// firmware tests: START/STOP_RECORDING's pieces: the DSP thread <-> housekeeping handoff
// (RecordingMailbox) and the disk side (start_numbered_recording): its NACK reasons and the
// rig block it writes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "tacse3/firmware/recording_mailbox.hpp"
#if TACSE3_HAVE_RECORDER
#include "tacse3/firmware/recorder.hpp"
#include "tacse3/recording/recording.hpp"
#endif

namespace fs = std::filesystem;
using namespace tacse3;
using namespace tacse3::firmware;
using protocol::AckCode;

namespace {

FrameRecorder* fake(std::uintptr_t n) {
  return reinterpret_cast<FrameRecorder*>(n * 64);  // only compared, never used
}

}  // namespace

TEST(RecordingMailbox, OneStartInFlightAnsweredOnce) {
  RecordingMailbox box;
  RecordingMailbox::StartRequest req;
  EXPECT_FALSE(box.pending_start(&req));
  ASSERT_TRUE(box.request_start({7, 0.0625}));
  EXPECT_TRUE(box.start_in_flight());
  EXPECT_FALSE(box.request_start({8, 0.05})) << "a second start while one is in flight";
  FrameRecorder* got = nullptr;
  AckCode code = AckCode::kBusy;
  EXPECT_FALSE(box.poll_start(&got, &code)) << "not answered yet";
  ASSERT_TRUE(box.pending_start(&req));
  EXPECT_EQ(req.number, 7);
  EXPECT_DOUBLE_EQ(req.finger_separation_m, 0.0625);
  box.answer_start(fake(1), AckCode::kAck);
  EXPECT_FALSE(box.pending_start(&req)) << "answered: housekeeping must not start it twice";
  ASSERT_TRUE(box.poll_start(&got, &code));
  EXPECT_EQ(got, fake(1));
  EXPECT_EQ(code, AckCode::kAck);
  EXPECT_FALSE(box.start_in_flight());
  EXPECT_FALSE(box.poll_start(&got, &code)) << "an answer is taken once";
}

TEST(RecordingMailbox, OneCloseInFlight) {
  RecordingMailbox box;
  EXPECT_EQ(box.take_close(), nullptr);
  ASSERT_TRUE(box.request_close(fake(1)));
  EXPECT_FALSE(box.request_close(fake(2))) << "the first one is not taken yet";
  EXPECT_EQ(box.take_close(), fake(1));
  EXPECT_EQ(box.take_close(), nullptr);
  EXPECT_TRUE(box.request_close(fake(2)));
}

// The request's fields reach the other thread whole (release/acquire on the state).
TEST(RecordingMailbox, HandsRequestsAcrossThreads) {
  RecordingMailbox box;
  std::thread housekeeping([&] {
    for (int n = 0; n < 200; ++n) {
      RecordingMailbox::StartRequest req;
      while (!box.pending_start(&req)) std::this_thread::yield();
      EXPECT_EQ(req.finger_separation_m, req.number * 0.001);
      box.answer_start(fake(req.number + 1u), AckCode::kAck);
    }
  });
  for (std::uint16_t n = 0; n < 200; ++n) {
    ASSERT_TRUE(box.request_start({n, n * 0.001}));
    FrameRecorder* got = nullptr;
    AckCode code = AckCode::kBusy;
    while (!box.poll_start(&got, &code)) std::this_thread::yield();
    EXPECT_EQ(got, fake(n + 1u));
  }
  housekeeping.join();
}

#if TACSE3_HAVE_RECORDER
class NumberedRecording : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("tacse3-fw-reccmd-" + std::to_string(getpid()));
    fs::create_directories(root_);
    config_.sensors = {true, false};
    config_.width = 32;
    config_.height = 24;
    config_.pixel_pitch_mm = 0.075;
    config_.finger_separation_mm = 62.5;
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path root_;
  RecorderConfig config_;
};

TEST_F(NumberedRecording, NackReasons) {
  std::unique_ptr<FrameRecorder> r;
  std::string m;
  EXPECT_EQ(start_numbered_recording("", 1, config_, &r, &m), AckCode::kNoRecordDir);
  EXPECT_NE(m.find("no [record] dir"), std::string::npos) << m;
  EXPECT_EQ(start_numbered_recording((root_ / "missing").string(), 1, config_, &r, &m),
            AckCode::kDiskError);
  EXPECT_NE(m.find("is not a directory"), std::string::npos) << m;
  fs::create_directories(root_ / "rec-00003");
  EXPECT_EQ(start_numbered_recording(root_.string(), 3, config_, &r, &m),
            AckCode::kRecordingExists);
  EXPECT_NE(m.find("rec-00003 exists"), std::string::npos) << m;
  std::ofstream(root_ / "rec-00004") << "a file, not a recording\n";
  EXPECT_EQ(start_numbered_recording(root_.string(), 4, config_, &r, &m),
            AckCode::kRecordingExists);
  EXPECT_EQ(r, nullptr);
  EXPECT_EQ(numbered_recording_dir("/r", 65535), fs::path("/r/rec-65535"));
}

TEST_F(NumberedRecording, WritesTheRigItIsGiven) {
  std::unique_ptr<FrameRecorder> r;
  std::string m;
  ASSERT_EQ(start_numbered_recording(root_.string(), 12, config_, &r, &m), AckCode::kAck) << m;
  ASSERT_NE(r, nullptr);
  std::vector<std::uint8_t> pixels(32 * 24, 100);
  dsp::FrameView v;
  v.data = pixels.data();
  v.size_bytes = pixels.size();
  v.width = 32;
  v.height = 24;
  v.stride_bytes = 32;
  v.format = dsp::PixelFormat::kGrey;
  for (int i = 0; i < 3; ++i) r->record(1'000'000'000LL + i * 8'333'333LL, &v, nullptr);
  EXPECT_EQ(r->close(), "");
  auto rd = recording::RecordingReader::open(root_ / "rec-00012");
  ASSERT_TRUE(rd.ok()) << rd.status().message();
  EXPECT_EQ(rd.value().frame_count(), 3u);
  EXPECT_DOUBLE_EQ(rd.value().info().rig.finger_separation_mm, 62.5);
  EXPECT_DOUBLE_EQ(rd.value().info().rig.pixel_pitch_mm, 0.075);
}
#endif
