// SPDX-License-Identifier: Apache-2.0
// tacse3 config: the live viewer's listen address, as given to `tacse3d --http` or the board
// file's [viewer] listen (docs/viewer.md).
#pragma once

#include <string>
#include <string_view>

namespace tacse3::config {

struct ListenAddress {
  std::string host;  // an IPv4 address literal; "127.0.0.1" when only a port was given
  int port = 0;      // 1..65535
};

// "PORT", "ADDR:PORT" or "localhost:PORT" with ADDR an IPv4 literal (0.0.0.0 = every
// interface). false with *error saying what is wrong (the caller names the option or key).
bool parse_listen_address(std::string_view text, ListenAddress* out, std::string* error);

}  // namespace tacse3::config
