// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: umbrella header for the controller-side CAN protocol library.
#pragma once

#include "tacse3/protocol/bus_load.hpp"
#include "tacse3/protocol/can_frame.hpp"
#include "tacse3/protocol/candump.hpp"
#include "tacse3/protocol/codec.hpp"
#include "tacse3/protocol/commands.hpp"
#include "tacse3/protocol/crc8.hpp"
#include "tacse3/protocol/ids.hpp"
#include "tacse3/protocol/message_table.hpp"
#include "tacse3/protocol/reassembler.hpp"
#include "tacse3/protocol/status.hpp"
#include "tacse3/protocol/types.hpp"
