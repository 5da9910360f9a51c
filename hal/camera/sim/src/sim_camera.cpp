// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: the live `sim` camera backend (shared simulation, paced rendering, fault injection).
#include "tacse3/hal/camera/sim_camera.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <span>

#include "tacse3/hal/camera/clock.hpp"
#include "tacse3/hal/camera/spsc_ring.hpp"
#include "tacse3/sim/arm_log.hpp"
#include "tacse3/sim/simulator.hpp"

namespace tacse3::hal {

namespace {

constexpr int kMaxBuffers = 16;
// While unplugged or held up, next_frame() re-checks the fault flags this often.
constexpr std::int64_t kPollNs = 1'000'000;

void bump(std::atomic<std::uint64_t>& c, std::uint64_t n = 1) noexcept {
  c.fetch_add(n, std::memory_order_relaxed);
}

void copy_text(char* dst, std::size_t cap, const char* src) noexcept {
  std::snprintf(dst, cap, "%s", src);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// SimRig

std::shared_ptr<SimRig> SimRig::create(const SimRigConfig& config, std::string* error) {
  auto fail = [&](std::string msg) -> std::shared_ptr<SimRig> {
    if (error) *error = std::move(msg);
    return nullptr;
  };
  const SimSceneConfig& sc = config.scene;
  if (config.fps < 1 || config.fps > 1000) {
    return fail("[sim] fps " + std::to_string(config.fps) + ": must be within 1..1000");
  }
  sim::SimConfig cfg;
  if (!sim::object_preset(sc.object, &cfg.scenario.object)) {
    return fail("[sim] object \"" + sc.object + "\": unknown; one of " +
                sim::object_preset_names());
  }
  if (!sim::parse_axis(sc.motion, &cfg.scenario.axis)) {
    return fail("[sim] motion \"" + sc.motion + "\": must be rx, ry, rz, tx or ty");
  }
  if (sc.regime == "stick") {
    cfg.scenario.regime = sim::Regime::kStick;
  } else if (sc.regime == "slide") {
    cfg.scenario.regime = sim::Regime::kSlide;
  } else {
    return fail("[sim] regime \"" + sc.regime + "\": must be stick or slide");
  }
  if (!std::isfinite(sc.magnitude)) return fail("[sim] magnitude: must be a finite number");
  cfg.scenario.magnitude = sc.magnitude;
  cfg.scenario.loop = sc.repeat;
  // With repeat the pads open again at the end of each cycle, so every cycle starts with a
  // clean no-contact reference (the daemon's tare) as a real grasp-and-release would.
  cfg.scenario.release_s = sc.repeat ? 0.3 : 0.0;
  cfg.scenario.fps = static_cast<double>(config.fps);
  cfg.seed = sc.seed;
  cfg.scenario.object.seed = sc.seed;
  cfg.rig.width = config.width;
  cfg.rig.height = config.height;
  if (sc.finger_separation_mm < 0.0 || !std::isfinite(sc.finger_separation_mm)) {
    return fail("[sim] finger separation: must be >= 0 mm");
  }
  if (sc.finger_separation_mm > 0.0) {
    std::string e;
    if (!sim::fit_object_to_separation(&cfg, sc.finger_separation_mm, &e)) {
      return fail("[sim] object \"" + sc.object + "\" at finger separation " +
                  std::to_string(sc.finger_separation_mm) + " mm: " + e);
    }
  }
  std::string e;
  std::unique_ptr<sim::Simulator> s = sim::Simulator::create(cfg, &e);
  if (!s) return fail("[sim] simulator: " + e);
  std::shared_ptr<SimRig> rig(new SimRig());
  rig->config_ = config;
  rig->sim_ = std::move(s);
  if (!sc.plan.empty() && !rig->load_plan(cfg, &e)) return fail(e);
  return rig;
}

SimRig::~SimRig() = default;

double SimRig::finger_separation_mm() const {
  return sim_->finger_separation_mm();
}

std::int64_t SimRig::grid_time_ns(std::int64_t k) const noexcept {
  // Same rounding as sim::Scenario::frame_time_ns, without its int index limit.
  return std::llround(static_cast<double>(k) * 1e9 / static_cast<double>(config_.fps));
}

sim::Pose SimRig::truth(std::int64_t timestamp_ns) const noexcept {
  if (has_plan()) {
    const std::int64_t t_sim = sim_time_ns(timestamp_ns);
    const double k = std::floor(static_cast<double>(t_sim) * config_.fps * 1e-9 + 1e-6);
    const Segment seg = segments_[segment_at(static_cast<std::int64_t>(k))];
    return motion_truth(seg.motion, seg.start_grid, t_sim);
  }
  return sim_->truth(sim_time_ns(timestamp_ns));
}

sim::Twist SimRig::truth_twist(std::int64_t timestamp_ns) const noexcept {
  return has_plan() ? sim::Twist{} : sim_->truth_twist(sim_time_ns(timestamp_ns));
}

std::int64_t SimRig::start_clock() noexcept {
  std::int64_t t0 = t0_.load(std::memory_order_acquire);
  if (t0 != 0) return t0;
  // One period of lead: the first frame is rendered and then waited for, like any other.
  const std::int64_t mine = monotonic_ns() + period_ns();
  if (t0_.compare_exchange_strong(t0, mine, std::memory_order_acq_rel)) return mine;
  return t0;  // the other camera won the race
}

std::unique_ptr<SimCamera> SimRig::make_camera(const SimCameraConfig& config) {
  return std::unique_ptr<SimCamera>(new SimCamera(shared_from_this(), config));
}

// ---------------------------------------------------------------------------------------------
// SimCamera

struct SimCamera::Impl {
  std::unique_ptr<std::uint8_t[]> pixels;  // buffer_count frames, allocated in open()
  std::size_t frame_bytes = 0;
  int channels = 3;
  int nbufs = 0;
  std::array<bool, kMaxBuffers> held{};
  int outstanding = 0;
  SpscRing<std::uint32_t, kMaxBuffers> returned;  // release() -> capture thread

  std::int64_t grid = 0;            // next grid frame to deliver
  std::uint32_t seq = 0;            // next sequence number
  bool resync = false;              // after a stall/replug: jump the grid to the wall clock
  std::uint32_t carry_dropped = 0;  // skipped before a call that then timed out
  std::int64_t pending_grid = -1;   // grid slot already rendered into pending_slot
  int pending_slot = 0;

  struct {
    std::atomic<std::uint64_t> frames{0}, drops{0}, corrupt{0}, timeouts{0}, disconnects{0},
        reconnects{0}, reconnect_attempts{0};
  } n;
};

SimCamera::SimCamera(std::shared_ptr<SimRig> rig, const SimCameraConfig& config)
    : rig_(std::move(rig)), cfg_(config), impl_(std::make_unique<Impl>()) {
  copy_text(info_.backend.data(), info_.backend.size(), "sim");
  copy_text(info_.driver.data(), info_.driver.size(), "tacse3_sim");
  std::snprintf(info_.card.data(), info_.card.size(), "simulated %s pad",
                sim::to_string(cfg_.sensor));
}

SimCamera::~SimCamera() {
  stop();
}

void SimCamera::stall_for_ms(int ms) noexcept {
  const std::int64_t until =
      monotonic_ns() + static_cast<std::int64_t>(std::max(ms, 0)) * 1'000'000;
  // Keep the later of an already pending stall and this one.
  std::int64_t cur = stall_until_ns_.load(std::memory_order_acquire);
  while (cur < until && !stall_until_ns_.compare_exchange_weak(cur, until)) {
  }
}

CameraStatus SimCamera::open() {
  const char* side = sim::to_string(cfg_.sensor);
  if (link_state() != LinkState::kClosed) {
    return CameraStatus::error(CameraError::kBadState, "sim camera %s: open() called twice", side);
  }
  if (cfg_.format != dsp::PixelFormat::kRgb888 && cfg_.format != dsp::PixelFormat::kGrey) {
    return CameraStatus::error(CameraError::kBadConfig,
                               "sim camera %s: pixel format must be RGB888 or GREY", side);
  }
  if (cfg_.buffer_count < 2 || cfg_.buffer_count > kMaxBuffers) {
    return CameraStatus::error(CameraError::kBadConfig,
                               "sim camera %s: buffer_count %d: must be within 2..%d", side,
                               cfg_.buffer_count, kMaxBuffers);
  }
  const SimRigConfig& rc = rig_->config();
  Impl& m = *impl_;
  m.channels = cfg_.format == dsp::PixelFormat::kRgb888 ? 3 : 1;
  m.frame_bytes = rig_->simulator().frame_bytes(m.channels);
  m.nbufs = cfg_.buffer_count;
  m.pixels.reset(new std::uint8_t[m.frame_bytes * static_cast<std::size_t>(m.nbufs)]());
  m.held.fill(false);
  m.outstanding = 0;

  info_.format = cfg_.format;
  copy_text(info_.fourcc.data(), info_.fourcc.size(), m.channels == 3 ? "RGB3" : "GREY");
  info_.width = rc.width;
  info_.height = rc.height;
  info_.stride_bytes = rc.width * m.channels;
  info_.buffer_count = m.nbufs;
  info_.decoded = false;
  info_.interval_num = 1;
  info_.interval_den = static_cast<std::uint32_t>(rc.fps);
  info_.timestamp_source = TimestampSource::kSimulated;
  state_.store(LinkState::kOpen, std::memory_order_release);
  return CameraStatus::success();
}

CameraStatus SimCamera::start() {
  if (link_state() != LinkState::kOpen) {
    return CameraStatus::error(CameraError::kBadState, "sim camera %s: start() in state %s",
                               sim::to_string(cfg_.sensor), to_string(link_state()));
  }
  Impl& m = *impl_;
  const std::int64_t t0 = rig_->start_clock();
  rig_->restart_pad(cfg_.sensor);
  m.grid = 0;
  m.seq = 0;
  m.carry_dropped = 0;
  m.pending_grid = -1;
  // A camera started after the other one has been streaming for a while joins the grid at the
  // present instead of replaying the past (realtime only; fast mode always starts at frame 0).
  m.resync = rig_->config().scene.realtime && monotonic_ns() > t0;
  state_.store(LinkState::kStreaming, std::memory_order_release);
  return CameraStatus::success();
}

CameraStats SimCamera::stats() const {
  const Impl& m = *impl_;
  CameraStats s;
  s.frames = m.n.frames.load(std::memory_order_relaxed);
  s.drops = m.n.drops.load(std::memory_order_relaxed);
  s.corrupt = m.n.corrupt.load(std::memory_order_relaxed);
  s.timeouts = m.n.timeouts.load(std::memory_order_relaxed);
  s.disconnects = m.n.disconnects.load(std::memory_order_relaxed);
  s.reconnects = m.n.reconnects.load(std::memory_order_relaxed);
  s.reconnect_attempts = m.n.reconnect_attempts.load(std::memory_order_relaxed);
  return s;
}

CameraStatus SimCamera::next_frame(Frame& frame, int timeout_ms) {
  const char* side = sim::to_string(cfg_.sensor);
  const std::int64_t deadline = deadline_after_ms(timeout_ms);
  Impl& m = *impl_;
  const bool realtime = rig_->config().scene.realtime;
  const std::int64_t t0 = rig_->t0_ns();

  auto take_returned = [&m]() noexcept {
    std::uint32_t slot = 0;
    while (m.returned.pop(slot)) {
      if (slot >= static_cast<std::uint32_t>(m.nbufs) || !m.held[slot]) continue;
      m.held[slot] = false;
      --m.outstanding;
    }
  };
  // Sleeps until `until` or the deadline, whichever is first; false when the deadline came first.
  auto wait_until = [deadline](std::int64_t until) noexcept {
    sleep_until_ns(std::min(until, deadline));
    return monotonic_ns() >= until;
  };
  auto timed_out = [&](const char* why) {
    bump(m.n.timeouts);
    return CameraStatus::error(CameraError::kTimeout, "sim camera %s: no frame within %d ms (%s)",
                               side, timeout_ms, why);
  };

  take_returned();
  std::uint32_t dropped = m.carry_dropped;  // grid frames skipped for this delivery
  m.carry_dropped = 0;
  for (;;) {
    const LinkState s = link_state();
    if (s != LinkState::kStreaming && s != LinkState::kDisconnected) {
      return CameraStatus::error(CameraError::kBadState,
                                 "sim camera %s: next_frame() in state %s (call start())", side,
                                 to_string(s));
    }
    // Unplug / replug.
    if (!plugged_.load(std::memory_order_acquire)) {
      if (s == LinkState::kStreaming) {
        bump(m.n.disconnects);
        state_.store(LinkState::kDisconnected, std::memory_order_release);
        return CameraStatus::error(CameraError::kDisconnected,
                                   "sim camera %s: unplugged (fault injection); waiting for replug",
                                   side);
      }
      const std::int64_t now = monotonic_ns();
      if (now >= deadline) {
        return CameraStatus::error(CameraError::kTimeout, "sim camera %s: still unplugged", side);
      }
      sleep_until_ns(std::min(deadline, now + kPollNs));
      continue;
    }
    if (s == LinkState::kDisconnected) {
      bump(m.n.reconnect_attempts);
      bump(m.n.reconnects);
      m.resync = realtime;
      state_.store(LinkState::kStreaming, std::memory_order_release);
    }
    // Stall.
    const std::int64_t stall_until = stall_until_ns_.load(std::memory_order_acquire);
    if (monotonic_ns() < stall_until) {
      // Wake up at least every kPollNs so an unplug during the stall is seen.
      if (!wait_until(std::min(stall_until, monotonic_ns() + kPollNs))) return timed_out("stalled");
      if (monotonic_ns() < stall_until) continue;
      m.resync = realtime;
    }
    // Skip grid frames: requested drops, and in realtime the time spent stalled or unplugged.
    if (m.resync) {
      const std::int64_t now = monotonic_ns();
      const double k = std::ceil(static_cast<double>(now - t0) * rig_->config().fps * 1e-9);
      m.grid = std::max(m.grid, static_cast<std::int64_t>(k));
      m.resync = false;
    }
    if (const std::uint32_t n = drop_.exchange(0, std::memory_order_acq_rel); n > 0) {
      m.grid += n;
      m.seq += n;
      dropped += n;
      bump(m.n.drops, n);
    }
    // A free buffer.
    if (m.outstanding >= m.nbufs) {
      if (!wait_until(monotonic_ns() + kPollNs)) {
        return timed_out("all buffers are held by the consumer");
      }
      take_returned();
      continue;
    }
    if (realtime && m.pending_grid != m.grid) {
      // More than a period behind (slow rendering on a loaded machine, or a consumer that calls
      // late): like a sensor whose queue overflowed, skip frames and count them as drops, so the
      // latency stays bounded instead of growing. The skip goes to the next instant (not yet
      // exposed) and is published to the rig, so the other pad skips to the same instant.
      const std::int64_t behind = monotonic_ns() - (t0 + rig_->grid_time_ns(m.grid));
      if (behind > rig_->period_ns()) {
        const auto now_k = static_cast<std::int64_t>(
            std::floor(static_cast<double>(monotonic_ns() - t0) * rig_->config().fps * 1e-9));
        std::int64_t target = now_k + 1;
        std::int64_t seen = rig_->resume_grid_.load(std::memory_order_acquire);
        while (seen < target &&
               !rig_->resume_grid_.compare_exchange_weak(seen, target, std::memory_order_acq_rel)) {
        }
      }
      const std::int64_t resume = rig_->resume_grid_.load(std::memory_order_acquire);
      if (resume > m.grid) {
        const auto skip = static_cast<std::uint32_t>(resume - m.grid);
        m.grid = resume;
        m.seq += skip;
        dropped += skip;
        bump(m.n.drops, skip);
      }
    }
    const std::int64_t t_sim = rig_->grid_time_ns(m.grid);
    const std::int64_t stamp = t0 + t_sim;
    // Render ahead, then wait for the frame's time: delivery happens at the timestamp (as a
    // sensor's end of exposure), not a render time after it. A frame rendered for a grid slot
    // that a fault has since skipped is simply rendered again for the new slot.
    if (m.pending_grid != m.grid) {
      int free_slot = 0;
      while (m.held[static_cast<std::size_t>(free_slot)]) ++free_slot;
      std::uint8_t* dst = m.pixels.get() + m.frame_bytes * static_cast<std::size_t>(free_slot);
      const sim::SimStatus st = rig_->render(
          cfg_.sensor, m.grid, std::span<std::uint8_t>(dst, m.frame_bytes), m.channels);
      if (st != sim::SimStatus::kOk) {
        bump(m.n.corrupt);
        return CameraStatus::error(CameraError::kIo, "sim camera %s: simulator: %s", side,
                                   sim::to_string(st));
      }
      m.pending_grid = m.grid;
      m.pending_slot = free_slot;
    }
    if (realtime && monotonic_ns() < stamp) {
      // Sleep in bounded steps so a fault injected meanwhile still applies to this frame.
      if (!wait_until(std::min(stamp, monotonic_ns() + 4 * kPollNs)) && monotonic_ns() < stamp) {
        m.carry_dropped = dropped;  // reported with the frame that is finally delivered
        return timed_out("next frame not due yet");
      }
      continue;
    }
    const int slot = m.pending_slot;
    const std::uint8_t* out = m.pixels.get() + m.frame_bytes * static_cast<std::size_t>(slot);
    m.pending_grid = -1;
    frame.view.data = out;
    frame.view.size_bytes = m.frame_bytes;
    frame.view.width = info_.width;
    frame.view.height = info_.height;
    frame.view.stride_bytes = info_.stride_bytes;
    frame.view.format = cfg_.format;
    frame.sequence = m.seq;
    frame.timestamp_ns = stamp;
    frame.dropped_before = dropped;
    frame.timestamp_source = TimestampSource::kSimulated;
    frame.slot = static_cast<std::uint32_t>(slot);
    m.held[static_cast<std::size_t>(slot)] = true;
    ++m.outstanding;
    ++m.grid;
    ++m.seq;
    bump(m.n.frames);
    return CameraStatus::success();
  }
}

void SimCamera::release(const Frame& frame) {
  // Never blocks; the capture thread takes it back on its next call. Capacity covers every slot.
  (void)impl_->returned.push(frame.slot);
}

void SimCamera::stop() {
  if (link_state() == LinkState::kClosed) return;
  Impl& m = *impl_;
  m.pixels.reset();
  m.held.fill(false);
  m.outstanding = 0;
  std::uint32_t slot = 0;
  while (m.returned.pop(slot)) {
  }
  state_.store(LinkState::kClosed, std::memory_order_release);
}

}  // namespace tacse3::hal
