// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: V4L2 capture backend for UVC sensors (mmap streaming, MJPEG decode, reconnect).
#include "tacse3/hal/camera/v4l2_camera.hpp"

#include <errno.h>
#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>

#include "tacse3/hal/camera/backoff.hpp"
#include "tacse3/hal/camera/clock.hpp"
#include "tacse3/hal/camera/formats.hpp"
#include "tacse3/hal/camera/mjpeg_decoder.hpp"
#include "tacse3/hal/camera/sequence.hpp"
#include "tacse3/hal/camera/spsc_ring.hpp"

namespace tacse3::hal {

static_assert(v4l2_fourcc::kYuyv == V4L2_PIX_FMT_YUYV);
static_assert(v4l2_fourcc::kRgb24 == V4L2_PIX_FMT_RGB24);
static_assert(v4l2_fourcc::kGrey == V4L2_PIX_FMT_GREY);
static_assert(v4l2_fourcc::kMjpeg == V4L2_PIX_FMT_MJPEG);
static_assert(v4l2_fourcc::kJpeg == V4L2_PIX_FMT_JPEG);

namespace {

constexpr int kMaxBuffers = 16;
constexpr int kMaxOffers = 32;
// Consecutive POLLERR wake-ups without a frame on a device that still answers before the
// stream is treated as lost and reopened.
constexpr int kPollErrLimit = 3;

int xioctl(int fd, unsigned long request, void* arg) noexcept {
  int r = 0;
  do {
    r = ::ioctl(fd, request, arg);
  } while (r == -1 && errno == EINTR);
  return r;
}

bool is_disconnect_errno(int e) noexcept {
  return e == ENODEV || e == ENXIO;
}

// a/b faster (shorter) than c/d.
bool shorter(const v4l2_fract& a, const FrameInterval& b) noexcept {
  return !b.known() || static_cast<std::uint64_t>(a.numerator) * b.den <
                           static_cast<std::uint64_t>(b.num) * a.denominator;
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

class V4l2Camera final : public Camera {
 public:
  explicit V4l2Camera(const CameraConfig& config) : cfg_(config), backoff_(config.reconnect) {
    copy_text(info_.backend, "v4l2");
  }
  ~V4l2Camera() override { stop(); }
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  CameraStatus open() override;
  CameraStatus start() override;
  CameraStatus next_frame(Frame& frame, int timeout_ms) override;
  void release(const Frame& frame) override;
  void stop() override;
  const CameraInfo& info() const override { return info_; }
  CameraStats stats() const override;
  LinkState link_state() const override { return state_.load(std::memory_order_acquire); }

 private:
  struct Buffer {
    std::uint8_t* addr = nullptr;
    std::size_t length = 0;
    bool held = false;  // handed to the consumer, not yet released
  };

  const char* dev() const noexcept { return cfg_.device.c_str(); }
  CameraStatus open_device();
  CameraStatus negotiate();
  CameraStatus map_buffers();
  CameraStatus start_streaming();
  CameraStatus queue_buffer(std::uint32_t index);
  void unmap(Buffer& b) noexcept;
  void close_device() noexcept;
  CameraStatus lose(int err, const char* what);
  CameraStatus reconnect(std::int64_t deadline_ns);
  void take_returned() noexcept;
  void set_state(LinkState s) noexcept { state_.store(s, std::memory_order_release); }

  CameraConfig cfg_;
  Backoff backoff_;
  SequenceTracker sequence_;
  MjpegDecoder decoder_;
  std::unique_ptr<std::uint8_t[]> decoded_;  // one decode slot per V4L2 buffer (MJPEG only)
  std::size_t decoded_capacity_ = 0;
  std::array<Buffer, kMaxBuffers> bufs_{};
  int nbufs_ = 0;
  int outstanding_ = 0;  // buffers held by the consumer
  int fd_ = -1;
  std::uint32_t fourcc_ = 0;
  bool mjpeg_ = false;
  dsp::PixelFormat format_ = dsp::PixelFormat::kGrey;
  int stride_ = 0;
  std::int64_t next_retry_ns_ = 0;
  int pollerr_streak_ = 0;
  SpscRing<std::uint32_t, 32> returned_;
  std::atomic<LinkState> state_{LinkState::kClosed};
  CameraInfo info_;
  Counters counters_;
};

CameraStatus V4l2Camera::open() {
  if (link_state() != LinkState::kClosed) {
    return CameraStatus::error(CameraError::kBadState, "V4L2 camera %s: open() called twice",
                               dev());
  }
  if (cfg_.device.empty()) {
    return CameraStatus::error(CameraError::kBadConfig,
                               "V4L2 camera: no device node configured (e.g. /dev/video0)");
  }
  CameraStatus st = validate(cfg_);
  if (!st.ok()) return st;
  st = open_device();
  if (!st.ok()) {
    close_device();
    return st;
  }
  set_state(LinkState::kOpen);
  return st;
}

CameraStatus V4l2Camera::open_device() {
  fd_ = ::open(dev(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    const int e = errno;
    switch (e) {
      case ENOENT:
        return CameraStatus::error(CameraError::kNotFound,
                                   "V4L2 camera %s: no such device node (sensor unplugged, or "
                                   "the udev rule for its name is missing)",
                                   dev());
      case ENODEV:
      case ENXIO:
        return CameraStatus::error(CameraError::kNotFound,
                                   "V4L2 camera %s: the node exists but its device is gone (%s)",
                                   dev(), std::strerror(e));
      case EACCES:
      case EPERM:
        return CameraStatus::error(CameraError::kPermission,
                                   "V4L2 camera %s: permission denied (is the user in group "
                                   "'video'?)",
                                   dev());
      case EBUSY:
        return CameraStatus::error(CameraError::kBusy, "V4L2 camera %s: device busy", dev());
      default:
        return CameraStatus::error(CameraError::kIo, "V4L2 camera %s: open failed: %s", dev(),
                                   std::strerror(e));
    }
  }
  struct stat sb {};
  if (::fstat(fd_, &sb) != 0 || !S_ISCHR(sb.st_mode)) {
    return CameraStatus::error(CameraError::kNotSupported, "V4L2 camera %s: not a character device",
                               dev());
  }
  v4l2_capability cap{};
  if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) != 0) {
    const int e = errno;
    return CameraStatus::error(CameraError::kNotSupported,
                               "V4L2 camera %s: not a V4L2 device (VIDIOC_QUERYCAP: %s)", dev(),
                               std::strerror(e));
  }
  const std::uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
  if ((caps & V4L2_CAP_VIDEO_CAPTURE) == 0) {
    if ((caps & V4L2_CAP_META_CAPTURE) != 0) {
      return CameraStatus::error(CameraError::kNotSupported,
                                 "V4L2 camera %s: a metadata node, not video capture (UVC "
                                 "cameras expose two nodes: use the other /dev/videoN)",
                                 dev());
    }
    if ((caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE) != 0) {
      return CameraStatus::error(CameraError::kNotSupported,
                                 "V4L2 camera %s: multi-planar capture (a CSI/ISP node) is not "
                                 "handled here: use the libcamera backend",
                                 dev());
    }
    return CameraStatus::error(CameraError::kNotSupported,
                               "V4L2 camera %s: not a video capture device", dev());
  }
  if ((caps & V4L2_CAP_STREAMING) == 0) {
    return CameraStatus::error(CameraError::kNotSupported,
                               "V4L2 camera %s: no streaming I/O (mmap) support", dev());
  }
  copy_text(info_.driver, reinterpret_cast<const char*>(cap.driver), sizeof(cap.driver));
  copy_text(info_.card, reinterpret_cast<const char*>(cap.card), sizeof(cap.card));

  CameraStatus st = negotiate();
  if (!st.ok()) return st;
  return map_buffers();
}

CameraStatus V4l2Camera::negotiate() {
  std::array<V4l2FormatOffer, kMaxOffers> offers{};
  std::size_t count = 0;
  for (std::uint32_t i = 0; count < offers.size(); ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd_, VIDIOC_ENUM_FMT, &d) != 0) break;
    V4l2FormatOffer& o = offers[count++];
    o.fourcc = d.pixelformat;

