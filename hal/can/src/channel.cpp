// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: names of the bus states (status text, logs).
#include "tacse3/hal/can/channel.hpp"

namespace tacse3::hal::can {

const char* to_string(BusState s) noexcept {
  switch (s) {
    case BusState::kErrorActive:
      return "error-active";
    case BusState::kErrorWarning:
      return "error-warning";
    case BusState::kErrorPassive:
      return "error-passive";
    case BusState::kBusOff:
      return "bus-off";
    case BusState::kDown:
      return "down";
  }
  return "?";
}

}  // namespace tacse3::hal::can
