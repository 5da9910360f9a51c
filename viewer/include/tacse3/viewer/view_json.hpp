// SPDX-License-Identifier: Apache-2.0
// tacse3 viewer: the live viewer's JSON documents (docs/viewer.md, "API").
#pragma once

#include <array>
#include <string>
#include <string_view>

#include "tacse3/viewer/view_snapshot.hpp"

namespace tacse3::viewer {

// A recording's truth at a frame (truth.csv, docs/recording-format.md): the object's pose in G.
struct ViewTruth {
  std::array<double, 4> q{1.0, 0.0, 0.0, 0.0};  // w, x, y, z
  std::array<double, 3> p{};                    // m
};

// GET /api/state and each /api/stream event: the cycle's scalars, one line, no spaces; with a
// "truth" object after "sensors" when `truth` is not null (a recording's frame).
std::string view_state_json(const ViewSnapshot& v, const ViewTruth* truth = nullptr);
// GET /api/info: what does not change while the daemon runs.
struct ViewInfo {
  std::string version;       // tacse3d's
  std::string board;         // the board's name
  std::string board_file;    // the file it came from
  std::string calibration;   // the calibration file, empty: the built-in defaults
  std::string controls_off;  // why POST /api/command answers 403; empty: the controls are on
  std::string recording;     // tacse3-replay --view: the recording shown; empty: live (no key)
};
std::string view_info_json(const ViewInfo& info);
// A JSON string literal of `text`: quotes, backslashes and control characters escaped.
std::string json_quote(std::string_view text);
// GET /api/fields: the per-pad grid fields (contact mask, shear, f^z), row-major.
std::string view_fields_json(const ViewSnapshot& v);

}  // namespace tacse3::viewer