    // Frame sizes: discrete list, or a stepwise/continuous range. A driver that cannot
    // enumerate sizes is given the benefit of the doubt; S_FMT checks below.
    v4l2_frmsizeenum fs{};
    fs.index = 0;
    fs.pixel_format = d.pixelformat;
    if (xioctl(fd_, VIDIOC_ENUM_FRAMESIZES, &fs) != 0) {
      o.size_ok = true;
    } else if (fs.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
      for (std::uint32_t k = 0;; ++k) {
        fs.index = k;
        if (xioctl(fd_, VIDIOC_ENUM_FRAMESIZES, &fs) != 0) break;
        if (fs.discrete.width == static_cast<std::uint32_t>(cfg_.width) &&
            fs.discrete.height == static_cast<std::uint32_t>(cfg_.height)) {
          o.size_ok = true;
          break;
        }
      }
    } else {
      const auto& s = fs.stepwise;
      const auto w = static_cast<std::uint32_t>(cfg_.width);
      const auto h = static_cast<std::uint32_t>(cfg_.height);
      o.size_ok = w >= s.min_width && w <= s.max_width && h >= s.min_height && h <= s.max_height &&
                  (s.step_width == 0 || (w - s.min_width) % s.step_width == 0) &&
                  (s.step_height == 0 || (h - s.min_height) % s.step_height == 0);
    }
    if (!o.size_ok) continue;

