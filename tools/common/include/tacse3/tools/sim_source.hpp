// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: a simulated recording rendered in memory (tacse3_sim), as a replay frame source.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tacse3/recording/recording.hpp"
#include "tacse3/sim/simulator.hpp"
#include "tacse3/tools/source.hpp"

namespace tacse3::tools {

// The sim_labels.csv row of one pad at one frame: contact, slip and patch geometry from the
// simulator's ground truth (docs/recording-format.md).
recording::SimLabel sim_label(const sim::Simulator& simulator, sim::Sensor sensor,
                              std::int64_t index, std::int64_t t_ns);

// Exactly what `tacse3-sim` would write for the same configuration (frame times, truth,
// sim_labels), but the frames are rendered on demand and never touch the disk. A rendered frame
// is kept, within a budget shared by every SimSource of the process (kFrameCacheBytes), so a
// calibration's later passes over the same recording do not simulate it again. Reading an index
// not after the previous one that is not kept restarts the simulation from frame 0 (the slide
// regime integrates a lag, so frames are rendered in order).
class SimSource final : public FrameSource {
 public:
  // channels: 1 (grey, the fastest) or 3 (RGB).
  static std::unique_ptr<SimSource> create(const sim::SimConfig& config, const std::string& name,
                                           int channels, std::string* error);
  const SourceInfo& info() const noexcept override { return info_; }
  std::string read(std::size_t index, std::array<const dsp::FrameView*, 2>* views) override;
  const sim::Simulator& simulator() const noexcept { return *sim_; }
  ~SimSource() override;
  SimSource(const SimSource&) = delete;
  SimSource& operator=(const SimSource&) = delete;

  // The process-wide budget of kept frames: 1 GiB, the quick accuracy benchmark's calibration
  // sets several times over (a grey pad frame is 75 KiB).
  static constexpr std::size_t kFrameCacheBytes = std::size_t{1} << 30;
  // Frames of this source read from the cache (tests).
  std::size_t cache_hits() const noexcept { return cache_hits_; }

 private:
  SimSource() = default;
  std::string simulate_to(std::size_t index);
  void keep(std::size_t index);
  std::unique_ptr<sim::Simulator> sim_;
  SourceInfo info_;
  int channels_ = 1;
  std::array<std::vector<std::uint8_t>, 2> buf_;
  std::array<dsp::FrameView, 2> views_{};
  std::int64_t last_ = -1;
  // Per frame index, both pads' rendered frames (empty: not kept).
  std::vector<std::array<std::vector<std::uint8_t>, 2>> cache_;
  std::size_t cached_bytes_ = 0;  // this source's share of the budget
  std::size_t cache_hits_ = 0;
};

}  // namespace tacse3::tools
