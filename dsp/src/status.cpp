// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: compile-time checks that the shared stage containers stay trivially copyable.
#include <type_traits>

#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {
static_assert(std::is_trivially_copyable_v<WorkImage>,
              "WorkImage is copied by value between stages");
static_assert(std::is_trivially_copyable_v<VectorField>,
              "fields are copied by value between stages");
static_assert(sizeof(VectorField) == 2 * kGridCount * sizeof(std::int32_t), "no padding in fields");
}  // namespace tacse3::dsp
