// SPDX-License-Identifier: Apache-2.0
// tacse3-v4l2-feed: plays a recording's two pads into two v4l2loopback devices (VM scenario 7).
//
// Usage: tacse3-v4l2-feed --rec DIR --left DEV --right DEV [--slowdown K] [--stamp sim|write]
//                         [--go FILE] [--hold-s S]
//
// All frames are decoded into memory first (PNG decoding under TCG would otherwise set the pace).
// Both devices get the output format of the recording (GREY or RGB24, its size) and 4 mmap
// buffers. Until FILE exists (--go), the first frame is repeated at the recording's rate, so a
// capturing daemon can start and take it as its undeformed reference; then every frame is played
// once, at the recording's rate divided by K (the emulated pipeline may not keep up with 120 Hz),
// and the last frame is held for S seconds. --stamp write (default) leaves the stamp to
// v4l2loopback (the write time); with --stamp sim each buffer carries the recording's own time on
// CLOCK_MONOTONIC (v4l2loopback 0.12.7 keeps a timestamp set by the writer, but flags no clock, so
// tacse3's V4L2 backend ignores it and stamps at dequeue: the VM scenarios use the default).
// Prints "feed: played N frames ..." on stderr; exit 0, or 1 with a message naming the device.
#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <string>
#include <vector>

#include "tacse3/recording/recording.hpp"

namespace {

namespace rec = tacse3::recording;
constexpr int kBuffers = 4;

struct Options {
  std::string rec_dir, left, right, go_file;
  double slowdown = 1.0;
  bool sim_stamps = false;
  double hold_s = 2.0;
};

std::int64_t now_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

void sleep_until_ns(std::int64_t t) {
  timespec ts{static_cast<time_t>(t / 1000000000), static_cast<long>(t % 1000000000)};
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

int xioctl(int fd, unsigned long req, void* arg) {
  int r = 0;
  do {
    r = ::ioctl(fd, req, arg);
  } while (r < 0 && errno == EINTR);
  return r;
}

// One v4l2loopback output: format set, buffers mapped, streaming.
class Output {
 public:
  Output() = default;
  Output(const Output&) = delete;
  Output& operator=(const Output&) = delete;
  ~Output() {
    for (auto& b : maps_)
      if (b.data != nullptr) ::munmap(b.data, b.length);
    if (fd_ >= 0) ::close(fd_);
  }

  // Returns an empty string or the error, naming the device.
  std::string open(const std::string& dev, int width, int height, int channels, int fps) {
    dev_ = dev;
    fd_ = ::open(dev.c_str(), O_RDWR);
    if (fd_ < 0) return errno_error("open");
    v4l2_format fmt{};
    fmt.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    fmt.fmt.pix.width = static_cast<std::uint32_t>(width);
    fmt.fmt.pix.height = static_cast<std::uint32_t>(height);
    fmt.fmt.pix.pixelformat = channels == 1 ? V4L2_PIX_FMT_GREY : V4L2_PIX_FMT_RGB24;
    fmt.fmt.pix.field = V4L2_FIELD_NONE;
    fmt.fmt.pix.bytesperline = static_cast<std::uint32_t>(width * channels);
    fmt.fmt.pix.sizeimage = static_cast<std::uint32_t>(width * height * channels);
    if (xioctl(fd_, VIDIOC_S_FMT, &fmt) < 0) return errno_error("VIDIOC_S_FMT");
    if (fmt.fmt.pix.width != static_cast<std::uint32_t>(width) ||
        fmt.fmt.pix.height != static_cast<std::uint32_t>(height)) {
      return dev + ": the device took " + std::to_string(fmt.fmt.pix.width) + "x" +
             std::to_string(fmt.fmt.pix.height) + " for a " + std::to_string(width) + "x" +
             std::to_string(height) + " output format";
    }
    size_ = fmt.fmt.pix.sizeimage;
    // The capture side reports this rate (VIDIOC_G_PARM) to a reader that checks it.
    v4l2_streamparm parm{};
    parm.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    parm.parm.output.timeperframe = {1, static_cast<std::uint32_t>(fps)};
    if (xioctl(fd_, VIDIOC_S_PARM, &parm) < 0) return errno_error("VIDIOC_S_PARM");
    v4l2_requestbuffers req{};
    req.count = kBuffers;
    req.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    req.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_, VIDIOC_REQBUFS, &req) < 0) return errno_error("VIDIOC_REQBUFS");
    if (req.count < 2) return dev + ": only " + std::to_string(req.count) + " output buffers";
    maps_.resize(req.count);
    for (std::uint32_t i = 0; i < req.count; ++i) {
      v4l2_buffer b = out_buffer(i);
      if (xioctl(fd_, VIDIOC_QUERYBUF, &b) < 0) return errno_error("VIDIOC_QUERYBUF");
      void* p = ::mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
      if (p == MAP_FAILED) return errno_error("mmap");
      maps_[i] = {p, b.length};
      if (b.length < size_) return dev + ": buffer shorter than a frame";
    }
    int type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    if (xioctl(fd_, VIDIOC_STREAMON, &type) < 0) return errno_error("VIDIOC_STREAMON");
    return {};
  }

