// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: no heap allocation per frame in the sim camera and the stream writer's push().
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <vector>

#include "alloc/alloc_hooks.hpp"
#include "tacse3/hal/camera/sim_camera.hpp"
#if TACSE3_TEST_HAS_RECORDING
#include <unistd.h>

#include <filesystem>

#include "tacse3/recording/stream_writer.hpp"
#endif
#if TACSE3_TEST_HAS_REPLAY
#include "tacse3/hal/camera/replay_camera.hpp"
#endif

namespace {

using tacse3::test::allocation_count;
using tacse3::test::reset_allocation_count;
namespace hal = tacse3::hal;
namespace sim = tacse3::sim;

// The hook itself counts (so a zero below means something).
TEST(NoAlloc, HookCounts) {
  reset_allocation_count();
  auto p = std::make_unique<std::vector<int>>(16);
  void* m = std::malloc(32);
  std::free(m);
  EXPECT_GE(allocation_count(), 3u);
}

void count_frames(bool realtime, tacse3::dsp::PixelFormat format) {
  hal::SimRigConfig rc;
  rc.scene.realtime = realtime;
  std::string err;
  auto rig = hal::SimRig::create(rc, &err);
  ASSERT_TRUE(rig) << err;
  hal::SimCameraConfig cc;
  cc.sensor = sim::Sensor::kRight;
  cc.format = format;
  auto cam = rig->make_camera(cc);
  ASSERT_TRUE(cam->open().ok());
  ASSERT_TRUE(cam->start().ok());
  hal::Frame f;
  ASSERT_TRUE(cam->next_frame(f, 1000).ok());
  cam->release(f);
  // The measured loop covers delivery, the buffer-full path, a drop and a stall.
  reset_allocation_count();
  int ok = 0;
  for (int i = 0; i < 12; ++i) {
    if (i == 4) cam->drop_frames(2);
    if (i == 8) cam->stall_for_ms(5);
    hal::Frame a, b;
    if (cam->next_frame(a, 1000).ok()) ++ok;
    if (cam->next_frame(b, 1000).ok()) ++ok;
    cam->release(a);
    cam->release(b);
    (void)cam->stats();
  }
  const std::uint64_t n = allocation_count();
  EXPECT_EQ(ok, 24);
  EXPECT_EQ(n, 0u) << "heap allocations in next_frame()/release()";
  cam->stop();
}

TEST(NoAlloc, SimCameraFastMode) {
  count_frames(false, tacse3::dsp::PixelFormat::kRgb888);
}
TEST(NoAlloc, SimCameraRealtime) {
  count_frames(true, tacse3::dsp::PixelFormat::kGrey);
}

#if TACSE3_TEST_HAS_RECORDING
namespace rec = tacse3::recording;

// Accepts every frame without allocating, so the writer thread adds nothing to the count.
class NullSink final : public rec::FrameSink {
 public:
  rec::Status write_frame(std::int64_t, std::span<const rec::ImageView>) override { return {}; }
  rec::Status finish() override { return {}; }
};

TEST(NoAlloc, StreamWriterPush) {
  rec::StreamWriterOptions o;
  o.channels = 3;
  o.ring_frames = 4;
  auto started = rec::StreamWriter::start(std::make_unique<NullSink>(), o);
  ASSERT_TRUE(started) << started.status().message();
  auto& w = *started.value();
  std::vector<std::uint8_t> img(320u * 240u * 3u, 7);
  const rec::StreamImage imgs[2] = {{img.data(), 320, 240, 3, 0}, {img.data(), 320, 240, 3, 0}};
  reset_allocation_count();
  int accepted = 0;
  // Faster than the writer can drain now and then: the full-ring path is covered as well.
  for (int i = 0; i < 200; ++i) accepted += w.push(1000 + i, imgs) ? 1 : 0;
  const std::uint64_t n = allocation_count();
  EXPECT_GT(accepted, 0);
  EXPECT_EQ(n, 0u) << "heap allocations in push()";
  ASSERT_TRUE(w.close().ok());
  EXPECT_EQ(w.stats().pushed + w.stats().dropped_full, 200u);
}
#endif

#if TACSE3_TEST_HAS_REPLAY
// Full-size RGB frames from the sim camera, recorded, then replayed: no heap per frame, neither
// in this executable's code nor inside libspng/zlib (their allocations go to the arena).
TEST(NoAlloc, ReplayCamera) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("tacse3-noalloc-replay-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  {
    hal::SimRigConfig rc;
    rc.scene.realtime = false;
    std::string err;
    auto rig = hal::SimRig::create(rc, &err);
    ASSERT_TRUE(rig) << err;
    auto cam = rig->make_camera({});
    ASSERT_TRUE(cam->open().ok());
    ASSERT_TRUE(cam->start().ok());
    rec::RecordingInfo info;
    info.sensors = {rec::SensorId::kLeft};
    auto w = rec::RecordingWriter::open(dir, info);
    ASSERT_TRUE(w) << w.status().message();
    for (int i = 0; i < 8; ++i) {
      hal::Frame f;
      ASSERT_TRUE(cam->next_frame(f, 1000).ok());
      const rec::ImageView v{f.view.data, 320, 240, 3};
      ASSERT_TRUE(
          w.value()->write_frame(f.timestamp_ns, std::span<const rec::ImageView>(&v, 1)).ok());
      cam->release(f);
    }
    ASSERT_TRUE(w.value()->finish().ok());
  }
  hal::ReplayCameraConfig c;
  c.dir = dir.string();
  c.realtime = false;
  c.loop = true;
  auto cam = hal::make_replay_camera(c);
  ASSERT_TRUE(cam->open().ok());
  ASSERT_TRUE(cam->start().ok());
  hal::Frame f;
  ASSERT_TRUE(cam->next_frame(f, 1000).ok());
  cam->release(f);
  reset_allocation_count();
  int ok = 0;
  for (int i = 0; i < 20; ++i) {  // through the loop's wrap-around as well
    if (cam->next_frame(f, 1000).ok()) ++ok;
    cam->release(f);
  }
  const std::uint64_t n = allocation_count();
  EXPECT_EQ(ok, 20);
  EXPECT_EQ(n, 0u) << "heap allocations in the replay camera's next_frame()";
  const auto d = hal::replay_decode_stats(*cam);
  EXPECT_EQ(d.heap_fallbacks, 0u);
  EXPECT_GT(d.arena_allocations, 0u);
  std::printf("replay 320x240 RGB: %llu decodes, %llu arena allocations, peak %zu bytes\n",
              static_cast<unsigned long long>(d.decodes),
              static_cast<unsigned long long>(d.arena_allocations), d.arena_peak_bytes);
  cam->stop();
  fs::remove_all(dir);
}
#endif

}  // namespace
