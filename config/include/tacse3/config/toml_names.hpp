// SPDX-License-Identifier: Apache-2.0
// tacse3 config: wording shared by the TOML readers' error messages (calibration and board files).
#pragma once

#include <toml++/toml.h>

#include <string>

namespace tacse3::config {

// "a string", "an integer", "a float", ... : the type a TOML value has, for "got ..." messages.
// Needs toml++ on the include path (the callers parse TOML themselves).
std::string type_name(const toml::node& n);

}  // namespace tacse3::config
