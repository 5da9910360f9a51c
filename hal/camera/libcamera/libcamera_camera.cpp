// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: libcamera capture backend for CSI sensors and other libcamera pipelines.
#include "tacse3/hal/camera/libcamera_camera.hpp"

#include <errno.h>
#include <libcamera/libcamera.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <new>
#include <vector>

#include "tacse3/hal/camera/backoff.hpp"
#include "tacse3/hal/camera/clock.hpp"
#include "tacse3/hal/camera/formats.hpp"
#include "tacse3/hal/camera/sequence.hpp"
#include "tacse3/hal/camera/spsc_ring.hpp"

namespace tacse3::hal {
namespace {

namespace lc = libcamera;

static_assert(drm_fourcc::kYuyv == lc::formats::YUYV.fourcc());
static_assert(drm_fourcc::kBgr888 == lc::formats::BGR888.fourcc());
static_assert(drm_fourcc::kR8 == lc::formats::R8.fourcc());
static_assert(drm_fourcc::kYuv420 == lc::formats::YUV420.fourcc());
static_assert(drm_fourcc::kNv12 == lc::formats::NV12.fourcc());

constexpr int kMaxSlots = 16;

// libcamera allows one CameraManager per process (a second one is fatal), so every camera of
// the process shares this one. Only touched at open/reconnect/destruction.
std::shared_ptr<lc::CameraManager> shared_manager(CameraStatus& status) {
  static std::mutex mutex;
  static std::weak_ptr<lc::CameraManager> weak;
  std::lock_guard<std::mutex> lock(mutex);
  if (auto cm = weak.lock()) return cm;
  std::shared_ptr<lc::CameraManager> cm(new (std::nothrow) lc::CameraManager(),
                                        [](lc::CameraManager* m) {
                                          m->stop();
                                          delete m;
                                        });
  if (!cm) {
    status = CameraStatus::error(CameraError::kIo, "libcamera: cannot create the CameraManager");
    return nullptr;
  }
  const int r = cm->start();
  if (r < 0) {
    status = CameraStatus::error(CameraError::kIo, "libcamera: CameraManager::start failed: %s",
                                 std::strerror(-r));
    return nullptr;
  }
  weak = cm;
  return cm;
}

struct Counters {
  std::atomic<std::uint64_t> frames{0};
  std::atomic<std::uint64_t> drops{0};
  std::atomic<std::uint64_t> corrupt{0};
  std::atomic<std::uint64_t> timeouts{0};
  std::atomic<std::uint64_t> disconnects{0};
  std::atomic<std::uint64_t> reconnects{0};
  std::atomic<std::uint64_t> reconnect_attempts{0};
};

void bump(std::atomic<std::uint64_t>& c, std::uint64_t n = 1) noexcept {
  c.fetch_add(n, std::memory_order_relaxed);
}

class LibcameraCamera final : public Camera {
 public:
  explicit LibcameraCamera(const CameraConfig& config) : cfg_(config), backoff_(config.reconnect) {
    copy_text(info_.backend, "libcamera");
    copy_text(info_.driver, "libcamera");
  }
  ~LibcameraCamera() override {
    stop();
    if (wake_fd_ >= 0) ::close(wake_fd_);
  }
  LibcameraCamera(const LibcameraCamera&) = delete;
  LibcameraCamera& operator=(const LibcameraCamera&) = delete;

  CameraStatus open() override;
  CameraStatus start() override;
  CameraStatus next_frame(Frame& frame, int timeout_ms) override;
  void release(const Frame& frame) override { (void)returned_.push(frame.slot); }
  void stop() override;
  const CameraInfo& info() const override { return info_; }
  CameraStats stats() const override;
  LinkState link_state() const override { return state_.load(std::memory_order_acquire); }

 private:
  struct Slot {
    lc::Request* request = nullptr;
    lc::FrameBuffer* buffer = nullptr;
    void* map_base = nullptr;  // mmap of the plane's dmabuf, from offset 0
    std::size_t map_length = 0;
    const std::uint8_t* data = nullptr;  // first plane
    std::size_t length = 0;
    bool held = false;
  };