  // Queues one frame; stamp_ns 0 lets v4l2loopback stamp it.
  std::string put(const std::vector<std::uint8_t>& pixels, std::int64_t stamp_ns) {
    const std::uint32_t i = next_++ % static_cast<std::uint32_t>(maps_.size());
    std::memcpy(maps_[i].data, pixels.data(), size_);
    v4l2_buffer b = out_buffer(i);
    b.bytesused = size_;
    b.field = V4L2_FIELD_NONE;
    b.timestamp.tv_sec = static_cast<time_t>(stamp_ns / 1000000000);
    b.timestamp.tv_usec = static_cast<suseconds_t>((stamp_ns % 1000000000) / 1000);
    if (xioctl(fd_, VIDIOC_QBUF, &b) < 0) return errno_error("VIDIOC_QBUF");
    // v4l2loopback hands an output buffer back at once; take it so the queue never fills.
    v4l2_buffer d = out_buffer(0);
    if (xioctl(fd_, VIDIOC_DQBUF, &d) < 0) return errno_error("VIDIOC_DQBUF");
    return {};
  }

 private:
  // "<device>: <what>: <errno text>" for a failed call.
  std::string errno_error(const char* what) const {
    return dev_ + ": " + what + ": " + std::strerror(errno);
  }
  // A buffer descriptor of the output queue.
  static v4l2_buffer out_buffer(std::uint32_t index) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = index;
    return b;
  }
  struct Map {
    void* data = nullptr;
    std::size_t length = 0;
  };
  std::string dev_;
  int fd_ = -1;
  std::uint32_t size_ = 0;
  std::uint32_t next_ = 0;
  std::vector<Map> maps_;
};

int usage(const char* msg) {
  std::fprintf(stderr,
               "tacse3-v4l2-feed: %s\nusage: tacse3-v4l2-feed --rec DIR --left DEV --right DEV "
               "[--slowdown K] [--stamp sim|write] [--go FILE] [--hold-s S]\n",
               msg);
  return 2;
}

