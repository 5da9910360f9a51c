// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: the DSP thread's part of the live view.
#include "tacse3/firmware/view_fill.hpp"

namespace tacse3::firmware {

void fill_view_pads(const dsp::DualPipeline& pipeline, const dsp::DualResult& result,
                    const StateOutput& state, std::array<bool, 2> configured,
                    ViewSnapshot* out) noexcept {
  for (std::size_t s = 0; s < 2; ++s) {
    viewer::ViewPad& pad = out->pads[s];
    pad.configured = configured[s];
    pad.health = static_cast<std::uint8_t>(state.health[s]);
    viewer::fill_view_pad(pipeline.sensor(static_cast<dsp::SensorSlot>(s)), result.sensors[s],
                          result.present[s], &pad);
  }
}

}  // namespace tacse3::firmware
