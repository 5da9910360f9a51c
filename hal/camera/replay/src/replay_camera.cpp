// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: the `replay` camera backend (recording reader, heap-free PNG decode, pacing).
#include "tacse3/hal/camera/replay_camera.hpp"

#include <fcntl.h>
#include <spng.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "tacse3/hal/camera/clock.hpp"
#include "tacse3/hal/camera/spsc_ring.hpp"
#include "tacse3/recording/recording.hpp"

namespace tacse3::hal {

namespace {

namespace rec = tacse3::recording;

constexpr int kMaxBuffers = 16;
constexpr std::int64_t kPollNs = 4'000'000;
// libspng's context, zlib's inflate state and window and two row buffers: about 46 KiB for a
// 320x240 RGB frame. open() decodes the first frame in a trial arena of this size and keeps an
// arena twice what that decode used (libspng's allocations follow the image's size and format,
// not its content); a decode that needs more falls back to the heap and is counted.
constexpr std::size_t kTrialArenaBytes = 1u << 20;
constexpr std::size_t kMinArenaBytes = 64u << 10;

void bump(std::atomic<std::uint64_t>& c, std::uint64_t n = 1) noexcept {
  c.fetch_add(n, std::memory_order_relaxed);
}

// A bump allocator for one decode at a time. libspng's allocator callbacks carry no user pointer,
// so the arena in use is a thread_local set around each decode (each capture thread decodes its
// own frames). Blocks carry their size in a 16-byte header so realloc can copy.
struct Arena {
  std::unique_ptr<std::uint8_t[]> mem;
  std::size_t size = 0;
  std::size_t used = 0;
  std::size_t peak = 0;
  std::uint64_t allocations = 0;
  std::uint64_t fallbacks = 0;

  bool owns(const void* p) const noexcept {
    const auto* b = static_cast<const std::uint8_t*>(p);
    return b >= mem.get() && b < mem.get() + size;
  }
};

thread_local Arena* t_arena = nullptr;
constexpr std::size_t kHeader = 16;

void* arena_malloc(std::size_t size) noexcept {
  Arena* a = t_arena;
  const std::size_t need = kHeader + ((size + 15) & ~static_cast<std::size_t>(15));
  if (a != nullptr && a->used + need <= a->size) {
    std::uint8_t* p = a->mem.get() + a->used;
    std::memcpy(p, &size, sizeof(size));
    a->used += need;
    a->peak = std::max(a->peak, a->used);
    ++a->allocations;
    return p + kHeader;
  }
  if (a != nullptr) ++a->fallbacks;
  return std::malloc(size);
}

void arena_free(void* p) noexcept {
  if (p == nullptr) return;
  if (t_arena != nullptr && t_arena->owns(p)) return;  // reclaimed when the arena is reset
  std::free(p);
}

void* arena_calloc(std::size_t n, std::size_t size) noexcept {
  if (size != 0 && n > SIZE_MAX / size) return nullptr;
  void* p = arena_malloc(n * size);
  if (p != nullptr) std::memset(p, 0, n * size);
  return p;
}

void* arena_realloc(void* p, std::size_t size) noexcept {
  if (p == nullptr) return arena_malloc(size);
  if (t_arena == nullptr || !t_arena->owns(p)) return std::realloc(p, size);
  std::size_t old = 0;
  std::memcpy(&old, static_cast<std::uint8_t*>(p) - kHeader, sizeof(old));
  void* q = arena_malloc(size);
  if (q != nullptr) std::memcpy(q, p, std::min(old, size));
  return q;
}

class ReplayCamera final : public Camera {
 public:
  explicit ReplayCamera(const ReplayCameraConfig& c) : cfg_(c) {
    std::snprintf(info_.backend.data(), info_.backend.size(), "replay");
    std::snprintf(info_.driver.data(), info_.driver.size(), "tacse3_recording");
    std::snprintf(info_.card.data(), info_.card.size(), "%s", c.dir.c_str());
  }
  ~ReplayCamera() override { stop(); }

  CameraStatus open() override;
  CameraStatus start() override;
  CameraStatus next_frame(Frame& frame, int timeout_ms) override;
  void release(const Frame& frame) override { (void)returned_.push(frame.slot); }
  void stop() override;
  const CameraInfo& info() const override { return info_; }
  CameraStats stats() const override;
  LinkState link_state() const override { return state_.load(std::memory_order_acquire); }

