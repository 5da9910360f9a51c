// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: --dump-fields: per-frame pipeline fields as NumPy .npy files (docs/replay.md).
#pragma once

#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "tacse3/dsp/pipeline.hpp"
#include "tacse3/tools/npy.hpp"

namespace tacse3::tools {

// One .npy per field and sensor under DIR/<sensor>/, shape (frames, 30, 40[, c]) on the
// 40 x 30 flow grid, plus DIR/t_ns.npy and DIR/index.json describing every file.
class FieldDumper {
 public:
  // Creates DIR (and DIR/left, DIR/right for the sensors used). Error names the path.
  std::string open(const std::filesystem::path& dir, std::int64_t frames,
                   const std::array<bool, 2>& sensors, double pixel_pitch_mm);
  // Appends one frame: each used sensor's fields (zeros for a sensor without a frame).
  std::string append(std::int64_t t_ns, const std::array<const dsp::SensorFields*, 2>& fields);
  std::string close();

  // Field names in file order (for docs/tests): displacement, smoothed, valid, density, d, r, k,
  // force, contact_mask, contact_points.
  static std::vector<std::string> field_names();

 private:
  std::filesystem::path dir_;
  std::array<bool, 2> sensors_{false, false};
  NpyWriter t_ns_;
  std::array<std::vector<std::unique_ptr<NpyWriter>>, 2> files_;
  std::vector<float> scratch_;
  std::vector<std::uint8_t> scratch_u8_;
};

}  // namespace tacse3::tools