    // Fastest frame interval at the requested size (unknown if the driver won't say).
    v4l2_frmivalenum fi{};
    fi.pixel_format = d.pixelformat;
    fi.width = static_cast<std::uint32_t>(cfg_.width);
    fi.height = static_cast<std::uint32_t>(cfg_.height);
    for (std::uint32_t k = 0; k < 64; ++k) {
      fi.index = k;
      if (xioctl(fd_, VIDIOC_ENUM_FRAMEINTERVALS, &fi) != 0) break;
      const v4l2_fract f = fi.type == V4L2_FRMIVAL_TYPE_DISCRETE ? fi.discrete : fi.stepwise.min;
      if (f.numerator != 0 && f.denominator != 0 && shorter(f, o.fastest)) {
        o.fastest.num = f.numerator;
        o.fastest.den = f.denominator;
      }
      if (fi.type != V4L2_FRMIVAL_TYPE_DISCRETE) break;
    }
  }
  if (count == 0) {
    return CameraStatus::error(CameraError::kNotSupported,
                               "V4L2 camera %s: the driver lists no capture formats", dev());
  }

  const bool allow_mjpeg = cfg_.allow_mjpeg && MjpegDecoder::available();
  const V4l2FormatChoice choice =
      choose_v4l2_format(offers.data(), count, cfg_.fps, allow_mjpeg, cfg_.mjpeg_output);
  if (!choice.found) {
    char list[160] = {};
    std::size_t used = 0;
    for (std::size_t i = 0; i < count && used + 24 < sizeof(list); ++i) {
      const int n = std::snprintf(list + used, sizeof(list) - used, "%s%s%s", i ? " " : "",
                                  fourcc_string(offers[i].fourcc).data(),
                                  offers[i].size_ok ? "" : "(no size match)");
      if (n > 0) used += static_cast<std::size_t>(n);
    }
    return CameraStatus::error(CameraError::kNotSupported,
                               "V4L2 camera %s: no usable format at %dx%d (offers: %s; usable: "
                               "YUYV RGB3 GREY%s)",
                               dev(), cfg_.width, cfg_.height, list,
                               allow_mjpeg ? " MJPG" : "; MJPEG decoding unavailable or off");
  }

  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = static_cast<std::uint32_t>(cfg_.width);
  fmt.fmt.pix.height = static_cast<std::uint32_t>(cfg_.height);
  fmt.fmt.pix.pixelformat = choice.fourcc;
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (xioctl(fd_, VIDIOC_S_FMT, &fmt) != 0) {
    const int e = errno;
    return CameraStatus::error(e == EBUSY ? CameraError::kBusy : CameraError::kIo,
                               "V4L2 camera %s: VIDIOC_S_FMT %s %dx%d: %s", dev(),
                               fourcc_string(choice.fourcc).data(), cfg_.width, cfg_.height,
                               std::strerror(e));
  }
  if (fmt.fmt.pix.pixelformat != choice.fourcc ||
      fmt.fmt.pix.width != static_cast<std::uint32_t>(cfg_.width) ||
      fmt.fmt.pix.height != static_cast<std::uint32_t>(cfg_.height)) {
    return CameraStatus::error(
        CameraError::kNotSupported, "V4L2 camera %s: asked for %s %dx%d, the driver set %s %ux%u",
        dev(), fourcc_string(choice.fourcc).data(), cfg_.width, cfg_.height,
        fourcc_string(fmt.fmt.pix.pixelformat).data(), fmt.fmt.pix.width, fmt.fmt.pix.height);
  }
  fourcc_ = choice.fourcc;
  mjpeg_ = choice.mjpeg;
  format_ = choice.output;
  stride_ = mjpeg_ ? 0 : static_cast<int>(fmt.fmt.pix.bytesperline);

