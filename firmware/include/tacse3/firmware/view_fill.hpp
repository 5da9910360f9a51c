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

// Fills the per-cycle pad scalars of *out from the pipeline's last result, the pads' |Ω| in it
// and their health. The grid fields and image come from the pad threads (PadStager), which own
// them; the calibration read here is the motion half, the DSP thread's.
void fill_view_pads(const dsp::DualPipeline& pipeline, const dsp::DualResult& result,
                    const StateOutput& state, std::array<bool, 2> configured,
                    std::array<int, 2> contact_cells, ViewSnapshot* out) noexcept;

}  // namespace tacse3::firmware
