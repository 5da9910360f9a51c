// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp (private): how the Highway kernels (*_simd.cpp) are dispatched.
//
// x86 (TACSE3_SIMD_DYNAMIC=1): every kernel is compiled for SSE4, AVX2 and the single-lane
// fallback, and the first call picks the best one the CPU runs (libhwy's CPU detection), so the
// host programs run on any x86-64. Arm (TACSE3_SIMD_DYNAMIC=0): NEON only, chosen at compile
// time: every Raspberry Pi 4/5 has it (the armhf build compiles the kernels with
// -mfpu=neon-vfpv4), and the firmware then needs Highway's headers only, no libhwy at run time.
// dsp/CMakeLists.txt sets the macros.
#pragma once

#if TACSE3_SIMD_DYNAMIC
#define TACSE3_SIMD_EXPORT(f) HWY_EXPORT(f)
#define TACSE3_SIMD_CALL(f) HWY_DYNAMIC_DISPATCH(f)
#else
#define TACSE3_SIMD_EXPORT(f) static_assert(true)
#define TACSE3_SIMD_CALL(f) HWY_STATIC_DISPATCH(f)
#endif