  // Frame rate through the frame interval. Drivers round to what they can do; report that.
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  info_.interval_num = 0;
  info_.interval_den = 0;
  if (xioctl(fd_, VIDIOC_G_PARM, &parm) == 0) {
    if ((parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME) != 0) {
      parm.parm.capture.timeperframe.numerator = 1;
      parm.parm.capture.timeperframe.denominator = static_cast<std::uint32_t>(cfg_.fps);
      if (xioctl(fd_, VIDIOC_S_PARM, &parm) != 0) {
        const int e = errno;
        return CameraStatus::error(CameraError::kIo, "V4L2 camera %s: VIDIOC_S_PARM %d fps: %s",
                                   dev(), cfg_.fps, std::strerror(e));
      }
    }
    info_.interval_num = parm.parm.capture.timeperframe.numerator;
    info_.interval_den = parm.parm.capture.timeperframe.denominator;
  }

  if (mjpeg_) {
    CameraStatus st = decoder_.init(cfg_.width, cfg_.height, cfg_.mjpeg_output);
    if (!st.ok()) return st;
  }
  info_.fourcc = {};
  copy_text(info_.fourcc, fourcc_string(fourcc_).data());
  info_.format = format_;
  info_.width = cfg_.width;
  info_.height = cfg_.height;
  info_.stride_bytes = mjpeg_ ? decoder_.output_stride() : stride_;
  info_.decoded = mjpeg_;
  return CameraStatus::success();
}

CameraStatus V4l2Camera::map_buffers() {
  v4l2_requestbuffers req{};
  req.count = static_cast<std::uint32_t>(cfg_.buffer_count);
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_REQBUFS, &req) != 0) {
    const int e = errno;
    return CameraStatus::error(e == EBUSY ? CameraError::kBusy : CameraError::kNotSupported,
                               "V4L2 camera %s: VIDIOC_REQBUFS %d mmap buffers: %s", dev(),
                               cfg_.buffer_count, std::strerror(e));
  }
  if (req.count < 2) {
    return CameraStatus::error(CameraError::kNotSupported,
                               "V4L2 camera %s: the driver granted %u buffers, need at least 2",
                               dev(), req.count);
  }
  nbufs_ = std::min(static_cast<int>(req.count), kMaxBuffers);
  for (int i = 0; i < nbufs_; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = static_cast<std::uint32_t>(i);
    if (xioctl(fd_, VIDIOC_QUERYBUF, &b) != 0) {
      const int e = errno;
      return CameraStatus::error(CameraError::kIo, "V4L2 camera %s: VIDIOC_QUERYBUF %d: %s", dev(),
                                 i, std::strerror(e));
    }
    void* p = ::mmap(nullptr, b.length, PROT_READ, MAP_SHARED, fd_, b.m.offset);
    if (p == MAP_FAILED) {
      const int e = errno;
      return CameraStatus::error(CameraError::kIo, "V4L2 camera %s: mmap buffer %d: %s", dev(), i,
                                 std::strerror(e));
    }
    bufs_[static_cast<std::size_t>(i)].addr = static_cast<std::uint8_t*>(p);
    bufs_[static_cast<std::size_t>(i)].length = b.length;
    bufs_[static_cast<std::size_t>(i)].held = false;
  }
  info_.buffer_count = nbufs_;

  if (mjpeg_) {
    const std::size_t need = decoder_.output_bytes() * static_cast<std::size_t>(nbufs_);
    if (decoded_capacity_ < need) {  // at open, or a reconnect that grew the buffer count
      decoded_.reset(new (std::nothrow) std::uint8_t[need]);
      decoded_capacity_ = decoded_ ? need : 0;
      if (!decoded_) {
        return CameraStatus::error(CameraError::kIo,
                                   "V4L2 camera %s: cannot allocate %zu bytes of MJPEG output",
                                   dev(), need);
      }
    }
  }
  return CameraStatus::success();
}

