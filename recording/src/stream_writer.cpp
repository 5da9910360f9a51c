// SPDX-License-Identifier: Apache-2.0
// tacse3 recording: bounded-memory streaming recorder (a frame ring plus a PNG writer thread).
#include "tacse3/recording/stream_writer.hpp"

#include <array>
#include <cstring>
#include <exception>
#include <new>
#include <utility>

namespace tacse3::recording {

namespace {

constexpr std::size_t kMaxSensors = 2;

// The default sink: a recording directory in the documented format.
class DirectorySink final : public FrameSink {
 public:
  explicit DirectorySink(std::unique_ptr<RecordingWriter> w) : w_(std::move(w)) {}
  Status write_frame(std::int64_t t_ns, std::span<const ImageView> images) override {
    return w_->write_frame(t_ns, images);
  }
  Status finish() override { return w_->finish(); }

 private:
  std::unique_ptr<RecordingWriter> w_;
};

void bump(std::atomic<std::uint64_t>& c) noexcept {
  c.fetch_add(1, std::memory_order_relaxed);
}

Status check(const StreamWriterOptions& options) {
  const RecordingInfo& in = options.info;
  if (in.sensors.empty() || in.sensors.size() > kMaxSensors) {
    return Status::error("stream writer: sensors: one or two sensors must be recorded");
  }
  if (in.width <= 0 || in.height <= 0) {
    return Status::error("stream writer: width/height must be positive");
  }
  if (options.channels != 1 && options.channels != 3) {
    return Status::error("stream writer: channels " + std::to_string(options.channels) +
                         ": must be 1 (grey) or 3 (RGB)");
  }
  if (options.ring_frames < 2 || options.ring_frames > 4096) {
    return Status::error("stream writer: ring_frames " + std::to_string(options.ring_frames) +
                         ": must be within 2..4096");
  }
  return {};
}

}  // namespace

Result<std::unique_ptr<StreamWriter>> StreamWriter::start(const std::filesystem::path& dir,
                                                          const StreamWriterOptions& options) {
  // Checked before anything is created on disk.
  if (Status s = check(options); !s) return s;
  auto opened = RecordingWriter::open(dir, options.info, options.writer);
  if (!opened) return opened.status();
  return start(std::make_unique<DirectorySink>(std::move(opened).value()), options);
}

Result<std::unique_ptr<StreamWriter>> StreamWriter::start(std::unique_ptr<FrameSink> sink,
                                                          const StreamWriterOptions& options) {
  if (!sink) return Status::error("stream writer: no sink");
  if (Status s = check(options); !s) return s;
  const RecordingInfo& in = options.info;
  std::unique_ptr<StreamWriter> w(new StreamWriter());
  w->sink_ = std::move(sink);
  w->opt_ = options;
  w->image_bytes_ = static_cast<std::size_t>(in.width) * static_cast<std::size_t>(in.height) *
                    static_cast<std::size_t>(options.channels);
  w->slot_bytes_ = w->image_bytes_ * in.sensors.size();
  w->nslots_ = options.ring_frames;
  try {
    // Every byte the recording will ever hold in memory, allocated (and touched) now.
    w->pixels_.reset(new std::uint8_t[w->slot_bytes_ * w->nslots_]());
    w->times_.reset(new std::int64_t[w->nslots_]());
    w->thread_ = std::thread([p = w.get()] { p->run(); });
  } catch (const std::bad_alloc&) {
    return Status::error("stream writer: cannot allocate " +
                         std::to_string(w->slot_bytes_ * w->nslots_) + " bytes of frame slots");
  } catch (const std::exception& e) {
    return Status::error(std::string("stream writer: cannot start the writer thread: ") + e.what());
  }
  return w;
}

StreamWriter::~StreamWriter() {
  (void)close();
}

bool StreamWriter::push(std::int64_t t_ns, std::span<const StreamImage> images) noexcept {
  if (stopping_.load(std::memory_order_acquire) || failed_.load(std::memory_order_acquire)) {
    bump(n_.after_stop);
    return false;
  }
  const RecordingInfo& in = opt_.info;
  bool good = images.size() == in.sensors.size() && (!any_pushed_ || t_ns > last_pushed_t_ns_);
  for (std::size_t k = 0; good && k < images.size(); ++k) {
    const StreamImage& im = images[k];
    good = im.data != nullptr && im.width == in.width && im.height == in.height &&
           im.channels == opt_.channels &&
           (im.stride_bytes == 0 || im.stride_bytes >= im.width * im.channels);
  }
  if (!good) {
    bump(n_.rejected);
    return false;
  }
  const std::uint64_t head = head_.load(std::memory_order_relaxed);
  const std::uint64_t used = head - tail_.load(std::memory_order_acquire);
  if (used >= nslots_) {
    bump(n_.dropped_full);
    return false;
  }
  const std::size_t slot = static_cast<std::size_t>(head % nslots_);
  std::uint8_t* dst = pixels_.get() + slot * slot_bytes_;
  const std::size_t row =
      static_cast<std::size_t>(in.width) * static_cast<std::size_t>(opt_.channels);
  for (const StreamImage& im : images) {
    if (im.stride_bytes == 0 || static_cast<std::size_t>(im.stride_bytes) == row) {
      std::memcpy(dst, im.data, image_bytes_);
    } else {
      for (int y = 0; y < im.height; ++y) {
        std::memcpy(
            dst + static_cast<std::size_t>(y) * row,
            im.data + static_cast<std::size_t>(y) * static_cast<std::size_t>(im.stride_bytes), row);
      }
    }
    dst += image_bytes_;
  }
  times_[slot] = t_ns;
  head_.store(head + 1, std::memory_order_release);
  // Only this thread writes the high-water mark, so a plain load/store pair is enough.
  if (used + 1 > n_.high_water.load(std::memory_order_relaxed)) {
    n_.high_water.store(used + 1, std::memory_order_relaxed);
  }
  // A 32-bit atomic: notify_one() is a bare futex wake (no lock), and none when nobody waits.
  wake_.fetch_add(1, std::memory_order_release);
  wake_.notify_one();
  last_pushed_t_ns_ = t_ns;
  any_pushed_ = true;
  bump(n_.pushed);
  return true;
}

void StreamWriter::run() {
  std::array<ImageView, kMaxSensors> views{};
  const std::size_t nsensors = opt_.info.sensors.size();
  for (;;) {
    const std::uint32_t seen = wake_.load(std::memory_order_acquire);
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    const std::uint64_t head = head_.load(std::memory_order_acquire);
    if (tail == head) {
      if (stopping_.load(std::memory_order_acquire)) return;
      wake_.wait(seen, std::memory_order_acquire);
      continue;
    }
    bool wrote = false;
    if (!failed_.load(std::memory_order_acquire)) {
      const std::size_t slot = static_cast<std::size_t>(tail % nslots_);
      const std::uint8_t* src = pixels_.get() + slot * slot_bytes_;
      for (std::size_t k = 0; k < nsensors; ++k) {
        views[k] = {src + k * image_bytes_, opt_.info.width, opt_.info.height, opt_.channels};
      }
      const Status st =
          sink_->write_frame(times_[slot], std::span<const ImageView>(views.data(), nsensors));
      if (st.ok()) {
        wrote = true;
      } else {
        fail(st);
      }
    }
    // After a failure the remaining slots are discarded (push() no longer adds any).
    tail_.store(tail + 1, std::memory_order_release);
    // Counted only once the slot is free again (release, paired with stats()' acquire): a
    // producer pacing itself on pushed − written < ring_frames then always finds room. Counted
    // before the release, a push in between could be dropped as "ring full".
    if (wrote) n_.written.fetch_add(1, std::memory_order_release);
  }
}

void StreamWriter::fail(const Status& s) {
  std::lock_guard<std::mutex> lock(error_mutex_);
  if (error_.empty()) {
    error_ =
        "recording stopped after " + std::to_string(n_.written.load()) + " frames: " + s.message();
  }
  failed_.store(true, std::memory_order_release);
}

Status StreamWriter::close() {
  if (!closed_.exchange(true)) {
    stopping_.store(true, std::memory_order_release);
    wake_.fetch_add(1, std::memory_order_release);
    wake_.notify_one();
    if (thread_.joinable()) thread_.join();
    // Flush what was written even after a failure: the frames before it stay a valid recording.
    if (sink_) {
      const Status st = sink_->finish();
      if (!st.ok()) fail(st);
    }
  }
  std::lock_guard<std::mutex> lock(error_mutex_);
  return error_.empty() ? Status() : Status::error(error_);
}

std::string StreamWriter::error() const {
  std::lock_guard<std::mutex> lock(error_mutex_);
  return error_;
}

StreamWriterStats StreamWriter::stats() const noexcept {
  StreamWriterStats s;
  s.pushed = n_.pushed.load(std::memory_order_relaxed);
  s.written = n_.written.load(std::memory_order_acquire);  // its slot is free (run())
  s.dropped_full = n_.dropped_full.load(std::memory_order_relaxed);
  s.rejected = n_.rejected.load(std::memory_order_relaxed);
  s.after_stop = n_.after_stop.load(std::memory_order_relaxed);
  s.ring_high_water = n_.high_water.load(std::memory_order_relaxed);
  return s;
}

}  // namespace tacse3::recording