  const char* name() const noexcept {
    return camera_id_.empty() ? (cfg_.device.empty() ? "(first)" : cfg_.device.c_str())
                              : camera_id_.c_str();
  }
  CameraStatus acquire_and_configure();
  CameraStatus start_streaming();
  CameraStatus queue_slot(std::uint32_t index, bool reuse);
  void teardown() noexcept;
  void unmap(Slot& s) noexcept;
  CameraStatus lose(const char* why);
  CameraStatus reconnect(std::int64_t deadline_ns);
  void take_returned() noexcept;
  void wake() noexcept {
    const std::uint64_t one = 1;
    (void)!::write(wake_fd_, &one, sizeof(one));  // EFD_NONBLOCK: never blocks
  }
  void set_state(LinkState s) noexcept { state_.store(s, std::memory_order_release); }

  // libcamera's thread. Never block, lock or allocate here.
  void on_request_completed(lc::Request* request) {
    (void)completed_.push(static_cast<std::uint32_t>(request->cookie()));
    wake();
  }
  void on_disconnected() {
    lost_.store(true, std::memory_order_release);
    wake();
  }

  CameraConfig cfg_;
  Backoff backoff_;
  SequenceTracker sequence_;
  std::shared_ptr<lc::CameraManager> manager_;
  std::shared_ptr<lc::Camera> camera_;
  std::string camera_id_;
  std::unique_ptr<lc::CameraConfiguration> configuration_;
  std::unique_ptr<lc::FrameBufferAllocator> allocator_;
  lc::Stream* stream_ = nullptr;
  std::vector<std::unique_ptr<lc::Request>> requests_;
  std::array<Slot, kMaxSlots> slots_{};
  int nslots_ = 0;
  int outstanding_ = 0;
  bool acquired_ = false;
  bool running_ = false;
  dsp::PixelFormat format_ = dsp::PixelFormat::kGrey;
  int stride_ = 0;
  std::size_t crop_offset_ = 0;  // bytes from the buffer start to the kept 320x240 window
  std::int64_t next_retry_ns_ = 0;
  int wake_fd_ = -1;
  std::atomic<bool> lost_{false};
  SpscRing<std::uint32_t, 32> completed_;  // libcamera thread -> capture thread
  SpscRing<std::uint32_t, 32> returned_;   // consumer -> capture thread
  std::atomic<LinkState> state_{LinkState::kClosed};
  CameraInfo info_;
  Counters counters_;
};

CameraStatus LibcameraCamera::open() {
  if (link_state() != LinkState::kClosed) {
    return CameraStatus::error(CameraError::kBadState, "libcamera camera %s: open() called twice",
                               name());
  }
  CameraStatus st = validate(cfg_);
  if (!st.ok()) return st;
  if (wake_fd_ < 0) wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (wake_fd_ < 0) {
    return CameraStatus::error(CameraError::kIo, "libcamera camera: eventfd: %s",
                               std::strerror(errno));
  }
  if (!manager_) manager_ = shared_manager(st);
  if (!manager_) return st;
  st = acquire_and_configure();
  if (!st.ok()) {
    teardown();  // the manager stays (shared; released by stop() or destruction)
    return st;
  }
  set_state(LinkState::kOpen);
  return st;
}

CameraStatus LibcameraCamera::acquire_and_configure() {
  // Which camera.
  std::shared_ptr<lc::Camera> cam;
  if (!camera_id_.empty()) {
    cam = manager_->get(camera_id_);  // reconnect: the one we had
  } else if (cfg_.device.empty() || cfg_.device[0] == '#') {
    std::vector<std::shared_ptr<lc::Camera>> cams = manager_->cameras();
    std::sort(cams.begin(), cams.end(),
              [](const auto& a, const auto& b) { return a->id() < b->id(); });
    const long index = cfg_.device.empty() ? 0 : std::strtol(cfg_.device.c_str() + 1, nullptr, 10);
    if (index < 0 || static_cast<std::size_t>(index) >= cams.size()) {
      return CameraStatus::error(CameraError::kNotFound,
                                 "libcamera: camera #%ld requested, %zu found (check the sensor "
                                 "overlay in config.txt; 'cam --list' lists them)",
                                 index, cams.size());
    }
    cam = cams[static_cast<std::size_t>(index)];
  } else {
    cam = manager_->get(cfg_.device);
  }
  if (!cam) {
    const std::size_t n = manager_->cameras().size();
    return CameraStatus::error(CameraError::kNotFound,
                               "libcamera: no camera with id '%s' (%zu cameras present; 'cam "
                               "--list' lists their ids)",
                               camera_id_.empty() ? cfg_.device.c_str() : camera_id_.c_str(), n);
  }
  camera_ = cam;
  camera_id_ = cam->id();
  copy_text(info_.card, camera_id_.c_str());

  int r = camera_->acquire();
  if (r < 0) {
    return CameraStatus::error(r == -EBUSY ? CameraError::kBusy : CameraError::kIo,
                               "libcamera camera %s: acquire: %s", name(), std::strerror(-r));
  }
  acquired_ = true;

  configuration_ = camera_->generateConfiguration({lc::StreamRole::Viewfinder});
  if (!configuration_ || configuration_->size() != 1) {
    return CameraStatus::error(CameraError::kNotSupported,
                               "libcamera camera %s: no viewfinder stream configuration", name());
  }
  lc::StreamConfiguration& sc = configuration_->at(0);
  const std::vector<lc::PixelFormat> offered = sc.formats().pixelformats();
  std::array<std::uint32_t, 64> fourccs{};
  const std::size_t count = std::min(offered.size(), fourccs.size());
  for (std::size_t i = 0; i < count; ++i) fourccs[i] = offered[i].fourcc();
  const LibcameraFormatChoice choice = choose_libcamera_format(fourccs.data(), count);
  if (!choice.found) {
    return CameraStatus::error(CameraError::kNotSupported,
                               "libcamera camera %s: none of its %zu formats is usable (want YUYV, "
                               "BGR888, R8 or YUV420/NV12)",
                               name(), count);
  }
  sc.pixelFormat = lc::PixelFormat(choice.fourcc);
  sc.bufferCount = static_cast<unsigned int>(cfg_.buffer_count);
  // Ask for the configured size; when the pipeline can only grant a smaller one (vimc proposes
  // 318 for 320), ask again for a bit more, and centre-crop a slightly larger grant.
  const PixelSize want{cfg_.width, cfg_.height};
  PixelSize asked = want;
  lc::CameraConfiguration::Status vs = lc::CameraConfiguration::Invalid;
  for (int attempt = 0; attempt < 4; ++attempt) {
    sc.pixelFormat = lc::PixelFormat(choice.fourcc);
    sc.size =
        lc::Size(static_cast<unsigned int>(asked.width), static_cast<unsigned int>(asked.height));
    vs = configuration_->validate();
    const PixelSize got{static_cast<int>(sc.size.width), static_cast<int>(sc.size.height)};
    const PixelSize next = next_size_request(want, asked, got);
    if (vs == lc::CameraConfiguration::Invalid || sc.pixelFormat.fourcc() != choice.fourcc ||
        (next.width == asked.width && next.height == asked.height)) {
      break;
    }
    asked = next;
  }
  const int got_w = static_cast<int>(sc.size.width);
  const int got_h = static_cast<int>(sc.size.height);
  const CropPlan crop = plan_centre_crop(choice.output, cfg_.width, cfg_.height, got_w, got_h,
                                         static_cast<int>(sc.stride));
  if (vs == lc::CameraConfiguration::Invalid || sc.pixelFormat.fourcc() != choice.fourcc ||
      !crop.ok) {
    return CameraStatus::error(CameraError::kNotSupported,
                               "libcamera camera %s: %s %dx%d not accepted (pipeline proposes %s "
                               "%ux%u; a larger mode is centre-cropped by at most %d px per "
                               "dimension)",
                               name(), fourcc_string(choice.fourcc).data(), cfg_.width, cfg_.height,
                               fourcc_string(sc.pixelFormat.fourcc()).data(), sc.size.width,
                               sc.size.height, kMaxCropPixels);
  }
  r = camera_->configure(configuration_.get());
  if (r < 0) {
    return CameraStatus::error(CameraError::kIo, "libcamera camera %s: configure: %s", name(),
                               std::strerror(-r));
  }
  stream_ = sc.stream();
  format_ = choice.output;
  stride_ = static_cast<int>(sc.stride);
  // The crop again with the stride configure() settled on (validate() may not have set it).
  const CropPlan final_crop =
      plan_centre_crop(format_, cfg_.width, cfg_.height, got_w, got_h, stride_);
  if (!final_crop.ok) {
    return CameraStatus::error(
        CameraError::kNotSupported,
        "libcamera camera %s: configured %dx%d with %d-byte rows cannot hold a "
        "%dx%d window",
        name(), got_w, got_h, stride_, cfg_.width, cfg_.height);
  }
  crop_offset_ = final_crop.byte_offset;

  allocator_ = std::make_unique<lc::FrameBufferAllocator>(camera_);
  r = allocator_->allocate(stream_);
  if (r < 0) {
    return CameraStatus::error(CameraError::kIo, "libcamera camera %s: allocating buffers: %s",
                               name(), std::strerror(-r));
  }
  const auto& buffers = allocator_->buffers(stream_);
  nslots_ = static_cast<int>(std::min<std::size_t>(buffers.size(), kMaxSlots));
  if (nslots_ < 2) {
    return CameraStatus::error(CameraError::kNotSupported,
                               "libcamera camera %s: %d buffers allocated, need at least 2", name(),
                               nslots_);
  }
  requests_.clear();
  requests_.reserve(static_cast<std::size_t>(nslots_));
  for (int i = 0; i < nslots_; ++i) {
    lc::FrameBuffer* fb = buffers[static_cast<std::size_t>(i)].get();
    std::unique_ptr<lc::Request> req = camera_->createRequest(static_cast<std::uint64_t>(i));
    if (!req || req->addBuffer(stream_, fb) < 0) {
      return CameraStatus::error(CameraError::kIo, "libcamera camera %s: building request %d",
                                 name(), i);
    }
    const lc::FrameBuffer::Plane& plane = fb->planes().at(0);
    const std::size_t offset =
        plane.offset == lc::FrameBuffer::Plane::kInvalidOffset ? 0 : plane.offset;
    const std::size_t map_length = offset + plane.length;
    void* base = ::mmap(nullptr, map_length, PROT_READ, MAP_SHARED, plane.fd.get(), 0);
    if (base == MAP_FAILED) {
      return CameraStatus::error(CameraError::kIo, "libcamera camera %s: mmap buffer %d: %s",
                                 name(), i, std::strerror(errno));
    }
    Slot& s = slots_[static_cast<std::size_t>(i)];
    s.request = req.get();
    s.buffer = fb;
    s.map_base = base;
    s.map_length = map_length;
    s.data = static_cast<const std::uint8_t*>(base) + offset;
    s.length = plane.length;
    s.held = false;
    requests_.push_back(std::move(req));
  }
  camera_->requestCompleted.connect(this, &LibcameraCamera::on_request_completed);
  camera_->disconnected.connect(this, &LibcameraCamera::on_disconnected);

  info_.fourcc = {};
  copy_text(info_.fourcc, fourcc_string(choice.fourcc).data());
  info_.format = format_;
  info_.width = cfg_.width;
  info_.height = cfg_.height;
  info_.native_width = got_w;
  info_.native_height = got_h;
  info_.stride_bytes = stride_;
  info_.buffer_count = nslots_;
  info_.decoded = false;
  info_.timestamp_source = TimestampSource::kSensor;
  return CameraStatus::success();
}

CameraStatus LibcameraCamera::queue_slot(std::uint32_t index, bool reuse) {
  Slot& s = slots_[index];
  if (reuse) s.request->reuse(lc::Request::ReuseBuffers);
  const int r = camera_->queueRequest(s.request);
  if (r < 0) {
    return CameraStatus::error(r == -ENODEV ? CameraError::kDisconnected : CameraError::kIo,
                               "libcamera camera %s: queueRequest: %s", name(), std::strerror(-r));
  }
  return CameraStatus::success();
}

CameraStatus LibcameraCamera::start_streaming() {
  lc::ControlList controls;
  const std::int64_t frame_us = 1'000'000 / cfg_.fps;  // 8333 us at 120 fps
  const bool can_limit = camera_->controls().count(&lc::controls::FrameDurationLimits) != 0;
  if (can_limit) {
    const std::array<std::int64_t, 2> limits{frame_us, frame_us};
    controls.set(lc::controls::FrameDurationLimits, lc::Span<const std::int64_t, 2>(limits));
  }
  const int r = camera_->start(&controls);
  if (r < 0) {
    return CameraStatus::error(CameraError::kIo, "libcamera camera %s: start: %s", name(),
                               std::strerror(-r));
  }
  running_ = true;
  info_.interval_num = can_limit ? static_cast<std::uint32_t>(frame_us) : 0;
  info_.interval_den = can_limit ? 1'000'000u : 0;
  sequence_.reset();
  for (int i = 0; i < nslots_; ++i) {
    if (slots_[static_cast<std::size_t>(i)].held) continue;
    CameraStatus st = queue_slot(static_cast<std::uint32_t>(i), false);
    if (!st.ok()) return st;
  }
  return CameraStatus::success();
}

CameraStatus LibcameraCamera::start() {
  const LinkState s = link_state();
  if (s == LinkState::kStreaming) return CameraStatus::success();
  if (s != LinkState::kOpen) {
    return CameraStatus::error(CameraError::kBadState, "libcamera camera %s: start() in state %s",
                               name(), to_string(s));
  }
  CameraStatus st = start_streaming();
  if (!st.ok()) return st;
  set_state(LinkState::kStreaming);
  return st;
}

void LibcameraCamera::unmap(Slot& s) noexcept {
  if (s.map_base != nullptr) ::munmap(s.map_base, s.map_length);
  s.map_base = nullptr;
  s.map_length = 0;
  s.data = nullptr;
}

void LibcameraCamera::teardown() noexcept {
  if (camera_) {
    if (running_) camera_->stop();  // completes every queued request (cancelled)
    running_ = false;
    camera_->requestCompleted.disconnect(this);
    camera_->disconnected.disconnect(this);
  }
  std::uint32_t dropped = 0;
  while (completed_.pop(dropped)) {
  }
  // Mappings of frames the consumer still holds survive (a mapping keeps its dmabuf alive).
  for (Slot& s : slots_) {
    if (!s.held) unmap(s);
    s.request = nullptr;
    s.buffer = nullptr;
  }
  requests_.clear();
  if (allocator_ && stream_ != nullptr) allocator_->free(stream_);
  allocator_.reset();
  configuration_.reset();
  stream_ = nullptr;
  if (camera_ && acquired_) camera_->release();
  acquired_ = false;
  camera_.reset();
  nslots_ = 0;
}

CameraStatus LibcameraCamera::lose(const char* why) {
  teardown();
  bump(counters_.disconnects);
  backoff_.reset();
  const std::int64_t delay = backoff_.next_delay_ns();
  next_retry_ns_ = monotonic_ns() + (delay < 0 ? 0 : delay);
  set_state(LinkState::kDisconnected);
  return CameraStatus::error(CameraError::kDisconnected,
                             "libcamera camera %s lost (%s); reopening in %lld ms", name(), why,
                             static_cast<long long>(delay / 1'000'000));
}

void LibcameraCamera::take_returned() noexcept {
  std::uint32_t index = 0;
  while (returned_.pop(index)) {
    if (index >= static_cast<std::uint32_t>(kMaxSlots)) continue;
    Slot& s = slots_[index];
    if (!s.held) continue;
    s.held = false;
    --outstanding_;
    if (link_state() == LinkState::kStreaming && s.request != nullptr) {
      (void)queue_slot(index, true);  // a lost camera shows up through its signal
    } else if (s.request == nullptr) {
      unmap(s);  // its camera was torn down while the consumer held it
    }
  }
}

CameraStatus LibcameraCamera::reconnect(std::int64_t deadline_ns) {
  if (link_state() == LinkState::kFailed) {
    return CameraStatus::error(CameraError::kDisconnected,
                               "libcamera camera %s: gave up after %d reopen attempts", name(),
                               backoff_.attempts());
  }
  while (outstanding_ > 0) {
    const std::int64_t now = monotonic_ns();
    if (now >= deadline_ns) {
      return CameraStatus::error(CameraError::kDisconnected,
                                 "libcamera camera %s lost; %d frames still held block the reopen",
                                 name(), outstanding_);
    }
    sleep_until_ns(std::min(deadline_ns, now + 1'000'000));
    take_returned();
  }
  std::int64_t now = monotonic_ns();
  if (now < next_retry_ns_) {
    sleep_until_ns(std::min(deadline_ns, next_retry_ns_));
    now = monotonic_ns();
    if (now < next_retry_ns_) {
      return CameraStatus::error(CameraError::kDisconnected,
                                 "libcamera camera %s lost; reopening in %lld ms", name(),
                                 static_cast<long long>((next_retry_ns_ - now) / 1'000'000));
    }
  }
  bump(counters_.reconnect_attempts);
  lost_.store(false, std::memory_order_release);
  CameraStatus st = acquire_and_configure();
  if (st.ok()) st = start_streaming();
  if (st.ok()) {
    bump(counters_.reconnects);
    backoff_.reset();
    set_state(LinkState::kStreaming);
    return st;
  }
  teardown();
  const std::int64_t delay = backoff_.next_delay_ns();
  if (delay < 0) {
    set_state(LinkState::kFailed);
    return CameraStatus::error(CameraError::kDisconnected,
                               "libcamera camera %s: gave up after %d reopen attempts; last: %s",
                               name(), backoff_.attempts(), st.message());
  }
  next_retry_ns_ = monotonic_ns() + delay;
  return CameraStatus::error(CameraError::kDisconnected,
                             "reopen failed, next attempt in %lld ms: %s",
                             static_cast<long long>(delay / 1'000'000), st.message());
}

CameraStatus LibcameraCamera::next_frame(Frame& frame, int timeout_ms) {
  const std::int64_t deadline = deadline_after_ms(timeout_ms);
  take_returned();
  for (;;) {
    const LinkState s = link_state();
    if (s == LinkState::kDisconnected || s == LinkState::kFailed) {
      CameraStatus st = reconnect(deadline);
      if (!st.ok()) return st;
      continue;
    }
    if (s != LinkState::kStreaming) {
      return CameraStatus::error(CameraError::kBadState,
                                 "libcamera camera %s: next_frame() in state %s (call start())",
                                 name(), to_string(s));
    }
    if (lost_.exchange(false, std::memory_order_acq_rel)) {
      return lose("libcamera reported the camera disconnected");
    }

    std::uint32_t index = 0;
    if (!completed_.pop(index)) {
      pollfd p{};
      p.fd = wake_fd_;
      p.events = POLLIN;
      const int r = ::poll(&p, 1, poll_timeout_ms(deadline));
      if (r < 0 && errno != EINTR) {
        return CameraStatus::error(CameraError::kIo, "libcamera camera %s: poll: %s", name(),
                                   std::strerror(errno));
      }
      if (r > 0) {
        std::uint64_t n = 0;
        (void)!::read(wake_fd_, &n, sizeof(n));
      }
      if (r == 0 && completed_.empty() && !lost_.load(std::memory_order_acquire)) {
        bump(counters_.timeouts);
        return CameraStatus::error(CameraError::kTimeout,
                                   "libcamera camera %s: no frame within %d ms", name(),
                                   timeout_ms);
      }
      take_returned();
      continue;
    }
    if (index >= static_cast<std::uint32_t>(nslots_)) continue;
    Slot& slot = slots_[index];
    lc::Request* req = slot.request;
    if (req == nullptr || req->status() == lc::Request::RequestCancelled) continue;

    const lc::FrameMetadata& md = slot.buffer->metadata();
    const std::uint32_t missing = sequence_.update(md.sequence);
    if (missing > 0) bump(counters_.drops, missing);
    CameraStatus st;
    dsp::FrameView view;
    if (md.status != lc::FrameMetadata::FrameSuccess) {
      st = CameraStatus::error(CameraError::kCorruptFrame,
                               "libcamera camera %s: frame %u completed with an error", name(),
                               md.sequence);
    } else {
      std::size_t bytes = slot.length;
      if (!md.planes().empty()) bytes = std::min<std::size_t>(bytes, md.planes()[0].bytesused);
      st = bytes <= crop_offset_
               ? CameraStatus::error(CameraError::kCorruptFrame,
                                     "libcamera camera %s: frame %u holds %zu bytes", name(),
                                     md.sequence, bytes)
               : make_frame_view(format_, slot.data + crop_offset_, bytes - crop_offset_,
                                 cfg_.width, cfg_.height, stride_, view);
    }
    if (!st.ok()) {
      bump(counters_.corrupt);
      (void)queue_slot(index, true);
      return st;
    }

    const std::optional<std::int64_t> sensor_ts =
        req->metadata().get(lc::controls::SensorTimestamp);
    if (sensor_ts && *sensor_ts > 0) {
      frame.timestamp_ns = *sensor_ts;
      frame.timestamp_source = TimestampSource::kSensor;
    } else if (md.timestamp != 0) {
      frame.timestamp_ns = static_cast<std::int64_t>(md.timestamp);
      frame.timestamp_source = TimestampSource::kDriver;
    } else {
      frame.timestamp_ns = monotonic_ns();
      frame.timestamp_source = TimestampSource::kDequeue;
    }
    info_.timestamp_source = frame.timestamp_source;
    const std::optional<std::int64_t> duration = req->metadata().get(lc::controls::FrameDuration);
    if (duration && *duration > 0) {  // what the pipeline actually delivers, in us
      info_.interval_num = static_cast<std::uint32_t>(*duration);
      info_.interval_den = 1'000'000u;
    }
    frame.view = view;
    frame.sequence = md.sequence;
    frame.dropped_before = missing;
    frame.slot = index;
    slot.held = true;
    ++outstanding_;
    bump(counters_.frames);
    return CameraStatus::success();
  }
}

void LibcameraCamera::stop() {
  if (link_state() == LinkState::kClosed) return;
  take_returned();
  teardown();
  for (Slot& s : slots_) {
    unmap(s);
    s.held = false;
  }
  outstanding_ = 0;
  manager_.reset();
  set_state(LinkState::kClosed);
}

CameraStats LibcameraCamera::stats() const {
  CameraStats s;
  s.frames = counters_.frames.load(std::memory_order_relaxed);
  s.drops = counters_.drops.load(std::memory_order_relaxed);
  s.corrupt = counters_.corrupt.load(std::memory_order_relaxed);
  s.timeouts = counters_.timeouts.load(std::memory_order_relaxed);
  s.disconnects = counters_.disconnects.load(std::memory_order_relaxed);
  s.reconnects = counters_.reconnects.load(std::memory_order_relaxed);
  s.reconnect_attempts = counters_.reconnect_attempts.load(std::memory_order_relaxed);
  return s;
}

}  // namespace

std::unique_ptr<Camera> make_libcamera_camera(const CameraConfig& config) {
  return std::make_unique<LibcameraCamera>(config);
}

}  // namespace tacse3::hal
