// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: tacse3-dbcgen, writes the DBC of one node (or the whole table as JSON for the
// Python package) from the message table.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <string>

#include "tacse3/fileio/file_io.hpp"
#include "tacse3/protocol_dbc/dbc_writer.hpp"
#include "tacse3/protocol_dbc/table_json.hpp"
#include "tacse3/tools/cli.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Write the tacse3 CAN DBC (generated from the protocol message table)",
               "tacse3-dbcgen"};
  unsigned node = tacse3::protocol::kDefaultNodeId;
  bool extended = false;
  std::string base = "0x1ACE0000";
  std::string prefix;
  std::string output = "-";
  std::string format = "dbc";
  app.add_option("--node", node, "Node id of the gripper (1..63)")
      ->check(CLI::Range(1u, 63u))
      ->capture_default_str();
  app.add_flag("--extended", extended, "29-bit identifiers (extended_base | node << 5 | message)");
  app.add_option("--extended-base", base, "Base of the 29-bit identifiers (bits 11..28)")
      ->capture_default_str();
  app.add_option("--prefix", prefix, "Prefix for every message name (merging several nodes)");
  app.add_option("--format", format,
                 "dbc, or json: the node-independent message table (python/src/tacse3)")
      ->check(CLI::IsMember({"dbc", "json"}))
      ->capture_default_str();
  app.add_option("-o,--output", output, "Output file, - for stdout")
      ->check(tacse3::tools::non_empty_path())
      ->capture_default_str();
  if (const int rc = tacse3::tools::parse_command_line(app, argc, argv); rc >= 0) return rc;

  tacse3::protocol::dbc::DbcOptions opt;
  opt.endpoint.node_id = static_cast<std::uint8_t>(node);
  opt.message_prefix = prefix;
  if (extended) {
    opt.endpoint.layout.mode = tacse3::protocol::IdMode::kExtended;
    unsigned long b = 0;
    try {
      b = std::stoul(base, nullptr, 0);
    } catch (const std::exception&) {
      std::cerr << "tacse3-dbcgen: --extended-base: not a number: " << base << '\n';
      return 2;
    }
    if (!tacse3::protocol::is_valid_extended_base(static_cast<std::uint32_t>(b)) ||
        b > 0x1FFFFFFFul) {
      std::cerr << "tacse3-dbcgen: --extended-base must have bits 0..10 clear and fit in 29 bits\n";
      return 2;
    }
    opt.endpoint.layout.extended_base = static_cast<std::uint32_t>(b);
  }
  const std::string dbc = format == "json" ? tacse3::protocol::dbc::generate_table_json()
                                           : tacse3::protocol::dbc::generate_dbc(opt);
  if (output == "-") {
    std::cout << dbc;
    return std::cout.good() ? 0 : 1;
  }
  // Atomically: a full disk or a killed run leaves the old file or none, never a part.
  std::string error;
  if (!tacse3::fileio::write_file_atomically(output, dbc, &error)) {
    std::cerr << "tacse3-dbcgen: " << error << '\n';
    return 1;
  }
  return 0;
}
