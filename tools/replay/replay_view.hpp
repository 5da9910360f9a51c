// SPDX-License-Identifier: Apache-2.0
// tacse3-replay --view: the web view of a recording (docs/viewer.md, "A recording"): one view
// per replayed frame, served by the viewer library until SIGINT or SIGTERM.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "tacse3/config/listen_address.hpp"
#include "tacse3/tools/replay.hpp"
#include "tacse3/tools/source.hpp"

namespace tacse3::tools {

class ReplayView {
 public:
  ReplayView(const SourceInfo& info, bool calibrated);
  ~ReplayView();
  ReplayView(const ReplayView&) = delete;
  ReplayView& operator=(const ReplayView&) = delete;

  // Why this build cannot serve (built without cpp-httplib, libturbojpeg or nlohmann-json);
  // null when it can.
  static const char* unavailable() noexcept;

  // ReplaySinks::on_frame: keeps frame `index`'s view.
  void add(std::size_t index, const FrameResult& r, const Replayer& engine);
  // Serves the kept frames on `listen` until SIGINT or SIGTERM; `about` names the recording on
  // /api/info. Empty on a clean stop, else why it could not serve.
  std::string serve(const config::ListenAddress& listen, const std::string& about);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tacse3::tools
