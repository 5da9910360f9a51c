// SPDX-License-Identifier: Apache-2.0
// tacse3 viewer: the live viewer's HTTP server (cpp-httplib): the page, /api/state,
// /api/stream (Server-Sent Events), /api/fields and the pads' JPEG images (docs/viewer.md).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "tacse3/config/listen_address.hpp"
#include "tacse3/viewer/command_mailbox.hpp"
#include "tacse3/viewer/view_json.hpp"
#include "tacse3/viewer/view_snapshot.hpp"

namespace tacse3::viewer {

struct ViewServerConfig {
  config::ListenAddress listen;
  std::filesystem::path assets;  // folder holding index.html, viewer.js, viewer.css, uPlot
  std::string info_json = "{}";  // GET /api/info (view_info_json)
  int threads = 8;               // connections served at once
  int max_waiting = 8;           // accepted connections waiting for a thread; more get 503
  int max_streams = 4;           // /api/stream clients at once; more get 503
  int write_timeout_ms = 2000;   // a client that takes no data this long is dropped
  int nice = 10;                 // the server threads' niceness (the DSP thread is SCHED_FIFO)
  // POST /api/command: the DSP thread's mailbox; null: the controls are off and the endpoint
  // answers 403 with `controls_off` (which names the board key that enables them).
  CommandMailbox* commands = nullptr;
  std::string controls_off = "the controls are off: set [viewer] controls = true in the board file";
  protocol::Endpoint endpoint{};  // this node: commands are built and validated as its CAN frames
  int command_timeout_ms = 1000;  // no answer from the DSP thread this long: 504
};

// POST /api/command's body, as the CAN command it stands for. false with *error (the HTTP 400
// message) for anything but the documented forms.
bool parse_web_command(const std::string& body, protocol::Command* command, std::string* error);

// The viewer assets folder: <exe_dir>/../share/tacse3/viewer (the package's, and the build
// tree's for a program one folder deep), else the build tree's own. Empty when none holds an
// index.html.
std::filesystem::path find_viewer_assets(const std::filesystem::path& exe_dir);

struct Rendered;

// A recording's frames as tacse3-replay --view serves them: each rendered once when added (its
// JSON and JPEGs), and kept with its snapshot for /api/fields (about 90 kB a frame).
class RecordedViews {
 public:
  RecordedViews();
  ~RecordedViews();
  RecordedViews(RecordedViews&&) noexcept;
  RecordedViews& operator=(RecordedViews&&) noexcept;

  // Appends the next frame; `truth`, when not null, is the recording's truth at its time.
  void add(const ViewSnapshot& snapshot, const ViewTruth* truth);
  std::size_t size() const noexcept;
  const std::shared_ptr<const Rendered>& at(std::size_t i) const;
  // GET /api/frames: {"frames":N,"states":[every frame's /api/state document]}.
  std::string frames_json() const;

 private:
  struct Frames;
  std::unique_ptr<Frames> frames_;
};

class ViewServer {
 public:
  // Loads the assets, binds and starts serving, reading snapshots from `slot` (this server is its
  // only reader). null with *error ("ADDR:PORT: address already in use", a missing asset).
  static std::unique_ptr<ViewServer> start(const ViewServerConfig& config, ViewSlot& slot,
                                           std::string* error);
  // The same page for a recording: /api/state, /api/fields and the images take ?frame=N, and
  // /api/frames gives every frame's state; no stream and no controls (docs/viewer.md).
  static std::unique_ptr<ViewServer> start(const ViewServerConfig& config, RecordedViews recording,
                                           std::string* error);
  ~ViewServer();  // stops serving and joins every thread
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  struct Stats {
    std::uint64_t snapshots = 0;            // snapshots taken from the slot and rendered
    std::uint64_t streams_refused = 0;      // /api/stream answered 503 (max_streams reached)
    std::uint64_t streams_dropped = 0;      // streams ended because the client did not take data
    std::uint64_t connections_refused = 0;  // answered 503 at once: max_waiting were waiting
  };
  Stats stats() const noexcept;

  struct Impl;

 private:
  explicit ViewServer(std::unique_ptr<Impl> impl);
  static std::unique_ptr<ViewServer> serve(std::unique_ptr<Impl> impl, std::string* error);
  std::unique_ptr<Impl> impl_;
};

}  // namespace tacse3::viewer
