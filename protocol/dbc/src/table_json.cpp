// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: the message table written as JSON (tacse3-dbcgen --format json).
#include "tacse3/protocol_dbc/table_json.hpp"

#include <sstream>

#include "tacse3/protocol/codec.hpp"
#include "tacse3/protocol/message_table.hpp"
#include "tacse3/protocol_dbc/dbc_writer.hpp"

namespace tacse3::protocol::dbc {
namespace {

std::string quoted(std::string_view s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

const char* invalid_name(Invalid i) {
  switch (i) {
    case Invalid::kMostNegative:
      return "most_negative";
    case Invalid::kAllOnes:
      return "all_ones";
    case Invalid::kNone:
      break;
  }
  return "none";
}

const char* role_name(Role r) {
  switch (r) {
    case Role::kFlag:
      return "flag";
    case Role::kEnum:
      return "enum";
    case Role::kCount:
      return "count";
    case Role::kCounter:
      return "counter";
    case Role::kCrc:
      return "crc";
    case Role::kMultiplexor:
      return "multiplexor";
    case Role::kValue:
      break;
  }
  return "value";
}

void signal_json(std::ostream& o, const SignalDef& s) {
  o << "{\"name\": " << quoted(s.name) << ", \"start\": " << s.start
    << ", \"length\": " << static_cast<unsigned>(s.length)
    << ", \"signed\": " << (s.is_signed ? "true" : "false")
    << ", \"factor\": " << format_decimal(s.factor) << ", \"raw_min\": " << s.raw_min
    << ", \"raw_max\": " << s.raw_max << ", \"unit\": " << quoted(s.unit) << ", \"invalid\": \""
    << invalid_name(s.invalid) << "\", \"role\": \"" << role_name(s.role)
    << "\", \"mux\": " << s.mux << ", \"values\": [";
  for (std::size_t i = 0; i < s.values.size(); ++i) {
    o << (i == 0 ? "" : ", ") << '[' << s.values[i].raw << ", " << quoted(s.values[i].name) << ']';
  }
  o << "]}";
}

void message_json(std::ostream& o, const MessageDef& m) {
  o << "    {\"id\": " << static_cast<unsigned>(m.id) << ", \"name\": " << quoted(m.name)
    << ", \"length\": " << static_cast<unsigned>(m.length)
    << ", \"fd_only\": " << (m.fd_only ? "true" : "false") << ", \"sender\": \""
    << (m.sender == Sender::kGripper ? "gripper" : "controller")
    << "\", \"comment\": " << quoted(m.comment) << ",\n     \"signals\": [\n";
  for (std::size_t i = 0; i < m.signals.size(); ++i) {
    o << "      ";
    signal_json(o, m.signals[i]);
    o << (i + 1 < m.signals.size() ? ",\n" : "\n");
  }
  o << "     ]}";
}

}  // namespace

std::string generate_table_json() {
  std::ostringstream o;
  o << "{\n  \"protocol_version\": [" << static_cast<unsigned>(kProtocolVersionMajor) << ", "
    << static_cast<unsigned>(kProtocolVersionMinor) << ", "
    << static_cast<unsigned>(kProtocolVersionPatch) << "],\n"
    << "  \"message_id_bits\": " << kMessageIdBits << ",\n"
    << "  \"node_id_bits\": " << kNodeIdBits << ",\n"
    << "  \"default_extended_base\": " << kDefaultExtendedBase << ",\n"
    << "  \"messages\": [\n";
  for (std::size_t i = 0; i < kMessages.size(); ++i) {
    message_json(o, kMessages[i]);
    o << (i + 1 < kMessages.size() ? ",\n" : "\n");
  }
  o << "  ]\n}\n";
  return o.str();
}

}  // namespace tacse3::protocol::dbc
