// SPDX-License-Identifier: Apache-2.0
// config tests: the [sim] object names kept in config are the simulator's presets, in its order
// (config may not include sim, so the list is duplicated and checked here).
#include <gtest/gtest.h>

#include <string>

#include "tacse3/config/board_file.hpp"
#include "tacse3/sim/object.hpp"

namespace tc = tacse3::config;

TEST(SimNames, ObjectNamesAreTheSimulatorsPresets) {
  std::string joined;
  for (const char* name : tc::kSimObjectNames) {
    joined += std::string(joined.empty() ? "" : ", ") + name;
    tacse3::sim::ObjectSpec spec;
    EXPECT_TRUE(tacse3::sim::object_preset(name, &spec)) << name;
  }
  EXPECT_EQ(joined, tacse3::sim::object_preset_names());
}
