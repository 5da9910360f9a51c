// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: the daemon's threads, devices, housekeeping, signals and shutdown.
#include "tacse3/firmware/daemon.hpp"

#include <signal.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdarg>

#include "tacse3/dsp/se3.hpp"
#include "tacse3/firmware/system.hpp"
#include "tacse3/hal/thread.hpp"
#if TACSE3_HAVE_VIEWER
#include "tacse3/viewer/view_json.hpp"
#include "tacse3/viewer/view_server.hpp"
#else
namespace tacse3::firmware {
class ViewServer {};  // --http is not built in; the member stays null
}  // namespace tacse3::firmware
#endif
#if TACSE3_HAVE_RECORDER
#include "tacse3/firmware/recorder.hpp"
#else
namespace tacse3::firmware {
class FrameRecorder {};  // --record is not built in; the member stays null
}  // namespace tacse3::firmware
#endif
#include "tacse3/hal/camera/clock.hpp"
#include "tacse3/hal/camera/sim_camera.hpp"
#include "tacse3/hal/camera/v4l2_camera.hpp"
#include "tacse3/hal/can/log_channel.hpp"
#include "tacse3/hal/can/socketcan.hpp"
#include "tacse3/hal/can/unix_channel.hpp"
#include "tacse3/hal/gpio.hpp"
#include "tacse3/hal/gpio/controller.hpp"
#include "tacse3/sim/simulator.hpp"
#if TACSE3_HAVE_REPLAY
#include "tacse3/hal/camera/replay_camera.hpp"
#endif
#if TACSE3_HAVE_LIBCAMERA
#include "tacse3/hal/camera/libcamera_camera.hpp"
#endif

