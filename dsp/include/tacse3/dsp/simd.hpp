// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: which SIMD instruction set the vectorised fixed-point stages run on.
//
// The vectorised stages (frame_to_work_image, ...) are bit-exact with their *_scalar variants on
// every target; these functions let tests and benchmarks run each compiled target in turn.
#pragma once

namespace tacse3::dsp {

// Number of instruction sets compiled into this build that this CPU runs, best first: on x86
// AVX2, SSE4 and the single-lane fallback "SCALAR" (those the CPU has); on Arm "NEON" only.
int simd_target_count() noexcept;

// Name of target i (0 <= i < simd_target_count()), e.g. "AVX2"; "" for any other i.
const char* simd_target_name(int i) noexcept;

// Makes the vectorised stages use target i from now on (tests, benchmarks); any i outside
// [0, simd_target_count()) restores the best one. Not thread-safe: call it with no stage running.
void simd_select_target(int i) noexcept;

}  // namespace tacse3::dsp
