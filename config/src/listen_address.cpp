// SPDX-License-Identifier: Apache-2.0
// tacse3 config: ADDR:PORT parsing for the live viewer.
#include "tacse3/config/listen_address.hpp"

#include <arpa/inet.h>

#include <charconv>

namespace tacse3::config {

namespace {

// "\"TEXT\": what" (built with append: GCC 12 -O3 warns on "literal" + std::string).
std::string problem(std::string_view text, const char* what) {
  std::string e(1, '"');
  e.append(text).append("\": ").append(what);
  return e;
}

}  // namespace

bool parse_listen_address(std::string_view text, ListenAddress* out, std::string* error) {
  const std::size_t colon = text.rfind(':');
  std::string host = "127.0.0.1";  // a port alone never exposes the board to the network
  std::string_view port_text = text;
  if (colon != std::string_view::npos) {
    host = std::string(text.substr(0, colon));
    port_text = text.substr(colon + 1);
    if (host == "localhost") host = "127.0.0.1";
    in_addr a{};
    if (host.empty() || inet_pton(AF_INET, host.c_str(), &a) != 1) {
      *error = problem(text, "the address must be an IPv4 address such as 127.0.0.1 or 0.0.0.0");
      return false;
    }
  }
  int port = 0;
  const auto [end, ec] =
      std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  if (port_text.empty() || ec != std::errc() || end != port_text.data() + port_text.size() ||
      port < 1 || port > 65535) {
    *error = problem(text, "the port must be a number in 1..65535");
    return false;
  }
  out->host = host;
  out->port = port;
  return true;
}

}  // namespace tacse3::config
