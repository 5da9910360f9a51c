// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: counters for heap allocations made through operator new and malloc/calloc/realloc.
#pragma once

#include <cstdint>

namespace tacse3::test {

// Number of heap allocations observed since the last reset. Counting is process-wide and
// relaxed-atomic; tests reset it after initialisation and read it after the measured loop.
std::uint64_t allocation_count() noexcept;
void reset_allocation_count() noexcept;

}  // namespace tacse3::test