namespace tacse3::firmware {

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr int kCaptureTimeoutMs = 100;  // bounds how long a capture thread takes to see stop
constexpr int kRxTimeoutMs = 100;
// The DSP loop's longest wait with nothing to do: a frame or a command rings it awake earlier
// (Doorbell); the wait bounds how late a status or a stale pad is noticed.
constexpr std::int64_t kIdleSleepNs = 200'000;
// The DSP thread's prefault: 4x the 16 KiB its loop touches (measured with a 4 KiB prefault,
// sim board with the viewer serving every endpoint, and replay board).
constexpr std::size_t kDspStackPrefault = 64 * 1024;
// Stack sizes (docs/performance.md, "Thread stacks"): memory locking keeps a touched stack page
// resident, so each thread gets what it was measured to touch, with a margin.
// DSP: the prefault plus 256 KiB. Capture and RX: high-water marks of 16 and 8 KiB on the sim
// and replay boards; 128 KiB leaves 8x for the V4L2 and libcamera paths, which cannot be
// measured off the board.
constexpr std::size_t kDspStack = kDspStackPrefault + 256 * 1024;
// A capture thread also runs its pad's image stages: its 16 KiB plus the stages (within the DSP
// loop's 12 KiB) are prefaulted with a margin, plus the 128 KiB for the camera paths.
constexpr std::size_t kPadStackPrefault = 64 * 1024;
constexpr std::size_t kCaptureStack = kPadStackPrefault + 128 * 1024;
constexpr std::size_t kRxStack = 128 * 1024;

hal::LedState led_state(protocol::State s) noexcept {
  switch (s) {
    case protocol::State::kBooting:
      return hal::LedState::kBooting;
    case protocol::State::kNoContact:
      return hal::LedState::kNoContact;
    case protocol::State::kTracking:
      return hal::LedState::kTracking;
    case protocol::State::kDegradedSingleSensor:
      return hal::LedState::kDegraded;
    case protocol::State::kFault:
      return hal::LedState::kFault;
  }
  return hal::LedState::kFault;
}

void sleep_ns(std::int64_t ns) noexcept {
  timespec ts{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
  nanosleep(&ts, nullptr);
}

}  // namespace

bool load_calibration_source(const std::string& file, CalibrationSource* out, std::string* error) {
  CalibrationSource c;
  if (!file.empty()) {
    c.file = file;
    const config::Status st = config::load_calibration(file, &c.set);
    if (!st) {
      *error = st.message();
      return false;
    }
  }
  *out = std::move(c);
  return true;
}

bool simulated_board(const config::BoardConfig& board) noexcept {
  bool any = false;
  for (const auto& s : board.sensors) {
    if (!s.enabled) continue;
    if (s.backend != config::CameraBackend::kSim) return false;
    any = true;
  }
  return any;
}

std::filesystem::path default_calibration(const config::BoardConfig& board,
                                          const std::filesystem::path& exe_dir,
                                          const std::filesystem::path& source_sim_calibration) {
  if (!simulated_board(board)) return {};
  return config::find_sim_calibration(exe_dir, source_sim_calibration);
}

bool make_pipeline_config(const config::BoardConfig& board, const CalibrationSource& cal,
                          dsp::DualConfig* dual, std::array<dsp::Calibration, 2>* sensors,
                          std::string* error) {
  dsp::DualConfig d;
  d.finger_separation_m = board.pipeline.finger_separation_m;
  d.fusion = config::fusion_config(board);
  const int fps = board.sensors[0].enabled ? board.sensors[0].fps : board.sensors[1].fps;
  d.nominal_frame_period_s = 1.0 / fps;
  std::array<dsp::Calibration, 2> c = cal.set.for_method(board.pipeline.method);
  for (auto& s : c)
    s.velocity_proxy = to_dsp_proxy(board.pipeline.velocity_proxy, s.velocity_proxy);
  if (dsp::validate(d) != dsp::Status::kOk) {
    *error =
        board.origin + ": [pipeline] / [sensors] rotation: the pipeline rejects this configuration";
    return false;
  }
  for (std::size_t s = 0; s < 2; ++s) {
    if (dsp::validate(c[s]) != dsp::Status::kOk) {
      *error = (cal.file.empty() ? std::string("built-in calibration") : cal.file.string()) + ": " +
               (s == 0 ? "left" : "right") + " calibration rejected by the pipeline";
      return false;
    }
  }
  *dual = d;
  *sensors = c;
  return true;
}

void Daemon::say(int level, const char* fmt, ...) {
  if (level > options_.verbosity || log_ == nullptr) return;
  char buf[512];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(buf, sizeof(buf), fmt, ap);
  va_end(ap);
  std::fprintf(log_, "tacse3d: %s\n", buf);
  std::fflush(log_);
}

std::unique_ptr<Daemon> Daemon::create(const config::BoardConfig& board, const Options& options,
                                       const CalibrationSource& calibration, std::FILE* log,
                                       std::string* error) {
  std::unique_ptr<Daemon> d(new Daemon());
  d->board_ = board;
  d->options_ = options;
  d->calibration_ = calibration;
  d->shared_.calibrated.store(calibration.fitted(), std::memory_order_relaxed);
  d->log_ = log;

  // Pipeline: ~1.2 MB, allocated once here.
  dsp::DualConfig dual;
  std::array<dsp::Calibration, 2> cal;
  if (!make_pipeline_config(board, calibration, &dual, &cal, error)) return nullptr;
  d->pipeline_ = std::make_unique<dsp::DualPipeline>();
  if (d->pipeline_->configure(dual, cal) != dsp::Status::kOk) {
    *error = board.origin + ": the pipeline rejected the board/calibration configuration";
    return nullptr;
  }

  // Cameras.
  if (board.uses_backend(config::CameraBackend::kSim)) {
    hal::SimRigConfig rc;
    rc.scene.object = board.sim.object;
    rc.scene.motion = board.sim.motion;
    rc.scene.magnitude = board.sim.magnitude;
    rc.scene.regime = board.sim.regime;
    rc.scene.seed = board.sim.seed;
    rc.scene.repeat = board.sim.repeat;
    rc.scene.realtime = board.sim.realtime;
    rc.scene.finger_separation_mm = board.pipeline.finger_separation_m * 1e3;
    rc.scene.plan = board.sim.plan;
    rc.tcp_to_grasp = board.rig.tcp_to_grasp;
    const auto& s0 = board.sensors[0].enabled ? board.sensors[0] : board.sensors[1];
    rc.width = s0.width;
    rc.height = s0.height;
    rc.fps = s0.fps;
    std::string e;
    d->rig_ = hal::SimRig::create(rc, &e);
    if (!d->rig_) {
      *error = board.origin + ": " + e;
      return nullptr;
    }
    if (d->rig_->has_plan()) d->motion_ = d->rig_.get();
  }
  for (std::size_t s = 0; s < 2; ++s) {
    const config::SensorBoardConfig& sc = board.sensors[s];
    if (!sc.enabled) continue;
    const char* side = s == 0 ? "left" : "right";
    hal::CameraConfig cc;
    cc.device = sc.device;
    cc.width = sc.width;
    cc.height = sc.height;
    cc.fps = sc.fps;
    cc.buffer_count = sc.buffer_count;
    cc.allow_mjpeg = sc.allow_mjpeg;
    switch (sc.backend) {
      case config::CameraBackend::kSim: {
        hal::SimCameraConfig scc;
        scc.sensor = s == 0 ? sim::Sensor::kLeft : sim::Sensor::kRight;
        // Grey: what the sim calibration was fitted on, and the cheapest luma stage.
        scc.format = dsp::PixelFormat::kGrey;
        scc.buffer_count = sc.buffer_count;
        auto cam = d->rig_->make_camera(scc);
        d->sim_cameras_[s] = cam.get();
        d->cameras_[s] = std::move(cam);
        break;
      }
      case config::CameraBackend::kV4l2:
        d->cameras_[s] = hal::make_v4l2_camera(cc);
        break;
      case config::CameraBackend::kLibcamera:
#if TACSE3_HAVE_LIBCAMERA
        d->cameras_[s] = hal::make_libcamera_camera(cc);
        break;
#else
        *error = board.origin + ": sensors." + side +
                 ".backend \"libcamera\": this tacse3d was built without libcamera";
        return nullptr;
#endif
      case config::CameraBackend::kReplay: {
#if TACSE3_HAVE_REPLAY
        // A recording's own pad: the board's left sensor replays the recording's left pad. The
        // [sim] table's realtime/repeat also pace and loop replayed sensors (docs/firmware.md).
        hal::ReplayCameraConfig rc;
        rc.dir = sc.device;
        rc.right = s == 1;
        rc.realtime = board.sim.realtime;
        rc.loop = board.sim.repeat;
        rc.buffer_count = sc.buffer_count;
        rc.phase_ns = static_cast<std::int64_t>(sc.phase_us) * 1000;
        d->cameras_[s] = hal::make_replay_camera(rc);
        break;
#else
        *error = board.origin + ": sensors." + side +
                 ".backend \"replay\": this tacse3d was built without the replay backend "
                 "(libspng missing for this target)";
        return nullptr;
#endif
      }
    }
    d->backpressure_[s] = !board.sim.realtime && (sc.backend == config::CameraBackend::kSim ||
                                                  sc.backend == config::CameraBackend::kReplay);
    const hal::CameraStatus st = d->cameras_[s]->open();
    if (!st.ok()) {
      *error = std::string("sensor ") + side + " (" + to_string(sc.backend) + " " + sc.device +
               "): " + st.message();
      return nullptr;
    }
    const hal::CameraInfo& ci = d->cameras_[s]->info();
    const bool cropped = ci.native_width > ci.width || ci.native_height > ci.height;
    char rate[48] = "frame rate set by the pipeline";
    if (ci.granted_fps() > 0.0)
      std::snprintf(rate, sizeof(rate), "%.1f fps granted", ci.granted_fps());
    d->say(1, "sensor %s: %s %s, %s %dx%d%s, %s, %d buffers", side, ci.backend.data(),
           ci.card.data(), ci.fourcc.data(), cropped ? ci.native_width : ci.width,
           cropped ? ci.native_height : ci.height,
           cropped ? " centre-cropped to the configured size" : "", rate, ci.buffer_count);
  }

  // CAN channel.
  protocol::Endpoint ep;
  ep.node_id = static_cast<std::uint8_t>(board.can.node_id);
  ep.layout.mode =
      board.can.extended_ids ? protocol::IdMode::kExtended : protocol::IdMode::kStandard;
  if (!options.can_socket.empty()) {
    std::string e;
    auto ch = hal::can::UnixSocketChannel::listen(
        options.can_socket, e, board.can.interface.empty() ? "can0" : board.can.interface);
    if (!ch) {
      *error = std::string("--can-socket: ") + e;
      return nullptr;
    }
    d->unix_channel_ = ch.get();
    d->channel_ = std::move(ch);
  } else if (!options.can_log.empty() || board.can.backend == config::CanBackend::kLog) {
    const std::string out = !options.can_log.empty() ? options.can_log : board.can.log;
    std::string e;
    auto ch = hal::can::LogChannel::open(
        "", out, e, board.can.interface.empty() ? "can0" : board.can.interface);
    if (!ch) {
      *error = "CAN log " + out + ": " + e;
      return nullptr;
    }
    d->log_channel_ = ch.get();
    d->channel_ = std::move(ch);
  } else {
    hal::can::SocketCanOptions so;
    so.fd = board.can.mode == protocol::FrameMode::kFd;
    so.filters = hal::can::command_filters(ep);
    so.tx_queue = static_cast<std::uint32_t>(board.can.tx_queue);
    const std::string iface = options.can_iface.empty() ? board.can.interface : options.can_iface;
    std::string e;
    auto ch = hal::can::SocketCanChannel::open(iface, so, e);
    if (!ch) {
      *error = "CAN interface " + iface + ": " + e;
      return nullptr;
    }
    d->channel_ = std::move(ch);
  }

  // GPIO.
  d->gpio_ = board.gpio.backend == config::GpioBackendKind::kLibgpiod ? hal::make_libgpiod_gpio()
                                                                      : hal::make_null_gpio();
  hal::GpioConfig gc = board.gpio.lines;
  gc.consumer = "tacse3d";
  if (const hal::GpioStatus st = d->gpio_->open(gc); !st.ok()) {
    *error = board.origin + ": [gpio]: " + st.message();
    return nullptr;
  }
  hal::GpioTiming timing;
  timing.debounce_ns = static_cast<std::int64_t>(board.gpio.debounce_ms) * 1'000'000;
  d->gpio_controller_ = std::make_unique<hal::GpioController>(*d->gpio_, timing);

  // The engine.
  // Default-initialised: value-initialising the array would zero every slot of both queues and
  // make them resident. A staged frame holds its camera buffer, so a pad never has more staged
  // frames than its camera has buffers: those slots are built now, before the memory is locked,
  // so the pad thread takes no page fault when a backlog first grows; the others never are.
  d->rings_ = std::make_unique_for_overwrite<std::array<StagedRing, 2>>();
  for (std::size_t s = 0; s < 2; ++s) {
    if (d->cameras_[s] != nullptr)
      (*d->rings_)[s].reserve(static_cast<std::size_t>(d->cameras_[s]->info().buffer_count));
  }
  d->command_rings_ = std::make_unique<std::array<CommandRing, 2>>();
  EngineConfig ec;
  ec.tx.endpoint = ep;
  ec.tx.frame_mode = board.can.mode;
  ec.pairing = pairing_config(board.pipeline.pair_tolerance_us, board.pipeline.stale_ms);
  ec.health.stale_ns = static_cast<std::int64_t>(board.pipeline.stale_ms) * 1'000'000;
  ec.health.lost_ns = static_cast<std::int64_t>(board.pipeline.lost_ms) * 1'000'000;
  ec.configured = {board.sensors[0].enabled, board.sensors[1].enabled};
  ec.rate_divider = static_cast<std::uint8_t>(board.can.rate_divider);
  ec.velocity_mode = board.pipeline.velocity_proxy;
  ec.frame_period_ns =
      1'000'000'000LL / (board.sensors[0].enabled ? board.sensors[0].fps : board.sensors[1].fps);
  std::array<hal::Camera*, 2> cams{d->cameras_[0].get(), d->cameras_[1].get()};
  std::array<StagedRing*, 2> rings{board.sensors[0].enabled ? &(*d->rings_)[0] : nullptr,
                                   board.sensors[1].enabled ? &(*d->rings_)[1] : nullptr};
  d->engine_ = std::make_unique<Engine>(
      ec, *d->pipeline_, *d->channel_, cams, std::array<FrameRing*, 2>{},
      std::array<CommandRing*, 2>{&(*d->command_rings_)[0], &(*d->command_rings_)[1]}, d->shared_);
  d->engine_->set_staged_rings(rings);

  // --record DIR: what the DSP thread processes, written off the DSP path (docs/firmware.md).
  if (!options.record_dir.empty()) {
#if TACSE3_HAVE_RECORDER
    std::string e;
    d->recording_path_ = options.record_dir;
    d->recorder_ = FrameRecorder::start(options.record_dir,
                                        d->recorder_config(board.pipeline.finger_separation_m), &e);
    if (!d->recorder_) {
      *error = std::string("--record ").append(e);
      return nullptr;
    }
    d->engine_->set_recorder(d->recorder_.get());
#else
    *error = "--record: this tacse3d was built without the recording writer (libspng missing)";
    return nullptr;
#endif
  }
  if (!d->start_viewer(error)) return nullptr;
  return d;
}

// --http, else the board's [viewer] listen: both checked by parse_listen_address already (the
// command line and the board file reader); empty: no viewer, and the DSP thread publishes nothing.
bool Daemon::start_viewer(std::string* error) {
  const bool from_cli = !options_.http.empty();
  const std::string text = from_cli ? options_.http : board_.viewer.listen;
  if (text.empty()) return true;
  const std::string what = from_cli ? std::string("--http ").append(text)
                                    : board_.origin + ": [viewer] listen \"" + text + "\"";
#if TACSE3_HAVE_VIEWER
  viewer::ViewServerConfig vc;
  std::string e;
  if (!config::parse_listen_address(text, &vc.listen, &e)) {
    *error = what + ": " + e;
    return false;
  }
  vc.assets = viewer::find_viewer_assets(config::executable_dir());
  if (vc.assets.empty()) {
    *error = what + ": the viewer's page is not installed (" +
             (config::executable_dir() / ".." / "share" / "tacse3" / "viewer").string() +
             "/index.html is missing; reinstall the package or build tacse3_viewer_assets)";
    return false;
  }
  viewer::ViewInfo info;
  info.version = std::to_string(TACSE3_VERSION_MAJOR) + "." + std::to_string(TACSE3_VERSION_MINOR) +
                 "." + std::to_string(TACSE3_VERSION_PATCH);
  info.board = board_.name;
  info.board_file = board_.origin;
  info.calibration = calibration_.file.string();
  if (!board_.viewer.controls) {
    info.controls_off = board_.origin +
                        ": [viewer] controls is not true (set controls = true there to enable "
                        "tare, reset pose and stream on/off)";
  } else {
    web_commands_ = std::make_unique<CommandMailbox>();
    vc.commands = web_commands_.get();
    engine_->set_web_commands(web_commands_.get());
  }
  vc.controls_off = info.controls_off;
  vc.endpoint.node_id = static_cast<std::uint8_t>(board_.can.node_id);
  vc.endpoint.layout.mode =
      board_.can.extended_ids ? protocol::IdMode::kExtended : protocol::IdMode::kStandard;
  vc.info_json = viewer::view_info_json(info);
  view_slot_ = std::make_unique<ViewSlot>();
  view_server_ = ViewServer::start(vc, *view_slot_, &e);
  if (!view_server_) {
    *error = what + ": " + e;
    return false;
  }
  engine_->set_view(view_slot_.get());
  say(1, "viewer: http://%s:%d/ (page from %s)", vc.listen.host.c_str(), vc.listen.port,
      vc.assets.c_str());
  return true;
#else
  *error = what +
           ": this tacse3d was built without the live viewer (libcpp-httplib-dev, "
           "libturbojpeg0-dev or nlohmann-json3-dev missing for this target)";
  return false;
#endif
}

Daemon::~Daemon() {
  for (auto& c : cameras_) {
    if (c) c->stop();
  }
  if (gpio_) gpio_->close();
}

hal::SimCamera* Daemon::sim_camera(std::size_t sensor) noexcept {
  return sensor < 2 ? sim_cameras_[sensor] : nullptr;
}

bool Daemon::reload_calibration(std::string* message) {
  if (calibration_.file.empty()) {
    *message = "SIGHUP: no --calibration file to reload (built-in defaults stay)";
    return false;
  }
  CalibrationSource next;
  std::string e;
  if (!load_calibration_source(calibration_.file.string(), &next, &e)) {
    *message = "calibration reload rejected, keeping the last good one: " + e;
    shared_.calibration_invalid.store(true, std::memory_order_relaxed);
    return false;
  }
  dsp::DualConfig dual;
  std::array<dsp::Calibration, 2> cal;
  if (!make_pipeline_config(board_, next, &dual, &cal, &e)) {
    *message = "calibration reload rejected, keeping the last good one: " + e;
    shared_.calibration_invalid.store(true, std::memory_order_relaxed);
    return false;
  }
  // Hand it to the DSP thread (it applies it between two cycles) and wait for the answer.
  for (int i = 0;
       i < 200 && shared_.calibration_flag.load(std::memory_order_acquire) == SharedState::kPending;
       ++i) {
    sleep_ns(1'000'000);
  }
  shared_.calibration = cal;
  shared_.calibration_flag.store(SharedState::kPending, std::memory_order_release);
  if (!dsp_ready_.load(std::memory_order_acquire)) {
    *message = "calibration " + calibration_.file.string() + " queued (the loop is not running)";
    calibration_ = next;
    shared_.calibrated.store(calibration_.fitted(), std::memory_order_relaxed);
    return true;
  }
  for (int i = 0; i < 1000; ++i) {
    const int f = shared_.calibration_flag.load(std::memory_order_acquire);
    if (f == SharedState::kApplied) {
      calibration_ = next;
      shared_.calibrated.store(calibration_.fitted(), std::memory_order_relaxed);
      *message = "calibration reloaded from " + calibration_.file.string();
      return true;
    }
    if (f == SharedState::kRejected) {
      *message = "calibration reload rejected by the pipeline, keeping the last good one: " +
                 calibration_.file.string();
      return false;
    }
    sleep_ns(1'000'000);
  }
  *message = "calibration reload: the DSP loop did not answer within 1 s";
  return false;
}

// The pad's thread: takes its camera's frames, runs their image stages at once (PadStager) and
// hands them to the DSP thread. It is on the path to the CAN frame, so it runs real-time like
// the DSP thread (stack prefaulted), on the pad's CPU, one priority below it: where they share
// a CPU the DSP thread, which finishes the cycle, goes first (a camera that decodes its next
// frame on this thread, as the replay camera does, must not hold the finish back).
void Daemon::capture_loop(std::size_t s) {
  hal::Camera& cam = *cameras_[s];
  StagedRing& ring = (*rings_)[s];
  PadStager& stager = engine_->stager(s);
  auto& sh = shared_.sensors[s];
  const char* side = s == 0 ? "left" : "right";
  std::uint64_t overflow = 0;
  bool reported_error = false;
  bool reported_bad = false;
  // The DSP thread, started first, has locked the memory.
  const int priority = std::max(board_.realtime.dsp_priority - 1, 0);
  const RealtimeResult rt =
      setup_realtime_thread(priority, board_.realtime.pad_cpus[s], kPadStackPrefault, false);
  if (!rt.message.empty()) say(1, "sensor %s: pad thread %s", side, rt.message.c_str());
  while (!stop_.load(std::memory_order_acquire)) {
    ArrivedFrame f;
    const hal::CameraStatus st = cam.next_frame(f.frame, kCaptureTimeoutMs);
    f.arrival_ns = hal::monotonic_ns();
    if (st.ok()) {
      if (sh.disconnected.load(std::memory_order_relaxed))
        say(1, "sensor %s: streaming again", side);
      sh.disconnected.store(false, std::memory_order_release);
      reported_error = false;
      reported_bad = false;
      StagedFrame* slot = ring.back();
      while (slot == nullptr && backpressure_[s] && !stop_.load(std::memory_order_acquire)) {
        sleep_ns(500'000);  // an unpaced source waits for the loop
        slot = ring.back();
      }
      if (slot == nullptr) {
        // The DSP thread is behind by a whole ring: drop the newest, counted, before its stages.
        cam.release(f.frame);
        ++overflow;
      } else {
        stager.stage(f, *slot);
        ring.commit();
        sh.frames.fetch_add(1, std::memory_order_relaxed);
        doorbell_.ring();
        stager.run_deferred();
      }
      sh.camera_drops.store(cam.stats().drops + overflow, std::memory_order_relaxed);
      continue;
    }
    switch (st.code) {
      case hal::CameraError::kTimeout:
        break;
      case hal::CameraError::kCorruptFrame:
        // Dropped and counted by the camera (summed up at the stop). Said once per run of bad
        // frames: a deleted recording fails every frame with the same cause.
        if (!reported_bad) say(1, "sensor %s: frame dropped: %s", side, st.message());
        reported_bad = true;
        break;
      case hal::CameraError::kDisconnected:
        // Said when the sensor is lost, not on every retry (an ended recording keeps saying so).
        if (!sh.disconnected.exchange(true, std::memory_order_acq_rel))
          say(1, "sensor %s lost: %s", side, st.message());
        break;
      default:
        if (cam.link_state() == hal::LinkState::kDisconnected ||
            cam.link_state() == hal::LinkState::kFailed) {
          sh.disconnected.store(true, std::memory_order_release);
        }
        if (!reported_error) say(1, "sensor %s: %s", side, st.message());
        reported_error = true;
        sleep_ns(kCaptureTimeoutMs * 1'000'000LL);
        break;
    }
  }
}

void Daemon::dsp_loop() {
  const RealtimeResult rt = setup_realtime_thread(board_.realtime.dsp_priority,
                                                  board_.realtime.dsp_cpu, kDspStackPrefault);
  if (!rt.message.empty())
    say(1, "real-time setup incomplete, running anyway: %s", rt.message.c_str());
  engine_->start(hal::monotonic_ns());
  dsp_ready_.store(true, std::memory_order_release);
  while (!stop_.load(std::memory_order_acquire)) {
    // Read before the step: a frame or command handed over during it ends the wait at once.
    const std::uint32_t rung = doorbell_.value();
    if (!engine_->step(hal::monotonic_ns())) doorbell_.wait(rung, kIdleSleepNs);
  }
}

void Daemon::rx_loop() {
  protocol::Endpoint ep;
  ep.node_id = static_cast<std::uint8_t>(board_.can.node_id);
  ep.layout.mode =
      board_.can.extended_ids ? protocol::IdMode::kExtended : protocol::IdMode::kStandard;
  protocol::CommandReceiver receiver(ep);
  CommandRing& ring = (*command_rings_)[0];
  bool reported = false;
  while (!stop_.load(std::memory_order_acquire)) {
    hal::can::RxFrame rx;
    const hal::can::RxResult r = channel_->receive(rx, kRxTimeoutMs);
    if (r == hal::can::RxResult::kFrame) {
      const protocol::CommandResult res = receiver.receive(rx.frame);
      shared_.rejected_commands.store(receiver.stats().rejected(), std::memory_order_relaxed);
      if (res.addressed && !ring.push(res)) say(1, "command queue full: command dropped");
      if (res.addressed) doorbell_.ring();
    } else if (r == hal::can::RxResult::kEnd) {
      sleep_ns(kRxTimeoutMs * 1'000'000LL);  // no command input (log backend writing only)
    } else if (r == hal::can::RxResult::kError) {
      if (!reported) say(1, "CAN receive: %s", channel_->last_error().c_str());
      reported = true;
      sleep_ns(kRxTimeoutMs * 1'000'000LL);
    }
  }
}

// The log is the daemon's only CAN output when it is the backend: streaming on without it would
// look healthy to nobody, so a write error (disk full, reader gone) stops the daemon with exit 1.
void Daemon::check_can_log() {
  if (log_channel_ == nullptr || exit_code_ != 0 || !log_channel_->write_failed()) return;
  exit_code_ = 1;
  say(0, "%s; stopping (free space or choose another --can-log)",
      log_channel_->write_error().c_str());
  stop_.store(true, std::memory_order_release);
}

// Peers of --can-socket come and go (each tacse3-ctl call is one); bad input is said once.
void Daemon::report_can_socket() {
  if (unix_channel_ == nullptr) return;
  const hal::can::UnixSocketChannel::Counters c = unix_channel_->counters();
  if (c.accepted != socket_seen_.accepted || c.disconnected != socket_seen_.disconnected) {
    say(2, "CAN socket %s: %u peer(s) connected", unix_channel_->path().c_str(), c.peers);
  }
  if (c.refused > 0 && socket_seen_.refused == 0) {
    say(1, "CAN socket %s: connection refused: %zu peers already connected",
        unix_channel_->path().c_str(), hal::can::UnixSocketChannel::kMaxPeers);
  }
  if (c.bad_lines > 0 && socket_seen_.bad_lines == 0) {
    say(1, "CAN socket %s: ignoring input lines that are not candump -L (counted; first: \"%s\")",
        unix_channel_->path().c_str(), unix_channel_->first_bad_line().c_str());
  }
  socket_seen_ = c;
}

#if TACSE3_HAVE_RECORDER
// What a recording of this board holds: the sensors as configured, the pixel pitch of the
// running calibration and the given finger separation.
RecorderConfig Daemon::recorder_config(double finger_separation_m) const {
  RecorderConfig rc;
  const config::SensorBoardConfig& s0 =
      board_.sensors[0].enabled ? board_.sensors[0] : board_.sensors[1];
  rc.width = s0.width;
  rc.height = s0.height;
  rc.fps = s0.fps;
  for (std::size_t s = 0; s < 2; ++s) {
    rc.sensors[s] = board_.sensors[s].enabled;
    if (cameras_[s]) rc.formats[s] = cameras_[s]->info().format;
  }
  rc.pixel_pitch_mm = calibration_.set.sensor[0].pixel_pitch_m * 1e3;
  rc.finger_separation_mm = finger_separation_m * 1e3;
  return rc;
}
#endif

// Writes what is queued, says how it went and frees the recorder.
void Daemon::close_recording() {
#if TACSE3_HAVE_RECORDER
  if (!recorder_) return;
  // The simulated rig opens its pads at once (the next tare must see them open), before the
  // writer drains; its robot's log covers the recording's last frame, which is already taken.
  std::string motion_error;
  const bool motion_stopped = motion_playing_;
  if (motion_playing_) {
    motion_playing_ = false;
    motion_error = motion_->stop_motion();
  }
  const std::string e = recorder_->close();
  const recording::StreamWriterStats rs = recorder_->stats();
  if (!e.empty()) {
    say(0, "recording %s: %s", recording_path_.c_str(), e.c_str());
  } else {
    say(1,
        "recording %s: %llu frames written, %llu dropped (ring full), %llu instants without "
        "every pad, %llu rejected",
        recording_path_.c_str(), static_cast<unsigned long long>(rs.written),
        static_cast<unsigned long long>(rs.dropped_full),
        static_cast<unsigned long long>(recorder_->skipped_incomplete()),
        static_cast<unsigned long long>(rs.rejected));
  }
  recorder_.reset();
  if (motion_stopped && motion_error.empty()) {
    say(1, "recording %s: the simulated robot's log is %s/robot/gripper.csv",
        recording_path_.c_str(), recording_path_.c_str());
  } else if (motion_stopped) {
    say(0, "recording %s: the simulated robot's log: %s", recording_path_.c_str(),
        motion_error.c_str());
  }
#endif
}

// START/STOP_RECORDING's disk work, asked for by the DSP thread (RecordingMailbox). A close goes
// first: the DSP thread asks for a new recording only after it let go of the last one.
void Daemon::service_recording() {
  RecordingMailbox& box = shared_.recording;
  if (FrameRecorder* done = box.take_close(); done != nullptr && done == recorder_.get()) {
    close_recording();
  }
  RecordingMailbox::StartRequest req;
  if (recorder_ || !box.pending_start(&req)) return;
#if TACSE3_HAVE_RECORDER
  // The sim rig plays one plan motion per recording: none left, no recording (nothing created).
  if (motion_ != nullptr) {
    if (const std::string why = motion_->next_motion_problem(); !why.empty()) {
      say(0, "START_RECORDING %u refused: %s", static_cast<unsigned>(req.number), why.c_str());
      box.answer_start(nullptr, protocol::AckCode::kOutOfRange);
      return;
    }
  }
  std::string message;
  const protocol::AckCode code =
      start_numbered_recording(board_.record.dir, req.number,
                               recorder_config(req.finger_separation_m), &recorder_, &message);
  say(code == protocol::AckCode::kAck ? 1 : 0, "%s", message.c_str());
  if (code == protocol::AckCode::kAck) {
    recording_path_ = numbered_recording_dir(board_.record.dir, req.number).string();
    recording_failure_reported_ = false;
    if (motion_ != nullptr) {
      motion_->start_motion(recording_path_);
      motion_playing_ = true;
    }
  }
  box.answer_start(recorder_.get(), code);
#else
  say(0, "START_RECORDING refused: this tacse3d was built without the recording writer");
  box.answer_start(nullptr, protocol::AckCode::kInternalError);
#endif
}

void Daemon::housekeeping_tick(std::int64_t now_ns, bool handle_signals) {
  check_can_log();
  report_can_socket();
  service_recording();
#if TACSE3_HAVE_RECORDER
  // A write error (disk full, directory gone) stops the recording, never the stream.
  if (recorder_ && !recording_failure_reported_ && recorder_->failed()) {
    recording_failure_reported_ = true;
    say(0, "recording stopped, streaming goes on: %s", recorder_->error().c_str());
  }
#endif
  if (handle_signals) {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGHUP);
    timespec zero{0, 0};
    for (;;) {
      const int sig = sigtimedwait(&set, nullptr, &zero);
      if (sig < 0) break;
      if (sig == SIGHUP) {
        std::string msg;
        reload_calibration(&msg);
        say(0, "%s", msg.c_str());
      } else {
        say(1, "%s: stopping", sig == SIGTERM ? "SIGTERM" : "SIGINT");
        stop_.store(true, std::memory_order_release);
      }
    }
  }
  // Tare button.
  const hal::GpioInputs in = gpio_controller_->take_inputs();
  if (in.tare_presses > 0) {
    tare_count_ += in.tare_presses;
    shared_.tare_requests.store(tare_count_, std::memory_order_release);
    say(1, "tare button pressed");
  }
  // State -> LED, log.
  const std::uint8_t st = shared_.state.load(std::memory_order_relaxed);
  if (st != last_state_) {
    gpio_controller_->set_state(led_state(static_cast<protocol::State>(st)));
    say(1, "state %s", protocol::to_string(static_cast<protocol::State>(st)));
    last_state_ = st;
  }
  // CAN channel counters for the status frames (stats() may take a lock: not on the DSP thread).
  const hal::can::ChannelStats cs = channel_->stats();
  shared_.can_tx_dropped.store(cs.tx_dropped, std::memory_order_relaxed);
  shared_.can_error_passive.store(cs.bus_state == hal::can::BusState::kErrorPassive ||
                                      cs.bus_state == hal::can::BusState::kBusOff,
                                  std::memory_order_relaxed);
  // READY=1 once every configured sensor streams.
  if (!ready_sent_) {
    bool all = true;
    for (std::size_t s = 0; s < 2; ++s) {
      if (board_.sensors[s].enabled && shared_.sensors[s].frames.load() == 0) all = false;
    }
    if (all) {
      ready_sent_ = true;
      streaming_since_ns_ = now_ns;
      notify("READY=1\nSTATUS=streaming");
      say(1, "sensors streaming");
    }
  }
  // Watchdog: only while the DSP loop's heartbeat advances.
  if (watchdog_usec_ > 0 && now_ns >= next_watchdog_ns_) {
    const std::uint64_t hb = shared_.heartbeat.load(std::memory_order_relaxed);
    if (hb != last_heartbeat_) notify("WATCHDOG=1");
    last_heartbeat_ = hb;
    next_watchdog_ns_ = now_ns + watchdog_usec_ * 1000 / 2;
  }
  if (options_.verbosity >= 2 && now_ns >= next_verbose_ns_) {
    next_verbose_ns_ = now_ns + 1'000'000'000;
    say(2, "cycles %llu, emitted %llu, state %s",
        static_cast<unsigned long long>(shared_.cycles.load()),
        static_cast<unsigned long long>(shared_.emitted.load()),
        protocol::to_string(static_cast<protocol::State>(st)));
  }
  if (options_.seconds > 0.0 && ready_sent_ &&
      static_cast<double>(now_ns - streaming_since_ns_) * 1e-9 >= options_.seconds) {
    stop_.store(true, std::memory_order_release);
  }
}

int Daemon::run(bool handle_signals) {
  watchdog_usec_ = watchdog_usec();
  gpio_controller_->start(hal::monotonic_ns());
  // The DSP thread first: its real-time setup (mlockall, stack prefault) can take a while, and
  // frames that arrive before it runs would overflow the capture rings (a replayed recording
  // would lose its first frames, which hold the reference). Cameras start once it is looping.
  hal::Thread dsp(kDspStack, [this] { dsp_loop(); });
  for (int i = 0; i < 2000 && !dsp_ready_.load(std::memory_order_acquire); ++i) sleep_ns(1'000'000);
  for (std::size_t s = 0; s < 2; ++s) {
    if (!cameras_[s]) continue;
    const hal::CameraStatus st = cameras_[s]->start();
    if (!st.ok()) {
      say(0, "sensor %s: %s", s == 0 ? "left" : "right", st.message());
      stop_.store(true, std::memory_order_release);
      dsp.join();
      return 1;
    }
  }
  std::array<hal::Thread, 2> capture;
  for (std::size_t s = 0; s < 2; ++s) {
    if (cameras_[s]) capture[s] = hal::Thread(kCaptureStack, [this, s] { capture_loop(s); });
  }
  hal::Thread rx(kRxStack, [this] { rx_loop(); });

  while (!stop_.load(std::memory_order_acquire)) {
    gpio_controller_->poll(5);  // also the housekeeping tick's sleep
    housekeeping_tick(hal::monotonic_ns(), handle_signals);
  }
  const std::int64_t stop_ns = hal::monotonic_ns();
  notify("STOPPING=1");
  dsp.join();
  for (auto& t : capture) {
    if (t.joinable()) t.join();
  }
  rx.join();
#if TACSE3_HAVE_VIEWER
  if (view_server_) {
    const ViewServer::Stats vs = view_server_->stats();
    view_server_.reset();
    say(1,
        "viewer: %llu snapshots served, %llu streams refused (too many), %llu dropped (slow), "
        "%llu connections refused (busy)",
        static_cast<unsigned long long>(vs.snapshots),
        static_cast<unsigned long long>(vs.streams_refused),
        static_cast<unsigned long long>(vs.streams_dropped),
        static_cast<unsigned long long>(vs.connections_refused));
  }
#endif
  engine_->release_all();
  for (std::size_t s = 0; s < 2; ++s) {
    const std::uint64_t bad = cameras_[s] ? cameras_[s]->stats().corrupt : 0;
    if (bad > 0)
      say(1, "sensor %s: %llu bad frame(s) dropped", s == 0 ? "left" : "right",
          static_cast<unsigned long long>(bad));
  }
  for (auto& c : cameras_) {
    if (c) c->stop();
  }
  channel_->service();
  close_recording();
  check_can_log();  // frames sent during the shutdown
  if (unix_channel_ != nullptr) {
    const hal::can::UnixSocketChannel::Counters c = unix_channel_->counters();
    if (c.bad_lines > 0)
      say(1, "CAN socket: %llu bad input line(s) ignored (%llu longer than %zu characters)",
          static_cast<unsigned long long>(c.bad_lines),
          static_cast<unsigned long long>(c.long_lines), hal::can::UnixSocketChannel::kLineMax - 1);
  }
  summary_.streaming_s =
      ready_sent_ ? static_cast<double>(stop_ns - streaming_since_ns_) * 1e-9 : 0.0;
  finish_summary();
  return exit_code_;
}

void Daemon::finish_summary() {
  summary_.engine = engine_->stats();
  summary_.last_cycle = engine_->last_cycle();
  summary_.latency_p50_us = engine_->latency_percentile_us(50);
  summary_.latency_p99_us = engine_->latency_percentile_us(99);
  const CycleLatency& lat = engine_->latency();
  summary_.later_arrival_p50_us = lat.later_arrival().percentile(50);
  summary_.later_arrival_p99_us = lat.later_arrival().percentile(99);
  summary_.earlier_arrival_p50_us = lat.earlier_arrival().percentile(50);
  summary_.earlier_arrival_p99_us = lat.earlier_arrival().percentile(99);
  summary_.dsp_p50_us = engine_->dsp_time_percentile_us(50);
  const EngineStats& e = summary_.engine;
  if (!calibration_.fitted()) say(0, "UNCALIBRATED run: the estimates below are not to scale");
  say(1,
      "stopped after %.2f s of streaming: %llu samples (%llu pairs, %llu single), %llu cycles "
      "sent, "
      "latency p50 %lld us p99 %lld us, dsp p50 %lld us; from the later frame's arrival p50 "
      "%lld us p99 %lld us, from the earlier's p50 %lld us p99 %lld us",
      summary_.streaming_s, static_cast<unsigned long long>(e.samples),
      static_cast<unsigned long long>(e.pairs), static_cast<unsigned long long>(e.singles),
      static_cast<unsigned long long>(e.cycles_sent),
      static_cast<long long>(summary_.latency_p50_us),
      static_cast<long long>(summary_.latency_p99_us), static_cast<long long>(summary_.dsp_p50_us),
      static_cast<long long>(summary_.later_arrival_p50_us),
      static_cast<long long>(summary_.later_arrival_p99_us),
      static_cast<long long>(summary_.earlier_arrival_p50_us),
      static_cast<long long>(summary_.earlier_arrival_p99_us));
  if (rig_ && e.cycles_sent > 0) {
    const protocol::Cycle& c = summary_.last_cycle;
    const std::int64_t t_ns = static_cast<std::int64_t>(c.timestamp_us) * 1000;
    const sim::Pose truth = rig_->truth(t_ns);
    const Eigen::Quaterniond q_est(c.orientation.w, c.orientation.x, c.orientation.y,
                                   c.orientation.z);
    const Eigen::Vector3d est = dsp::so3_log(q_est.normalized()) * kRadToDeg;
    const Eigen::Vector3d tru = dsp::so3_log(truth.q.normalized()) * kRadToDeg;
    const double err = q_est.normalized().angularDistance(truth.q.normalized()) * kRadToDeg;
    summary_.have_truth = true;
    for (int i = 0; i < 3; ++i) {
      summary_.truth_rotation_deg[i] = tru[i];
      summary_.estimated_rotation_deg[i] = est[i];
    }
    summary_.rotation_error_deg = err;
    say(0,
        "sim truth at the last cycle: rotation (%.2f, %.2f, %.2f) deg; sent estimate (%.2f, %.2f, "
        "%.2f) deg; error %.2f deg%s",
        tru.x(), tru.y(), tru.z(), est.x(), est.y(), est.z(), err,
        calibration_.fitted() ? "" : " (UNCALIBRATED)");
  }
}

}  // namespace tacse3::firmware
