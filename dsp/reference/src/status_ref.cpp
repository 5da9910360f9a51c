// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: anchor translation unit of the double-precision reference library.
#include "tacse3/dsp/geometry.hpp"

namespace tacse3::dsp_ref {
// The reference uses the same grid geometry as the fixed-point pipeline.
static_assert(tacse3::dsp::kGridCount == 1200);
}  // namespace tacse3::dsp_ref
