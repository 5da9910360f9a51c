// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: DBC generation from the message table (host tooling, allocates).
#pragma once

#include <string>

#include "tacse3/protocol/ids.hpp"

namespace tacse3::protocol::dbc {

struct DbcOptions {
  Endpoint endpoint{};         // node id and identifier layout the DBC is written for
  std::string message_prefix;  // prepended to every message name (to merge several nodes)
};

// The DBC text for one node. Deterministic: the same options give the same bytes.
std::string generate_dbc(const DbcOptions& options);

// Shortest decimal (no exponent) that reads back as `v`; DBC readers such as candied accept
// only plain decimals.
std::string format_decimal(double v);

}  // namespace tacse3::protocol::dbc
