// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: a camera source that plays one scripted motion per recording (the simulated rig).
#pragma once

#include <filesystem>
#include <string>

namespace tacse3::hal {

// What the daemon's recording commands (START/STOP_RECORDING) tell a source that plays a motion
// for each recording: the `sim` backend with a plan ([sim] plan, docs/firmware.md). A real
// camera shows what is in front of it, so the daemon has none for it. Called from one thread
// (the daemon's housekeeping), in the order ready, start, stop.
class RecordedMotion {
 public:
  virtual ~RecordedMotion() = default;
  // "" when a recording may start (a motion is left to play), else why not (logged, and the
  // START_RECORDING is refused before a recording directory is made).
  virtual std::string next_motion_problem() const = 0;
  // The recording in `dir` has started: play the next motion from rest (pads open).
  virtual void start_motion(const std::filesystem::path& dir) = 0;
  // The recording has stopped and its files are closed: back to rest, and write beside it what
  // the rig logged. "" or the error (the recording itself is kept).
  virtual std::string stop_motion() = 0;
};

}  // namespace tacse3::hal