  ReplayDecodeStats decode_stats() const noexcept {
    ReplayDecodeStats s;
    s.decodes = decodes_.load(std::memory_order_relaxed);
    s.arena_allocations = arena_allocations_.load(std::memory_order_relaxed);
    s.heap_fallbacks = heap_fallbacks_.load(std::memory_order_relaxed);
    s.arena_peak_bytes = arena_peak_.load(std::memory_order_relaxed);
    s.arena_bytes = arena_.size;
    return s;
  }

 private:
  const char* side() const noexcept { return cfg_.right ? "right" : "left"; }
  // Reads and decodes frame `index` into buffer `slot`.
  CameraStatus decode(std::size_t index, int slot) noexcept;
  // Sizes the decoder's arena by a trial decode of the first frame (kTrialArenaBytes).
  void size_arena();
  void take_returned() noexcept {
    std::uint32_t s = 0;
    while (returned_.pop(s)) {
      if (s < static_cast<std::uint32_t>(nbufs_) && held_[s]) {
        held_[s] = false;
        --outstanding_;
      }
    }
  }

  ReplayCameraConfig cfg_;
  CameraInfo info_;
  std::atomic<LinkState> state_{LinkState::kClosed};

  // Built in open().
  std::vector<std::string> paths_;  // this sensor's PNG of every frame
  std::vector<std::int64_t> t_ns_;  // frames.csv
  std::size_t frame_bytes_ = 0;
  int channels_ = 0;
  int nbufs_ = 0;
  std::unique_ptr<std::uint8_t[]> pixels_;
  std::unique_ptr<std::uint8_t[]> file_buf_;
  std::size_t file_buf_bytes_ = 0;
  Arena arena_;
  std::int64_t nominal_period_ns_ = 0;

  // Capture-thread state.
  std::array<bool, kMaxBuffers> held_{};
  int outstanding_ = 0;
  SpscRing<std::uint32_t, kMaxBuffers> returned_;
  std::size_t next_index_ = 0;    // next recording frame
  std::int64_t loop_offset_ = 0;  // added to t_ns for the current pass
  std::int64_t start_ns_ = 0;
  std::uint32_t seq_ = 0;
  int pending_slot_ = -1;  // decoded, waiting for its time
  // A frame that failed to decode, reported at its time when paced: a recording deleted mid-run
  // then fails at the frame rate, not as fast as open() can fail.
  bool pending_bad_ = false;
  CameraStatus bad_status_;
  bool ended_reported_ = false;

