// SPDX-License-Identifier: Apache-2.0
// tacse3 recording: bounded-memory streaming recorder (a frame ring plus a PNG writer thread).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>

#include "tacse3/recording/recording.hpp"

namespace tacse3::recording {

// One sensor image handed to push(): 8-bit grey (1 channel) or RGB (3), rows stride_bytes apart
// (0 = tightly packed). The writer copies it; the caller keeps ownership.
struct StreamImage {
  const std::uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  int channels = 0;
  int stride_bytes = 0;
};

// Where the writer thread puts the frames. The default writes a recording directory through
// RecordingWriter; tests inject a sink that fails on command.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  // One frame: an image per recorded sensor (RecordingInfo::sensors order), then its time.
  virtual Status write_frame(std::int64_t t_ns, std::span<const ImageView> images) = 0;
  // Flushes everything written so far.
  virtual Status finish() = 0;
};

struct StreamWriterOptions {
  RecordingInfo info;  // size, fps, sensors (slot order), rig, extra_json
  int channels = 3;    // 1 (grey) or 3 (RGB): every pushed image must have it
  // Frame slots allocated at start(): memory = ring_frames * sensors * width * height * channels
  // (16 x 2 x 320 x 240 x 3 = 7.4 MB, 133 ms of both streams at 120 Hz).
  std::size_t ring_frames = 16;
  WriterOptions writer;  // PNG compression level, overwrite
};

// Counters since start(); readable from any thread.
struct StreamWriterStats {
  std::uint64_t pushed = 0;        // accepted into the ring
  std::uint64_t written = 0;       // written by the sink (PNGs + frames.csv row), slot freed
  std::uint64_t dropped_full = 0;  // rejected: every slot was waiting for the writer
  std::uint64_t rejected = 0;    // rejected: wrong image count/size/channels or t_ns not increasing
  std::uint64_t after_stop = 0;  // pushes after the recording stopped (failure or close)
  std::uint64_t ring_high_water = 0;  // most slots in use at once
};

// A recording written while the daemon streams. push() is called from one thread (the DSP
// thread); it never blocks, never allocates and never touches the disk: it copies the images
// into a free slot of a ring allocated at start() and returns false (counted) when the ring is
// full. One writer thread encodes the PNGs and writes frames.csv; recording.json is written by
// start(). A write error (ENOSPC, a vanished directory) stops the recording: the message is kept
// (error()), frames already written stay readable, and later pushes are counted no-ops; the
// caller's stream is not affected. close() writes every frame still in the ring, flushes, joins
// the thread and returns the first error.
//
// Pairing: one push is one frames.csv row, with one image per recorded sensor. The caller pushes
// only complete pairs (the daemon pushes the frame pairs its DSP thread formed); a push with a
// missing image (null data) is rejected and counted, so the recording never holds a frame for
// only one sensor.
class StreamWriter {
 public:
  // Creates dir (recording.json now), allocates the ring and starts the writer thread.
  static Result<std::unique_ptr<StreamWriter>> start(const std::filesystem::path& dir,
                                                     const StreamWriterOptions& options);
  // Same with a caller-provided sink (tests, other containers). options.writer is unused.
  static Result<std::unique_ptr<StreamWriter>> start(std::unique_ptr<FrameSink> sink,
                                                     const StreamWriterOptions& options);
  ~StreamWriter();  // close()
  StreamWriter(const StreamWriter&) = delete;
  StreamWriter& operator=(const StreamWriter&) = delete;

  // Queues one frame: images[k] for the sensor in slot k. t_ns must increase strictly.
  // true: queued. false: not queued (ring full, bad images, or the recording stopped).
  bool push(std::int64_t t_ns, std::span<const StreamImage> images) noexcept;

  // Drains the ring, flushes, stops the thread. Idempotent; returns the first error.
  Status close();

  // True once a write error stopped the recording (any thread, lock-free).
  bool failed() const noexcept { return failed_.load(std::memory_order_acquire); }
  // The write error that stopped the recording ("" if none). Takes a lock: not for the DSP path.
  std::string error() const;
  StreamWriterStats stats() const noexcept;
  std::size_t slot_bytes() const noexcept { return slot_bytes_; }

 private:
  StreamWriter() = default;
  void run();
  void fail(const Status& s);

  std::unique_ptr<FrameSink> sink_;
  StreamWriterOptions opt_;
  std::size_t image_bytes_ = 0;  // one sensor image
  std::size_t slot_bytes_ = 0;   // every sensor's image of one frame
  std::size_t nslots_ = 0;
  std::unique_ptr<std::uint8_t[]> pixels_;
  std::unique_ptr<std::int64_t[]> times_;
  // Single producer (push) / single consumer (writer thread) ring of slot indices.
  alignas(64) std::atomic<std::uint64_t> head_{0};
  alignas(64) std::atomic<std::uint64_t> tail_{0};
  std::atomic<std::uint32_t> wake_{0};  // bumped by push() and close(); the writer waits on it
  std::atomic<bool> stopping_{false};
  std::atomic<bool> failed_{false};
  std::atomic<bool> closed_{false};
  std::int64_t last_pushed_t_ns_ = 0;
  bool any_pushed_ = false;
  struct Counters {
    std::atomic<std::uint64_t> pushed{0}, written{0}, dropped_full{0}, rejected{0}, after_stop{0},
        high_water{0};
  } n_;
  mutable std::mutex error_mutex_;
  std::string error_;
  std::thread thread_;
};

}  // namespace tacse3::recording