CameraStatus V4l2Camera::queue_buffer(std::uint32_t index) {
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  b.index = index;
  if (xioctl(fd_, VIDIOC_QBUF, &b) != 0) {
    const int e = errno;
    return CameraStatus::error(
        is_disconnect_errno(e) ? CameraError::kDisconnected : CameraError::kIo,
        "V4L2 camera %s: VIDIOC_QBUF %u: %s", dev(), index, std::strerror(e));
  }
  return CameraStatus::success();
}

CameraStatus V4l2Camera::start_streaming() {
  for (int i = 0; i < nbufs_; ++i) {
    if (bufs_[static_cast<std::size_t>(i)].held) continue;
    CameraStatus st = queue_buffer(static_cast<std::uint32_t>(i));
    if (!st.ok()) return st;
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_STREAMON, &type) != 0) {
    const int e = errno;
    return CameraStatus::error(CameraError::kIo, "V4L2 camera %s: VIDIOC_STREAMON: %s", dev(),
                               std::strerror(e));
  }
  sequence_.reset();
  pollerr_streak_ = 0;
  return CameraStatus::success();
}

CameraStatus V4l2Camera::start() {
  const LinkState s = link_state();
  if (s == LinkState::kStreaming) return CameraStatus::success();
  if (s != LinkState::kOpen) {
    return CameraStatus::error(CameraError::kBadState, "V4L2 camera %s: start() in state %s", dev(),
                               to_string(s));
  }
  CameraStatus st = start_streaming();
  if (!st.ok()) return st;
  set_state(LinkState::kStreaming);
  return st;
}

void V4l2Camera::unmap(Buffer& b) noexcept {
  if (b.addr != nullptr) ::munmap(b.addr, b.length);
  b.addr = nullptr;
  b.length = 0;
}

void V4l2Camera::close_device() noexcept {
  if (fd_ >= 0) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    xioctl(fd_, VIDIOC_STREAMOFF, &type);
  }
  for (Buffer& b : bufs_) {
    unmap(b);
    b.held = false;
  }
  if (fd_ >= 0) {
    v4l2_requestbuffers req{};
    req.count = 0;
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    xioctl(fd_, VIDIOC_REQBUFS, &req);
    ::close(fd_);
    fd_ = -1;
  }
  nbufs_ = 0;
  outstanding_ = 0;
}

CameraStatus V4l2Camera::lose(int err, const char* what) {
  // The device is gone or its stream is broken. Close it now; buffers the consumer still holds
  // stay mapped (a mapping outlives the fd) until they are released.
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (fd_ >= 0) xioctl(fd_, VIDIOC_STREAMOFF, &type);
  for (Buffer& b : bufs_) {
    if (!b.held) unmap(b);
  }
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  bump(counters_.disconnects);
  backoff_.reset();
  const std::int64_t delay = backoff_.next_delay_ns();
  next_retry_ns_ = monotonic_ns() + (delay < 0 ? 0 : delay);
  set_state(LinkState::kDisconnected);
  return CameraStatus::error(CameraError::kDisconnected,
                             "V4L2 camera %s lost (%s: %s); reopening in %lld ms", dev(), what,
                             std::strerror(err), static_cast<long long>(delay / 1'000'000));
}

