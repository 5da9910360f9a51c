// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: the DSP thread's part of the live view.
#include "tacse3/firmware/view_fill.hpp"

namespace tacse3::firmware {

void fill_view_pads(const dsp::DualPipeline& pipeline, const dsp::DualResult& result,
                    const StateOutput& state, std::array<bool, 2> configured,
                    std::array<int, 2> contact_cells, ViewSnapshot* out) noexcept {
  for (std::size_t s = 0; s < 2; ++s) {
    viewer::ViewPad& pad = out->pads[s];
    const bool present = result.present[s];
    const dsp::SensorResult& r = result.sensors[s];
    pad.configured = configured[s];
    pad.health = static_cast<std::uint8_t>(state.health[s]);
    pad.present = present;
    pad.contact = present && contact_cells[s] > 0;
    pad.slipping = present && r.slipping;
    const dsp::Calibration& cal = pipeline.sensor(static_cast<dsp::SensorSlot>(s)).calibration();
    pad.contact_area_m2 = present ? viewer::contact_area_m2(cal, contact_cells[s]) : 0.0;
    pad.tracked_fraction = present ? static_cast<double>(r.tracked_points) / dsp::kGridCount : 0.0;
  }
}

}  // namespace tacse3::firmware