bool parse(int argc, char** argv, Options* o, std::string* err) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) {
      *err = "missing value after " + a;
      return false;
    }
    const std::string v = argv[++i];
    char* end = nullptr;
    if (a == "--rec") {
      o->rec_dir = v;
    } else if (a == "--left") {
      o->left = v;
    } else if (a == "--right") {
      o->right = v;
    } else if (a == "--go") {
      o->go_file = v;
    } else if (a == "--stamp" && (v == "sim" || v == "write")) {
      o->sim_stamps = v == "sim";
    } else if (a == "--slowdown" && (o->slowdown = std::strtod(v.c_str(), &end), *end == '\0') &&
               o->slowdown >= 1.0 && o->slowdown <= 100.0) {
    } else if (a == "--hold-s" && (o->hold_s = std::strtod(v.c_str(), &end), *end == '\0') &&
               o->hold_s >= 0.0) {
    } else {
      *err = "bad option or value: " + a + " " + v;
      return false;
    }
  }
  if (o->rec_dir.empty() || o->left.empty() || o->right.empty()) {
    *err = "--rec, --left and --right are required";
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  std::string err;
  if (!parse(argc, argv, &o, &err)) return usage(err.c_str());

  auto opened = rec::RecordingReader::open(o.rec_dir);
  if (!opened) {
    std::fprintf(stderr, "tacse3-v4l2-feed: %s\n", opened.status().message().c_str());
    return 1;
  }
  const rec::RecordingReader& r = opened.value();
  const int sl = r.slot_of(rec::SensorId::kLeft), sr = r.slot_of(rec::SensorId::kRight);
  if (sl < 0 || sr < 0 || r.frame_count() < 2) {
    std::fprintf(stderr, "tacse3-v4l2-feed: %s: needs a two-sensor recording of >= 2 frames\n",
                 o.rec_dir.c_str());
    return 1;
  }
  const std::size_t n = r.frame_count();
  std::array<std::vector<std::vector<std::uint8_t>>, 2> frames;
  int channels = 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (int side = 0; side < 2; ++side) {
      rec::Image im;
      const rec::Status s = r.read_image(static_cast<std::size_t>(side == 0 ? sl : sr), i, &im);
      if (!s) {
        std::fprintf(stderr, "tacse3-v4l2-feed: %s\n", s.message().c_str());
        return 1;
      }
      channels = im.channels;
      frames[static_cast<std::size_t>(side)].push_back(std::move(im.pixels));
    }
  }
  const int w = r.info().width, h = r.info().height;
  const int fps = std::max(1, static_cast<int>(r.info().fps + 0.5));
  std::array<Output, 2> out;
  for (int side = 0; side < 2; ++side) {
    const std::string e =
        out[static_cast<std::size_t>(side)].open(side == 0 ? o.left : o.right, w, h, channels, fps);
    if (!e.empty()) {
      std::fprintf(stderr, "tacse3-v4l2-feed: %s\n", e.c_str());
      return 1;
    }
  }
  std::fprintf(stderr, "feed: %zu frames %dx%d %s loaded from %s; slowdown %.1f, %s stamps\n", n, w,
               h, channels == 1 ? "GREY" : "RGB24", o.rec_dir.c_str(), o.slowdown,
               o.sim_stamps ? "recording" : "write-time");

  const std::int64_t period_ns = (r.t_ns(n - 1) - r.t_ns(0)) / static_cast<std::int64_t>(n - 1);
  const auto wall_period = static_cast<std::int64_t>(static_cast<double>(period_ns) * o.slowdown);
  auto put_both = [&](std::size_t i, std::int64_t stamp) -> bool {
    for (std::size_t side = 0; side < 2; ++side) {
      const std::string e = out[side].put(frames[side][i], o.sim_stamps ? stamp : 0);
      if (!e.empty()) {
        std::fprintf(stderr, "tacse3-v4l2-feed: %s\n", e.c_str());
        return false;
      }
    }
    return true;
  };

  // Hold the first frame until the go file appears.
  std::int64_t t = now_ns(), stamp = t;
  std::size_t held = 0;
  while (!o.go_file.empty() && !std::filesystem::exists(o.go_file)) {
    if (!put_both(0, stamp)) return 1;
    ++held;
    t += wall_period;
    stamp += period_ns;
    sleep_until_ns(t);
  }
  // Play: the wall clock paces at period x slowdown, the stamps follow the recording.
  const std::int64_t t_play = now_ns(), base_stamp = std::max(stamp, t_play);
  std::int64_t late = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t due =
        t_play + static_cast<std::int64_t>(static_cast<double>(r.t_ns(i) - r.t_ns(0)) * o.slowdown);
    if (now_ns() > due + wall_period) ++late;
    sleep_until_ns(due);
    stamp = base_stamp + (r.t_ns(i) - r.t_ns(0));
    if (!put_both(i, stamp)) return 1;
  }
  const std::int64_t t_end = now_ns();
  // Hold the last frame so the pipeline settles on the final pose.
  const auto hold_frames =
      static_cast<std::int64_t>(o.hold_s * 1e9 / static_cast<double>(wall_period));
  t = t_end;
  for (std::int64_t k = 0; k < hold_frames; ++k) {
    t += wall_period;
    stamp += period_ns;
    sleep_until_ns(t);
    if (!put_both(n - 1, stamp)) return 1;
  }
  std::fprintf(stderr,
               "feed: held frame 0 x%zu, played %zu frames in %.3f s (%zu late by more than a "
               "period), held the last x%lld\n",
               held, n, static_cast<double>(t_end - t_play) * 1e-9, static_cast<std::size_t>(late),
               static_cast<long long>(hold_frames));
  return 0;
}
