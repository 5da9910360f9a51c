// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: the streaming recording writer: round trip, bounded ring, write failures.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <thread>
#include <vector>

#include "tacse3/recording/recording.hpp"
#include "tacse3/recording/stream_writer.hpp"

namespace {

namespace fs = std::filesystem;
namespace rec = tacse3::recording;

constexpr int kW = 64;
constexpr int kH = 48;

fs::path scratch(const char* name) {
  fs::path p = fs::temp_directory_path() /
               ("tacse3-stream-writer-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(p);
  return p;
}

rec::StreamWriterOptions small_options(int channels, std::size_t ring) {
  rec::StreamWriterOptions o;
  o.info.width = kW;
  o.info.height = kH;
  o.channels = channels;
  o.ring_frames = ring;
  return o;
}

// Deterministic, frame- and sensor-dependent pixels.
std::vector<std::uint8_t> pixels(int frame, int sensor, int channels, int stride) {
  std::vector<std::uint8_t> v(static_cast<std::size_t>(stride) * kH, 0xEE);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW * channels; ++x) {
      v[static_cast<std::size_t>(y * stride + x)] =
          static_cast<std::uint8_t>((x * 7 + y * 13 + frame * 31 + sensor * 101) & 0xFF);
    }
  }
  return v;
}

bool wait_for(const std::function<bool()>& cond, int ms = 5000) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
  while (!cond()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

// A sink that blocks in write_frame() until opened, and fails from frame `fail_at` on.
class GateSink final : public rec::FrameSink {
 public:
  struct Shared {
    std::mutex m;
    std::condition_variable cv;
    bool open = true;
    int fail_at = -1;
    std::atomic<int> frames{0};
    std::atomic<int> finishes{0};
    std::vector<std::int64_t> times;
  };
  explicit GateSink(std::shared_ptr<Shared> s) : s_(std::move(s)) {}
  rec::Status write_frame(std::int64_t t_ns, std::span<const rec::ImageView> images) override {
    std::unique_lock<std::mutex> lock(s_->m);
    s_->cv.wait(lock, [&] { return s_->open; });
    if (images.size() != 2) return rec::Status::error("expected two images");
    if (s_->fail_at >= 0 && s_->frames.load() >= s_->fail_at) {
      return rec::Status::error("REC/left/000003.png: write failed: No space left on device");
    }
    s_->times.push_back(t_ns);
    ++s_->frames;
    return {};
  }
  rec::Status finish() override {
    ++s_->finishes;
    return {};
  }

 private:
  std::shared_ptr<Shared> s_;
};

TEST(StreamWriter, RoundTripThroughTheReader) {
  for (int channels : {1, 3}) {
    const fs::path dir = scratch(channels == 1 ? "grey" : "rgb");
    auto started = rec::StreamWriter::start(dir, small_options(channels, 4));
    ASSERT_TRUE(started) << started.status().message();
    auto& w = *started.value();
    constexpr int kFrames = 25;
    std::vector<std::int64_t> times;
    for (int i = 0; i < kFrames; ++i) {
      // Rows padded to a larger stride on the right sensor: the writer packs them.
      const int stride_r = kW * channels + 16;
      auto l = pixels(i, 0, channels, kW * channels);
      auto r = pixels(i, 1, channels, stride_r);
      const rec::StreamImage imgs[2] = {{l.data(), kW, kH, channels, 0},
                                        {r.data(), kW, kH, channels, stride_r}};
      const std::int64_t t = 5'000'000'000 + i * 8'333'333LL + (i % 3);
      // A 4-slot ring is smaller than the 25 frames: wait for room like a slow producer would,
      // so every frame is kept (the full-ring policy has its own test).
      ASSERT_TRUE(wait_for([&] { return w.stats().pushed - w.stats().written < 4; }));
      ASSERT_TRUE(w.push(t, imgs));
      times.push_back(t);
    }
    ASSERT_TRUE(w.close().ok()) << w.error();
    const auto s = w.stats();
    EXPECT_EQ(s.pushed, static_cast<std::uint64_t>(kFrames));
    EXPECT_EQ(s.written, static_cast<std::uint64_t>(kFrames));
    EXPECT_EQ(s.dropped_full, 0u);
    EXPECT_LE(s.ring_high_water, 4u);

    auto opened = rec::RecordingReader::open(dir);
    ASSERT_TRUE(opened) << opened.status().message();
    const rec::RecordingReader& rd = opened.value();
    ASSERT_EQ(rd.frame_count(), static_cast<std::size_t>(kFrames));
    EXPECT_EQ(rd.channels(), channels);
    EXPECT_EQ(rd.info().width, kW);
    rec::RecordingReader::Frame f;
    for (int i = 0; i < kFrames; ++i) {
      ASSERT_TRUE(rd.read_frame(static_cast<std::size_t>(i), &f).ok());
      EXPECT_EQ(f.t_ns, times[static_cast<std::size_t>(i)]);
      for (int k = 0; k < 2; ++k) {
        const auto expect = pixels(i, k, channels, kW * channels);
        ASSERT_EQ(f.images[static_cast<std::size_t>(k)].pixels, expect)
            << "frame " << i << " sensor " << k;
      }
    }
    fs::remove_all(dir);
  }
}

TEST(StreamWriter, FullRingDropsAndCounts) {
  auto shared = std::make_shared<GateSink::Shared>();
  shared->open = false;  // the writer thread blocks on the first frame
  auto started = rec::StreamWriter::start(std::make_unique<GateSink>(shared), small_options(3, 4));
  ASSERT_TRUE(started) << started.status().message();
  auto& w = *started.value();
  auto l = pixels(0, 0, 3, kW * 3);
  const rec::StreamImage imgs[2] = {{l.data(), kW, kH, 3, 0}, {l.data(), kW, kH, 3, 0}};
  int accepted = 0;
  for (int i = 0; i < 10; ++i) accepted += w.push(1000 + i, imgs) ? 1 : 0;
  // The slot being written stays in use until the sink returns: exactly the ring's 4 fit.
  EXPECT_EQ(accepted, 4);
  EXPECT_EQ(w.stats().dropped_full, 6u);
  EXPECT_EQ(w.stats().ring_high_water, 4u);
  {
    std::lock_guard<std::mutex> lock(shared->m);
    shared->open = true;
  }
  shared->cv.notify_all();
  ASSERT_TRUE(w.close().ok());
  EXPECT_EQ(shared->frames.load(), 4);
  EXPECT_EQ(shared->finishes.load(), 1);
  EXPECT_EQ(shared->times, (std::vector<std::int64_t>{1000, 1001, 1002, 1003}));
  EXPECT_EQ(w.stats().written, 4u);
}

TEST(StreamWriter, RejectsBadPushesWithoutQueueing) {
  auto shared = std::make_shared<GateSink::Shared>();
  auto started = rec::StreamWriter::start(std::make_unique<GateSink>(shared), small_options(1, 4));
  ASSERT_TRUE(started);
  auto& w = *started.value();
  auto g = pixels(0, 0, 1, kW);
  const rec::StreamImage good[2] = {{g.data(), kW, kH, 1, 0}, {g.data(), kW, kH, 1, 0}};
  const rec::StreamImage one_missing[2] = {{g.data(), kW, kH, 1, 0}, {nullptr, kW, kH, 1, 0}};
  const rec::StreamImage wrong_size[2] = {{g.data(), kW, kH - 2, 1, 0}, {g.data(), kW, kH, 1, 0}};
  const rec::StreamImage wrong_channels[2] = {{g.data(), kW, kH, 3, 0}, {g.data(), kW, kH, 3, 0}};
  EXPECT_TRUE(w.push(100, good));
  EXPECT_FALSE(w.push(200, one_missing));  // a frame for only one sensor is never recorded
  EXPECT_FALSE(w.push(200, wrong_size));
  EXPECT_FALSE(w.push(200, wrong_channels));
  EXPECT_FALSE(w.push(100, good));  // t_ns not increasing
  EXPECT_FALSE(w.push(300, std::span<const rec::StreamImage>(good, 1)));
  EXPECT_TRUE(w.push(101, good));
  ASSERT_TRUE(w.close().ok());
  EXPECT_EQ(w.stats().rejected, 5u);
  EXPECT_EQ(shared->times, (std::vector<std::int64_t>{100, 101}));
  // After close() pushes are counted no-ops.
  EXPECT_FALSE(w.push(102, good));
  EXPECT_EQ(w.stats().after_stop, 1u);
}

TEST(StreamWriter, SinkFailureStopsTheRecordingWithAMessage) {
  auto shared = std::make_shared<GateSink::Shared>();
  shared->fail_at = 3;
  auto started = rec::StreamWriter::start(std::make_unique<GateSink>(shared), small_options(3, 8));
  ASSERT_TRUE(started);
  auto& w = *started.value();
  auto l = pixels(0, 0, 3, kW * 3);
  const rec::StreamImage imgs[2] = {{l.data(), kW, kH, 3, 0}, {l.data(), kW, kH, 3, 0}};
  std::int64_t t = 0;
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(wait_for([&] { return w.stats().pushed - w.stats().written < 2 || w.failed(); }));
    (void)w.push(++t, imgs);
  }
  ASSERT_TRUE(wait_for([&] { return w.failed(); }));
  EXPECT_EQ(w.error(),
            "recording stopped after 3 frames: REC/left/000003.png: write failed: No space left on "
            "device");
  // The stream goes on: pushes return at once, counted, never queued.
  for (int i = 0; i < 10; ++i) EXPECT_FALSE(w.push(++t, imgs));
  EXPECT_GE(w.stats().after_stop, 10u);
  const rec::Status st = w.close();
  EXPECT_FALSE(st.ok());
  EXPECT_EQ(st.message(), w.error());
  EXPECT_EQ(shared->frames.load(), 3);
  EXPECT_EQ(shared->finishes.load(), 1);  // what was written is flushed
}

