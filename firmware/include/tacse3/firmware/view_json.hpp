// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: the live viewer's JSON documents (docs/viewer.md, "API").
#pragma once

#include <string>

#include "tacse3/firmware/view_snapshot.hpp"

namespace tacse3::firmware {

// GET /api/state and each /api/stream event: the cycle's scalars, one line, no spaces.
std::string view_state_json(const ViewSnapshot& v);
// GET /api/fields: the per-pad grid fields (contact mask, shear, f^z), row-major.
std::string view_fields_json(const ViewSnapshot& v);

}  // namespace tacse3::firmware
