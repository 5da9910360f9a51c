// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: the message table as JSON, for decoders in other languages (python/).
#pragma once

#include <string>

namespace tacse3::protocol::dbc {

// Every message and signal of the table (ids, bit positions, scaling, ranges, invalid markers,
// roles, multiplexing, value names) plus the protocol version and identifier layout, as one JSON
// object. Deterministic and one signal per line, so the committed copy diffs readably.
std::string generate_table_json();

}  // namespace tacse3::protocol::dbc
