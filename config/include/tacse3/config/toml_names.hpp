// SPDX-License-Identifier: Apache-2.0
// tacse3 config: wording shared by the TOML readers' error messages (calibration and board files).
#pragma once

#include <toml++/toml.h>

#include <string>
#include <string_view>

namespace tacse3::config {

// "a string", "an integer", "a float", ... : the type a TOML value has, for "got ..." messages.
// Needs toml++ on the include path (the callers parse TOML themselves).
std::string type_name(const toml::node& n);

// Checks what toml++ 3.3 (Debian 12) must not see: its whitespace test reaches undefined
// behaviour (an "unreachable" branch) on a non-ASCII character, and it makes that test outside
// strings and comments, after a backslash and the blanks after it, and in its error paths. So a
// non-ASCII character there is refused, and a text with any is first parsed as a copy with those
// bytes made ASCII, whose syntax error is returned. TOML allows non-ASCII only in strings and
// comments, so nothing valid is refused. Returns "" or "ORIGIN:LINE:COLUMN: message".
std::string check_toml_characters(std::string_view text, const std::string& origin);

}  // namespace tacse3::config
