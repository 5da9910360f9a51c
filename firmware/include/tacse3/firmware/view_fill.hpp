// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: the DSP thread's part of the live view: the per-pad fields of its snapshot
// (docs/viewer.md).
#pragma once

#include <array>

#include "tacse3/dsp/pipeline.hpp"
#include "tacse3/firmware/health.hpp"
#include "tacse3/viewer/snapshot_slot.hpp"
#include "tacse3/viewer/view_snapshot.hpp"

namespace tacse3::firmware {

using viewer::ViewSlot;
using viewer::ViewSnapshot;

// Fills every pad field of *out from the pipeline's last result and the pads' health (bounded
// copy, no allocation).
void fill_view_pads(const dsp::DualPipeline& pipeline, const dsp::DualResult& result,
                    const StateOutput& state, std::array<bool, 2> configured,
                    ViewSnapshot* out) noexcept;

}  // namespace tacse3::firmware
