// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: double-precision luma, then the 2x2 box or the [1 3 3 1] filter and 2:1
// decimation (the maths of dsp/luma.hpp).
#pragma once

#include <vector>

#include "tacse3/dsp/luma.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp_ref {

// Luma of one pixel with the pipeline's BT.601 weights, (77 R + 150 G + 29 B) / 256, unrounded.
double luma_ref(double r, double g, double b);

// The working image in double, U8.2 scale (luma * 4), row-major 160x120, NOT rounded. Returns an
// empty vector when dsp::check_frame() rejects the frame.
std::vector<double> frame_to_work_image_ref(
    const dsp::FrameView& in, dsp::WorkImageFilter filter = dsp::WorkImageFilter::kBox);

}  // namespace tacse3::dsp_ref
