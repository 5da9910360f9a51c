// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: the replay camera backend: pixels and times, pacing, loop, end, bad recordings.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "tacse3/hal/camera/clock.hpp"
#include "tacse3/hal/camera/replay_camera.hpp"
#include "tacse3/recording/recording.hpp"

namespace {

namespace fs = std::filesystem;
namespace rec = tacse3::recording;
using tacse3::hal::CameraError;
using tacse3::hal::Frame;
using tacse3::hal::LinkState;
using tacse3::hal::make_replay_camera;
using tacse3::hal::monotonic_ns;
using tacse3::hal::ReplayCameraConfig;

constexpr int kW = 64;
constexpr int kH = 48;
constexpr int kFrames = 20;
constexpr std::int64_t kT0 = 123'000'000'000;

// Frame times 20 ms apart with a little jitter, as a real capture has.
std::int64_t frame_time(int i) {
  return kT0 + i * 20'000'000LL + (i % 2) * 150'000;
}

std::vector<std::uint8_t> image(int frame, int sensor, int channels) {
  std::vector<std::uint8_t> v(static_cast<std::size_t>(kW * kH * channels));
  for (std::size_t j = 0; j < v.size(); ++j) {
    v[j] = static_cast<std::uint8_t>(
        (j * 5 + static_cast<std::size_t>(frame) * 17 + static_cast<std::size_t>(sensor) * 90) &
        0xFF);
  }
  return v;
}

fs::path make_recording(const char* name, int channels, bool both = true) {
  const fs::path dir =
      fs::temp_directory_path() / ("tacse3-replay-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(dir);
  rec::RecordingInfo info;
  info.width = kW;
  info.height = kH;
  info.fps = 50.0;
  if (!both) info.sensors = {rec::SensorId::kLeft};
  auto w = rec::RecordingWriter::open(dir, info);
  EXPECT_TRUE(w) << w.status().message();
  for (int i = 0; i < kFrames; ++i) {
    auto l = image(i, 0, channels);
    auto r = image(i, 1, channels);
    std::vector<rec::ImageView> views{{l.data(), kW, kH, channels}};
    if (both) views.push_back({r.data(), kW, kH, channels});
    EXPECT_TRUE(w.value()->write_frame(frame_time(i), views).ok());
  }
  EXPECT_TRUE(w.value()->finish().ok());
  return dir;
}

ReplayCameraConfig config(const fs::path& dir, bool realtime, bool right = false) {
  ReplayCameraConfig c;
  c.dir = dir.string();
  c.realtime = realtime;
  c.right = right;
  return c;
}

TEST(ReplayCamera, FastModeDeliversEveryFrameThenEnds) {
  for (int channels : {1, 3}) {
    const fs::path dir = make_recording(channels == 1 ? "fast-grey" : "fast-rgb", channels);
    for (bool right : {false, true}) {
      auto cam = make_replay_camera(config(dir, false, right));
      const auto st = cam->open();
      ASSERT_TRUE(st.ok()) << st.message();
      EXPECT_EQ(cam->info().width, kW);
      EXPECT_EQ(cam->info().format, channels == 1 ? tacse3::dsp::PixelFormat::kGrey
                                                  : tacse3::dsp::PixelFormat::kRgb888);
      EXPECT_NEAR(cam->info().granted_fps(), 50.0, 1e-6);
      ASSERT_TRUE(cam->start().ok());
      std::int64_t first = 0;
      for (int i = 0; i < kFrames; ++i) {
        Frame f;
        const auto s = cam->next_frame(f, 1000);
        ASSERT_TRUE(s.ok()) << s.message();
        if (i == 0) first = f.timestamp_ns;
        EXPECT_EQ(f.sequence, static_cast<std::uint32_t>(i));
        EXPECT_EQ(f.timestamp_ns - first, frame_time(i) - kT0);
        EXPECT_EQ(f.timestamp_source, tacse3::hal::TimestampSource::kSimulated);
        const auto expect = image(i, right ? 1 : 0, channels);
        ASSERT_EQ(f.view.size_bytes, expect.size());
        ASSERT_EQ(std::memcmp(f.view.data, expect.data(), expect.size()), 0) << "frame " << i;
        cam->release(f);
      }
      Frame f;
      auto s = cam->next_frame(f, 1000);
      EXPECT_EQ(s.code, CameraError::kDisconnected);
      EXPECT_NE(std::string(s.message()).find("end of recording"), std::string::npos)
          << s.message();
      EXPECT_EQ(cam->link_state(), LinkState::kFailed);
      // Said again later, after waiting out the timeout (a capture loop does not spin).
      const std::int64_t t = monotonic_ns();
      s = cam->next_frame(f, 30);
      EXPECT_EQ(s.code, CameraError::kDisconnected);
      EXPECT_GE(monotonic_ns() - t, 29'000'000);
      EXPECT_EQ(cam->stats().frames, static_cast<std::uint64_t>(kFrames));
      EXPECT_EQ(cam->stats().disconnects, 1u);
      // The decoder ran on its arena only.
      const auto d = tacse3::hal::replay_decode_stats(*cam);
      EXPECT_EQ(d.decodes, static_cast<std::uint64_t>(kFrames));
      EXPECT_GT(d.arena_allocations, 0u);
      EXPECT_EQ(d.heap_fallbacks, 0u);
      // Sized by open()'s trial decode: twice its peak, at least 64 KiB, in whole pages.
      EXPECT_GE(d.arena_bytes, d.arena_peak_bytes);
      EXPECT_LE(d.arena_bytes, std::max<std::size_t>(2 * d.arena_peak_bytes, 64 << 10) + 4096);
      std::printf("channels %d: %llu arena allocations for %d decodes, peak %zu of %zu bytes\n",
                  channels, static_cast<unsigned long long>(d.arena_allocations), kFrames,
                  d.arena_peak_bytes, d.arena_bytes);
      cam->stop();
    }
    fs::remove_all(dir);
  }
}

TEST(ReplayCamera, PacedToTheRecordedTimes) {
  const fs::path dir = make_recording("paced", 1);
  auto cam = make_replay_camera(config(dir, true));
  ASSERT_TRUE(cam->open().ok());
  ASSERT_TRUE(cam->start().ok());
  std::vector<double> period_ms;
  std::vector<double> late_ms;
  std::int64_t last = 0;
  const std::int64_t t_start = monotonic_ns();
  for (int i = 0; i < kFrames; ++i) {
    Frame f;
    ASSERT_TRUE(cam->next_frame(f, 1000).ok());
    const std::int64_t now = monotonic_ns();
    if (last != 0) period_ms.push_back(static_cast<double>(now - last) * 1e-6);
    late_ms.push_back(static_cast<double>(now - f.timestamp_ns) * 1e-6);
    last = now;
    cam->release(f);
  }
  const double elapsed_ms = static_cast<double>(last - t_start) * 1e-6;
  std::sort(period_ms.begin(), period_ms.end());
  std::sort(late_ms.begin(), late_ms.end());
  const double med = period_ms[period_ms.size() / 2];
  std::printf(
      "paced: median period %.3f ms (recorded 20.075/19.925), median lateness %.3f ms, "
      "%.1f ms for %d frames\n",
      med, late_ms[late_ms.size() / 2], elapsed_ms, kFrames);
  EXPECT_NEAR(med, 20.0, 2.0);
  EXPECT_GE(late_ms.front(), 0.0);  // never before its time
  // 19 intervals of the recording (380.15 ms) after the first frame's lead of one period.
  EXPECT_GE(elapsed_ms, 380.0);

  // The same recording as fast as possible.
  auto fast = make_replay_camera(config(dir, false));
  ASSERT_TRUE(fast->open().ok());
  ASSERT_TRUE(fast->start().ok());
  const std::int64_t t_fast = monotonic_ns();
  for (int i = 0; i < kFrames; ++i) {
    Frame f;
    ASSERT_TRUE(fast->next_frame(f, 1000).ok());
    fast->release(f);
  }
  const double fast_ms = static_cast<double>(monotonic_ns() - t_fast) * 1e-6;
  std::printf("fast: %.1f ms for %d frames\n", fast_ms, kFrames);
  EXPECT_LT(fast_ms, elapsed_ms / 2);
  fs::remove_all(dir);
}

// phase_ns delays a pad's frames (stamps and, paced, delivery): two replay cameras started
// together play free-running cameras this far apart.
TEST(ReplayCamera, PhaseDelaysEveryFrame) {
  const fs::path dir = make_recording("phase", 1);
  auto left = make_replay_camera(config(dir, true));
  auto c = config(dir, true, true);
  c.phase_ns = 5'000'000;
  auto right = make_replay_camera(c);
  ASSERT_TRUE(left->open().ok());
  ASSERT_TRUE(right->open().ok());
  const std::int64_t t0 = monotonic_ns();
  ASSERT_TRUE(left->start().ok());
  ASSERT_TRUE(right->start().ok());
  const std::int64_t started_apart = monotonic_ns() - t0;
  for (int i = 0; i < 3; ++i) {
    Frame l, r;
    ASSERT_TRUE(left->next_frame(l, 1000).ok());
    ASSERT_TRUE(right->next_frame(r, 1000).ok());
    EXPECT_GE(monotonic_ns(), r.timestamp_ns) << "delivered before its (delayed) time";
    EXPECT_GE(r.timestamp_ns - l.timestamp_ns, 5'000'000) << i;
    EXPECT_LE(r.timestamp_ns - l.timestamp_ns, 5'000'000 + started_apart) << i;
    left->release(l);
    right->release(r);
  }
  fs::remove_all(dir);
}

TEST(ReplayCamera, LoopStartsOverWithLaterTimestamps) {
  const fs::path dir = make_recording("loop", 3);
  auto c = config(dir, false);
  c.loop = true;
  auto cam = make_replay_camera(c);
  ASSERT_TRUE(cam->open().ok());
  ASSERT_TRUE(cam->start().ok());
  std::int64_t first = 0;
  for (int i = 0; i < 2 * kFrames + 5; ++i) {
    Frame f;
    ASSERT_TRUE(cam->next_frame(f, 1000).ok());
    if (i == 0) first = f.timestamp_ns;
    const int k = i % kFrames;
    const int pass = i / kFrames;
    EXPECT_EQ(f.sequence, static_cast<std::uint32_t>(i));
    // Each pass adds the recording's span plus one nominal period (20 ms at 50 fps).
    const std::int64_t span = frame_time(kFrames - 1) - kT0 + 20'000'000;
    EXPECT_EQ(f.timestamp_ns - first, pass * span + frame_time(k) - kT0) << i;
    const auto expect = image(k, 0, 3);
    ASSERT_EQ(std::memcmp(f.view.data, expect.data(), expect.size()), 0) << i;
    cam->release(f);
  }
}

TEST(ReplayCamera, BadRecordingsNameTheFile) {
  {
    auto cam = make_replay_camera(config("/nonexistent/tacse3-rec", false));
    const auto st = cam->open();
    EXPECT_EQ(st.code, CameraError::kNotFound);
    EXPECT_NE(std::string(st.message()).find("/nonexistent/tacse3-rec"), std::string::npos)
        << st.message();
    std::printf("%s\n", st.message());
  }
  {
    const fs::path dir = make_recording("missing", 1);
    fs::remove(dir / "right" / "000005.png");
    auto cam = make_replay_camera(config(dir, false));
    const auto st = cam->open();
    EXPECT_EQ(st.code, CameraError::kBadConfig);
    EXPECT_NE(std::string(st.message()).find("000005.png"), std::string::npos) << st.message();
    std::printf("%s\n", st.message());
    fs::remove_all(dir);
  }
  {
    const fs::path dir = make_recording("only-left", 1, false);
    auto cam = make_replay_camera(config(dir, false, true));
    const auto st = cam->open();
    EXPECT_EQ(st.code, CameraError::kNotFound);
    EXPECT_NE(std::string(st.message()).find("sensor right is not recorded"), std::string::npos)
        << st.message();
    std::printf("%s\n", st.message());
    fs::remove_all(dir);
  }
  {
    // Damage the image data of one frame but keep its header: found when it is decoded.
    const fs::path dir = make_recording("corrupt", 3);
    const fs::path bad = dir / "left" / "000003.png";
    std::fstream f(bad, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(0, std::ios::end);
    const auto size = static_cast<std::streamoff>(f.tellg());
    ASSERT_GT(size, 200);
    f.seekp(60);
    const std::string junk(static_cast<std::size_t>(size - 80), '\x55');
    f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
    f.close();
    auto cam = make_replay_camera(config(dir, false));
    ASSERT_TRUE(cam->open().ok());
    ASSERT_TRUE(cam->start().ok());
    Frame fr;
    for (int i = 0; i < 3; ++i) {
      ASSERT_TRUE(cam->next_frame(fr, 1000).ok());
      cam->release(fr);
    }
    const auto st = cam->next_frame(fr, 1000);
    EXPECT_EQ(st.code, CameraError::kCorruptFrame);
    EXPECT_NE(std::string(st.message()).find(bad.string()), std::string::npos) << st.message();
    std::printf("%s\n", st.message());
    EXPECT_EQ(cam->stats().corrupt, 1u);
    // The stream continues with the next frame.
    ASSERT_TRUE(cam->next_frame(fr, 1000).ok());
    const auto expect = image(4, 0, 3);
    EXPECT_EQ(std::memcmp(fr.view.data, expect.data(), expect.size()), 0);
    EXPECT_EQ(fr.sequence, 3u);
    cam->release(fr);
    fs::remove_all(dir);
  }
}

}  // namespace