  struct {
    std::atomic<std::uint64_t> frames{0}, corrupt{0}, timeouts{0}, disconnects{0};
  } n_;
  std::atomic<std::uint64_t> decodes_{0}, arena_allocations_{0}, heap_fallbacks_{0};
  std::atomic<std::size_t> arena_peak_{0};
};

CameraStatus ReplayCamera::open() {
  if (link_state() != LinkState::kClosed) {
    return CameraStatus::error(CameraError::kBadState, "replay camera %s: open() called twice",
                               side());
  }
  if (cfg_.buffer_count < 2 || cfg_.buffer_count > kMaxBuffers) {
    return CameraStatus::error(CameraError::kBadConfig,
                               "replay camera %s: buffer_count %d: must be within 2..%d", side(),
                               cfg_.buffer_count, kMaxBuffers);
  }
  if (cfg_.dir.empty()) {
    return CameraStatus::error(CameraError::kBadConfig,
                               "replay camera %s: device (the recording directory) is empty",
                               side());
  }
  std::error_code ec;
  if (!std::filesystem::is_directory(cfg_.dir, ec)) {
    return CameraStatus::error(CameraError::kNotFound,
                               "replay camera %s: %s: no such recording directory", side(),
                               cfg_.dir.c_str());
  }
  auto opened = rec::RecordingReader::open(cfg_.dir);
  if (!opened) {
    return CameraStatus::error(CameraError::kBadConfig, "replay camera %s: %s", side(),
                               opened.status().message().c_str());
  }
  const rec::RecordingReader& r = opened.value();
  const int slot = r.slot_of(cfg_.right ? rec::SensorId::kRight : rec::SensorId::kLeft);
  if (slot < 0) {
    return CameraStatus::error(CameraError::kNotFound,
                               "replay camera %s: %s/recording.json: sensor %s is not recorded",
                               side(), cfg_.dir.c_str(), side());
  }
  if (r.frame_count() == 0) {
    return CameraStatus::error(CameraError::kBadConfig,
                               "replay camera %s: %s/frames.csv: no frames", side(),
                               cfg_.dir.c_str());
  }
  channels_ = r.channels();
  const rec::RecordingInfo& in = r.info();
  frame_bytes_ = static_cast<std::size_t>(in.width) * static_cast<std::size_t>(in.height) *
                 static_cast<std::size_t>(channels_);
  t_ns_ = r.times_ns();
  paths_.clear();
  paths_.reserve(r.frame_count());
  std::size_t largest = 0;
  for (std::size_t i = 0; i < r.frame_count(); ++i) {
    paths_.push_back(r.frame_path(static_cast<std::size_t>(slot), i).string());
    struct stat sb {};
    if (::stat(paths_.back().c_str(), &sb) != 0) {
      const int e = errno;
      return CameraStatus::error(CameraError::kNotFound, "replay camera %s: %s: %s", side(),
                                 paths_.back().c_str(), std::strerror(e));
    }
    largest = std::max(largest, static_cast<std::size_t>(sb.st_size));
  }
  nbufs_ = cfg_.buffer_count;
  // Zeroed, so every slot is resident (and locked) from the start: under load the consumer holds
  // more frames, and a slot's first use would otherwise fault on the capture thread.
  pixels_.reset(new std::uint8_t[frame_bytes_ * static_cast<std::size_t>(nbufs_)]());
  // Room for a file that grows a little after open() (a re-encoded frame); larger is an error.
  file_buf_bytes_ = largest + largest / 4 + 4096;
  // Left uninitialised: read() fills it, and its margin's pages stay unmapped until a file needs
  // them.
  file_buf_ = std::make_unique_for_overwrite<std::uint8_t[]>(file_buf_bytes_);
  nominal_period_ns_ = static_cast<std::int64_t>(1e9 / in.fps);

  info_.format = channels_ == 3 ? dsp::PixelFormat::kRgb888 : dsp::PixelFormat::kGrey;
  std::snprintf(info_.fourcc.data(), info_.fourcc.size(), "PNG");
  info_.width = in.width;
  info_.height = in.height;
  info_.stride_bytes = in.width * channels_;
  info_.buffer_count = nbufs_;
  info_.decoded = true;
  // The nominal rate of recording.json, as a fraction with a microsecond-exact denominator.
  info_.interval_num = 1'000'000;
  info_.interval_den = static_cast<std::uint32_t>(in.fps * 1e6 + 0.5);
  info_.timestamp_source = TimestampSource::kSimulated;
  held_.fill(false);
  outstanding_ = 0;
  size_arena();  // decode() checks the frame against info_
  state_.store(LinkState::kOpen, std::memory_order_release);
  return CameraStatus::success();
}

CameraStatus ReplayCamera::start() {
  if (link_state() != LinkState::kOpen) {
    return CameraStatus::error(CameraError::kBadState, "replay camera %s: start() in state %s",
                               side(), to_string(link_state()));
  }
  next_index_ = 0;
  loop_offset_ = 0;
  seq_ = 0;
  pending_slot_ = -1;
  pending_bad_ = false;
  ended_reported_ = false;
  start_ns_ = monotonic_ns() + nominal_period_ns_ + std::max<std::int64_t>(cfg_.phase_ns, 0);
  state_.store(LinkState::kStreaming, std::memory_order_release);
  return CameraStatus::success();
}

CameraStats ReplayCamera::stats() const {
  CameraStats s;
  s.frames = n_.frames.load(std::memory_order_relaxed);
  s.corrupt = n_.corrupt.load(std::memory_order_relaxed);
  s.timeouts = n_.timeouts.load(std::memory_order_relaxed);
  s.disconnects = n_.disconnects.load(std::memory_order_relaxed);
  return s;
}

void ReplayCamera::size_arena() {
  // The arena is left uninitialised: only the pages the decodes touch become resident.
  arena_ = Arena{};
  arena_.mem = std::make_unique_for_overwrite<std::uint8_t[]>(kTrialArenaBytes);
  arena_.size = kTrialArenaBytes;
  // A first frame that does not decode keeps the trial arena; next_frame() reports the frame.
  std::size_t size = kTrialArenaBytes;
  if (decode(0, 0).ok()) {
    size = (std::max(2 * arena_.peak, kMinArenaBytes) + 4095) & ~static_cast<std::size_t>(4095);
  }
  arena_ = Arena{};
  arena_.mem = std::make_unique_for_overwrite<std::uint8_t[]>(size);  // its calloc clears
  arena_.size = size;
  decodes_.store(0, std::memory_order_relaxed);
  arena_allocations_.store(0, std::memory_order_relaxed);
  heap_fallbacks_.store(0, std::memory_order_relaxed);
  arena_peak_.store(0, std::memory_order_relaxed);
}

CameraStatus ReplayCamera::decode(std::size_t index, int slot) noexcept {
  const char* file = paths_[index].c_str();
  const int fd = ::open(file, O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int e = errno;
    return CameraStatus::error(CameraError::kCorruptFrame, "replay camera %s: %s: cannot open: %s",
                               side(), file, std::strerror(e));
  }
  std::size_t got = 0;
  for (;;) {
    const ssize_t r = ::read(fd, file_buf_.get() + got, file_buf_bytes_ - got);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) {
      const int e = errno;
      ::close(fd);
      return CameraStatus::error(CameraError::kCorruptFrame, "replay camera %s: %s: read: %s",
                                 side(), file, std::strerror(e));
    }
    if (r == 0) break;
    got += static_cast<std::size_t>(r);
    if (got == file_buf_bytes_) {
      ::close(fd);
      return CameraStatus::error(CameraError::kCorruptFrame,
                                 "replay camera %s: %s: larger than at open() (%zu bytes)", side(),
                                 file, file_buf_bytes_);
    }
  }
  ::close(fd);