void V4l2Camera::take_returned() noexcept {
  std::uint32_t index = 0;
  while (returned_.pop(index)) {
    if (index >= static_cast<std::uint32_t>(kMaxBuffers)) continue;
    Buffer& b = bufs_[index];
    if (!b.held) continue;  // double release: ignore
    b.held = false;
    --outstanding_;
    if (link_state() == LinkState::kStreaming && fd_ >= 0) {
      // A failure here (device gone) shows up on the next poll/DQBUF.
      (void)queue_buffer(index);
    } else if (fd_ < 0) {
      unmap(b);
    }
  }
}

CameraStatus V4l2Camera::reconnect(std::int64_t deadline_ns) {
  if (link_state() == LinkState::kFailed) {
    return CameraStatus::error(CameraError::kDisconnected,
                               "V4L2 camera %s: gave up after %d reopen attempts", dev(),
                               backoff_.attempts());
  }
  // Wait (bounded by the deadline) for the consumer to hand back frames of the old stream.
  while (outstanding_ > 0) {
    const std::int64_t now = monotonic_ns();
    if (now >= deadline_ns) {
      return CameraStatus::error(CameraError::kDisconnected,
                                 "V4L2 camera %s lost; %d frames still held block the reopen",
                                 dev(), outstanding_);
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
                                 "V4L2 camera %s lost; reopening in %lld ms", dev(),
                                 static_cast<long long>((next_retry_ns_ - now) / 1'000'000));
    }
  }
  bump(counters_.reconnect_attempts);
  close_device();
  CameraStatus st = open_device();
  if (st.ok()) st = start_streaming();
  if (st.ok()) {
    bump(counters_.reconnects);
    backoff_.reset();
    set_state(LinkState::kStreaming);
    return st;
  }
  close_device();
  const std::int64_t delay = backoff_.next_delay_ns();
  if (delay < 0) {
    set_state(LinkState::kFailed);
    return CameraStatus::error(CameraError::kDisconnected,
                               "V4L2 camera %s: gave up after %d reopen attempts; last: %s", dev(),
                               backoff_.attempts(), st.message());
  }
  next_retry_ns_ = monotonic_ns() + delay;
  CameraStatus out =
      CameraStatus::error(CameraError::kDisconnected, "reopen failed, next attempt in %lld ms: %s",
                          static_cast<long long>(delay / 1'000'000), st.message());
  return out;
}

