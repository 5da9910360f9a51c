// SPDX-License-Identifier: Apache-2.0
// tacse3-replay --view: the replayed frames as the viewer's snapshots, and the server for them.
#include "replay_view.hpp"

#include <signal.h>

#include <cstdio>

#include "tacse3/config/calibration_file.hpp"
#include "tacse3/protocol/types.hpp"
#include "tacse3/tools/metrics.hpp"
#include "tacse3/version.hpp"
#include "tacse3/viewer/view_json.hpp"
#include "tacse3/viewer/view_snapshot.hpp"
#if TACSE3_HAVE_VIEWER
#include "tacse3/viewer/view_server.hpp"
#endif

namespace tacse3::tools {

namespace {

// The replay has no daemon state machine: a frame's state says what its estimate was.
protocol::State frame_state(const FrameResult& r) {
  if (!r.estimate_valid) return protocol::State::kNoContact;
  return r.single_sensor ? protocol::State::kDegradedSingleSensor : protocol::State::kTracking;
}

void fill_scalars(std::size_t index, const FrameResult& r, bool calibrated,
                  viewer::ViewSnapshot* v) {
  v->cycle = index + 1;
  v->t_us = r.t_ns / 1000;
  v->state = static_cast<std::uint8_t>(frame_state(r));
  v->have_result = true;
  v->valid = r.estimate_valid;
  v->single_sensor = r.single_sensor;
  v->calibrated = calibrated;
  for (std::size_t i = 0; i < 3; ++i) {
    v->w[i] = r.twist[static_cast<Eigen::Index>(i)];
    v->v[i] = r.twist[static_cast<Eigen::Index>(i + 3)];
  }
  v->q = {r.pose.q.w(), r.pose.q.x(), r.pose.q.y(), r.pose.q.z()};
  v->p = {r.pose.p.x(), r.pose.p.y(), r.pose.p.z()};
  v->confidence = r.estimate_valid ? r.confidence : 0.0;
}

}  // namespace

struct ReplayView::Impl {
  Impl(const SourceInfo& i, bool c) : info(i), calibrated(c) {}
  const SourceInfo& info;
  bool calibrated;
  viewer::ViewSnapshot scratch{};  // 70 kB: not on the stack
#if TACSE3_HAVE_VIEWER
  viewer::RecordedViews views;
#endif
};

ReplayView::ReplayView(const SourceInfo& info, bool calibrated)
    : impl_(std::make_unique<Impl>(info, calibrated)) {}
ReplayView::~ReplayView() = default;

const char* ReplayView::unavailable() noexcept {
  if (TACSE3_HAVE_VIEWER != 0) return nullptr;
  return "this tacse3-replay was built without the viewer (install libcpp-httplib-dev, "
         "libturbojpeg0-dev and nlohmann-json3-dev)";
}

void ReplayView::add(std::size_t index, const FrameResult& r, const Replayer& engine) {
  viewer::ViewSnapshot& v = impl_->scratch;
  v = viewer::ViewSnapshot{};
  fill_scalars(index, r, impl_->calibrated, &v);
  for (std::size_t s = 0; s < 2; ++s) {
    viewer::ViewPad& pad = v.pads[s];
    pad.configured = engine.setup().use[s];
    pad.health = static_cast<std::uint8_t>(pad.configured ? protocol::SensorHealth::kOk
                                                          : protocol::SensorHealth::kNotAvailable);
    pad.frames = pad.configured ? index + 1 : 0;
    viewer::fill_view_pad(engine.pipeline().sensor(static_cast<dsp::SensorSlot>(s)),
                          engine.result().sensors[s], r.present[s], &pad);
  }
#if TACSE3_HAVE_VIEWER
  if (!impl_->info.has_truth()) return impl_->views.add(v, nullptr);
  const dsp::Pose t = truth_pose_at(impl_->info.truth, r.t_ns);
  viewer::ViewTruth truth;
  truth.q = {t.q.w(), t.q.x(), t.q.y(), t.q.z()};
  truth.p = {t.p.x(), t.p.y(), t.p.z()};
  impl_->views.add(v, &truth);
#endif
}

std::string ReplayView::serve(const config::ListenAddress& listen, const std::string& about) {
#if TACSE3_HAVE_VIEWER
  viewer::ViewServerConfig c;
  c.listen = listen;
  c.assets = viewer::find_viewer_assets(config::executable_dir());
  if (c.assets.empty()) return "the viewer's page is not installed (build tacse3_viewer_assets)";
  viewer::ViewInfo info;
  info.version = kVersion;
  info.board = "recording";
  info.board_file = impl_->info.name;
  info.calibration = about;
  info.controls_off = "a recording: there is nothing to command";
  info.recording = impl_->info.name;
  c.info_json = viewer::view_info_json(info);
  // SIGINT and SIGTERM are taken by sigwait below; the server's threads inherit the mask.
  sigset_t stop;
  sigemptyset(&stop);
  sigaddset(&stop, SIGINT);
  sigaddset(&stop, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop, nullptr);
  const std::size_t frames = impl_->views.size();
  std::string e;
  auto server = viewer::ViewServer::start(c, std::move(impl_->views), &e);
  if (!server) return e;
  std::fprintf(stderr, "tacse3-replay: view: http://%s:%d/ (%zu frames; Ctrl-C stops)\n",
               listen.host.c_str(), listen.port, frames);
  int sig = 0;
  sigwait(&stop, &sig);
  return {};
#else
  (void)listen;
  (void)about;
  return unavailable();
#endif
}

}  // namespace tacse3::tools