  arena_.used = 0;
  t_arena = &arena_;
  spng_alloc alloc{arena_malloc, arena_realloc, arena_calloc, arena_free};
  spng_ctx* ctx = spng_ctx_new2(&alloc, 0);
  CameraStatus st;
  if (ctx == nullptr) {
    st = CameraStatus::error(CameraError::kIo, "replay camera %s: %s: no memory for the decoder",
                             side(), file);
  } else {
    spng_set_crc_action(ctx, SPNG_CRC_ERROR, SPNG_CRC_ERROR);
    spng_set_image_limits(ctx, 1 << 16, 1 << 16);
    int e = spng_set_png_buffer(ctx, file_buf_.get(), got);
    spng_ihdr ihdr{};
    if (e == 0) e = spng_get_ihdr(ctx, &ihdr);
    const int fmt = channels_ == 1 ? SPNG_FMT_G8 : SPNG_FMT_RGB8;
    const int want_type = channels_ == 1 ? SPNG_COLOR_TYPE_GRAYSCALE : SPNG_COLOR_TYPE_TRUECOLOR;
    std::size_t len = 0;
    if (e == 0) e = spng_decoded_image_size(ctx, fmt, &len);
    if (e != 0) {
      st = CameraStatus::error(CameraError::kCorruptFrame, "replay camera %s: %s: bad PNG: %s",
                               side(), file, spng_strerror(e));
    } else if (static_cast<int>(ihdr.width) != info_.width ||
               static_cast<int>(ihdr.height) != info_.height || ihdr.bit_depth != 8 ||
               ihdr.color_type != want_type || len != frame_bytes_) {
      st = CameraStatus::error(CameraError::kCorruptFrame,
                               "replay camera %s: %s: %ux%u colour type %u, expected %dx%d %s",
                               side(), file, ihdr.width, ihdr.height, ihdr.color_type, info_.width,
                               info_.height, channels_ == 1 ? "grey" : "RGB");
    } else {
      std::uint8_t* out = pixels_.get() + frame_bytes_ * static_cast<std::size_t>(slot);
      e = spng_decode_image(ctx, out, len, fmt, 0);
      if (e != 0) {
        st = CameraStatus::error(CameraError::kCorruptFrame,
                                 "replay camera %s: %s: corrupt PNG data: %s", side(), file,
                                 spng_strerror(e));
      }
    }
    spng_ctx_free(ctx);
  }
  t_arena = nullptr;
  bump(decodes_);
  arena_allocations_.store(arena_.allocations, std::memory_order_relaxed);
  heap_fallbacks_.store(arena_.fallbacks, std::memory_order_relaxed);
  arena_peak_.store(arena_.peak, std::memory_order_relaxed);
  return st;
}

CameraStatus ReplayCamera::next_frame(Frame& frame, int timeout_ms) {
  const std::int64_t deadline = deadline_after_ms(timeout_ms);
  take_returned();
  for (;;) {
    const LinkState s = link_state();
    if (s == LinkState::kFailed) {
      if (ended_reported_) {
        // Already said: wait out the timeout so a capture loop does not spin on it.
        sleep_until_ns(deadline == INT64_MAX ? monotonic_ns() + 1'000'000'000 : deadline);
      }
      ended_reported_ = true;
      return CameraStatus::error(CameraError::kDisconnected,
                                 "replay camera %s: end of recording %s (%zu frames)", side(),
                                 cfg_.dir.c_str(), t_ns_.size());
    }
    if (s != LinkState::kStreaming) {
      return CameraStatus::error(CameraError::kBadState,
                                 "replay camera %s: next_frame() in state %s (call start())",
                                 side(), to_string(s));
    }
    if (next_index_ >= t_ns_.size()) {
      if (!cfg_.loop) {
        bump(n_.disconnects);
        state_.store(LinkState::kFailed, std::memory_order_release);
        continue;
      }
      // Clamped sums: the reader bounds a recording's span (1e6 s), but an unpaced loop adds it
      // up without end.
      loop_offset_ = rec::clamped_sum(
          loop_offset_, rec::clamped_sum(rec::clamped_difference(t_ns_.back(), t_ns_.front()),
                                         nominal_period_ns_));
      next_index_ = 0;
    }
    if (pending_slot_ < 0 && !pending_bad_) {
      if (outstanding_ >= nbufs_) {
        const std::int64_t now = monotonic_ns();
        if (now >= deadline) {
          bump(n_.timeouts);
          return CameraStatus::error(CameraError::kTimeout,
                                     "replay camera %s: all %d buffers are held by the consumer",
                                     side(), nbufs_);
        }
        sleep_until_ns(std::min(deadline, now + 1'000'000));
        take_returned();
        continue;
      }
      int slot = 0;
      while (held_[static_cast<std::size_t>(slot)]) ++slot;
      // Decode ahead of the frame's time, on this (capture) thread.
      const CameraStatus st = decode(next_index_, slot);
      if (st.ok()) {
        pending_slot_ = slot;
      } else {
        pending_bad_ = true;
        bad_status_ = st;
      }
    }
    const std::int64_t stamp =
        rec::clamped_sum(rec::clamped_sum(start_ns_, loop_offset_),
                         rec::clamped_difference(t_ns_[next_index_], t_ns_.front()));
    if (cfg_.realtime) {
      const std::int64_t now = monotonic_ns();
      if (now < stamp) {
        if (now >= deadline) {
          bump(n_.timeouts);
          return CameraStatus::error(CameraError::kTimeout,
                                     "replay camera %s: no frame within %d ms", side(), timeout_ms);
        }
        sleep_until_ns(std::min({stamp, deadline, now + kPollNs}));
        continue;
      }
    }
    if (pending_bad_) {
      pending_bad_ = false;
      ++next_index_;
      bump(n_.corrupt);
      return bad_status_;
    }
    const int slot = pending_slot_;
    pending_slot_ = -1;
    frame.view.data = pixels_.get() + frame_bytes_ * static_cast<std::size_t>(slot);
    frame.view.size_bytes = frame_bytes_;
    frame.view.width = info_.width;
    frame.view.height = info_.height;
    frame.view.stride_bytes = info_.stride_bytes;
    frame.view.format = info_.format;
    frame.sequence = seq_++;
    frame.timestamp_ns = stamp;
    frame.dropped_before = 0;
    frame.timestamp_source = TimestampSource::kSimulated;
    frame.slot = static_cast<std::uint32_t>(slot);
    held_[static_cast<std::size_t>(slot)] = true;
    ++outstanding_;
    ++next_index_;
    bump(n_.frames);
    return CameraStatus::success();
  }
}

void ReplayCamera::stop() {
  if (link_state() == LinkState::kClosed) return;
  pixels_.reset();
  file_buf_.reset();
  arena_.mem.reset();
  held_.fill(false);
  outstanding_ = 0;
  std::uint32_t s = 0;
  while (returned_.pop(s)) {
  }
  state_.store(LinkState::kClosed, std::memory_order_release);
}

}  // namespace

std::unique_ptr<Camera> make_replay_camera(const ReplayCameraConfig& config) {
  return std::make_unique<ReplayCamera>(config);
}

ReplayDecodeStats replay_decode_stats(const Camera& camera) noexcept {
  if (const auto* r = dynamic_cast<const ReplayCamera*>(&camera)) return r->decode_stats();
  return {};
}

}  // namespace tacse3::hal