CameraStatus V4l2Camera::next_frame(Frame& frame, int timeout_ms) {
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
                                 "V4L2 camera %s: next_frame() in state %s (call start())", dev(),
                                 to_string(s));
    }
    if (outstanding_ >= nbufs_) {
      // Every buffer is with the consumer: nothing can be captured until one comes back.
      const std::int64_t now = monotonic_ns();
      if (now >= deadline) {
        bump(counters_.timeouts);
        return CameraStatus::error(CameraError::kTimeout,
                                   "V4L2 camera %s: all %d buffers are held by the consumer", dev(),
                                   nbufs_);
      }
      sleep_until_ns(std::min(deadline, now + 1'000'000));
      take_returned();
      continue;
    }

    pollfd p{};
    p.fd = fd_;
    p.events = POLLIN;
    const int r = ::poll(&p, 1, poll_timeout_ms(deadline));
    if (r < 0) {
      if (errno == EINTR) continue;
      const int e = errno;
      return CameraStatus::error(CameraError::kIo, "V4L2 camera %s: poll: %s", dev(),
                                 std::strerror(e));
    }
    if (r == 0) {
      bump(counters_.timeouts);
      return CameraStatus::error(CameraError::kTimeout, "V4L2 camera %s: no frame within %d ms",
                                 dev(), timeout_ms);
    }
    if ((p.revents & POLLNVAL) != 0) return lose(EBADF, "poll");

    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_, VIDIOC_DQBUF, &b) != 0) {
      const int e = errno;
      if (is_disconnect_errno(e)) return lose(e, "VIDIOC_DQBUF");
      if (e == EAGAIN) {
        if ((p.revents & (POLLERR | POLLHUP)) == 0) continue;  // spurious wake-up
        // POLLERR with nothing to dequeue: the device is gone, or its queue is in error.
        v4l2_capability cap{};
        if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) != 0 && is_disconnect_errno(errno)) {
          return lose(ENODEV, "poll");
        }
        if (++pollerr_streak_ >= kPollErrLimit) return lose(EIO, "poll reports a stream error");
        continue;
      }
      if (e == EIO) {  // a transient capture error; the driver may have consumed a buffer
        bump(counters_.corrupt);
        return CameraStatus::error(CameraError::kCorruptFrame, "V4L2 camera %s: VIDIOC_DQBUF: %s",
                                   dev(), std::strerror(e));
      }
      return CameraStatus::error(CameraError::kIo, "V4L2 camera %s: VIDIOC_DQBUF: %s", dev(),
                                 std::strerror(e));
    }
    pollerr_streak_ = 0;
    if (b.index >= static_cast<std::uint32_t>(nbufs_)) {  // beyond what we track: give it back
      (void)queue_buffer(b.index);
      continue;
    }
    const std::uint32_t missing = sequence_.update(b.sequence);
    if (missing > 0) bump(counters_.drops, missing);
    Buffer& buf = bufs_[b.index];

    CameraStatus st;
    dsp::FrameView view;
    if ((b.flags & V4L2_BUF_FLAG_ERROR) != 0 || b.bytesused == 0) {
      st = CameraStatus::error(CameraError::kCorruptFrame,
                               "V4L2 camera %s: frame %u flagged bad by the driver (%u bytes)",
                               dev(), b.sequence, b.bytesused);
    } else if (mjpeg_) {
      std::uint8_t* slot = decoded_.get() + decoder_.output_bytes() * b.index;
      st = decoder_.decode(buf.addr, std::min<std::size_t>(b.bytesused, buf.length), slot,
                           decoder_.output_bytes(), view);
    } else {
      st = make_frame_view(format_, buf.addr, std::min<std::size_t>(b.bytesused, buf.length),
                           cfg_.width, cfg_.height, stride_, view);
    }
    if (!st.ok()) {
      bump(counters_.corrupt);
      (void)queue_buffer(b.index);
      return st;
    }

    const std::uint32_t ts_kind = b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK;
    if (ts_kind == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC &&
        (b.timestamp.tv_sec != 0 || b.timestamp.tv_usec != 0)) {
      frame.timestamp_ns = static_cast<std::int64_t>(b.timestamp.tv_sec) * 1'000'000'000 +
                           static_cast<std::int64_t>(b.timestamp.tv_usec) * 1'000;
      frame.timestamp_source = TimestampSource::kDriver;
    } else {
      frame.timestamp_ns = monotonic_ns();
      frame.timestamp_source = TimestampSource::kDequeue;
    }
    info_.timestamp_source = frame.timestamp_source;
    frame.view = view;
    frame.sequence = b.sequence;
    frame.dropped_before = missing;
    frame.slot = b.index;
    buf.held = true;
    ++outstanding_;
    bump(counters_.frames);
    return CameraStatus::success();
  }
}

void V4l2Camera::release(const Frame& frame) {
  // Never blocks: the capture thread requeues it on its next call. Capacity covers every buffer.
  (void)returned_.push(frame.slot);
}

void V4l2Camera::stop() {
  if (link_state() == LinkState::kClosed) return;
  take_returned();
  close_device();
  set_state(LinkState::kClosed);
}

CameraStats V4l2Camera::stats() const {
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

std::unique_ptr<Camera> make_v4l2_camera(const CameraConfig& config) {
  return std::make_unique<V4l2Camera>(config);
}

}  // namespace tacse3::hal