// A real file-system failure: the sensor folder disappears under the writer.
TEST(StreamWriter, VanishedDirectoryStopsTheRecording) {
  const fs::path dir = scratch("vanish");
  auto started = rec::StreamWriter::start(dir, small_options(1, 8));
  ASSERT_TRUE(started) << started.status().message();
  auto& w = *started.value();
  auto g = pixels(0, 0, 1, kW);
  const rec::StreamImage imgs[2] = {{g.data(), kW, kH, 1, 0}, {g.data(), kW, kH, 1, 0}};
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(w.push(i + 1, imgs));
  ASSERT_TRUE(wait_for([&] { return w.stats().written == 3; }));
  fs::remove_all(dir / "left");
  EXPECT_TRUE(w.push(10, imgs));
  ASSERT_TRUE(wait_for([&] { return w.failed(); }));
  const std::string e = w.error();
  std::printf("%s\n", e.c_str());
  EXPECT_NE(e.find("recording stopped after 3 frames"), std::string::npos) << e;
  EXPECT_NE(e.find("000003.png"), std::string::npos) << e;
  EXPECT_FALSE(w.push(11, imgs));
  EXPECT_FALSE(w.close().ok());
  fs::remove_all(dir);
}

TEST(StreamWriter, BadOptionsAreErrors) {
  auto o = small_options(2, 4);
  auto r = rec::StreamWriter::start(scratch("bad"), o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("channels 2"), std::string::npos) << r.status().message();
  o = small_options(1, 1);
  r = rec::StreamWriter::start(std::make_unique<GateSink>(std::make_shared<GateSink::Shared>()), o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.status().message().find("ring_frames 1"), std::string::npos);
}

}  // namespace
