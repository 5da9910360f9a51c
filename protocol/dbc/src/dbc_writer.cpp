// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: DBC generation from the constexpr message table.
#include "tacse3/protocol_dbc/dbc_writer.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "tacse3/protocol/codec.hpp"
#include "tacse3/protocol/message_table.hpp"

namespace tacse3::protocol::dbc {
namespace {

constexpr const char* kGripperNode = "TACSE3";
constexpr const char* kControllerNode = "CONTROLLER";

int decimals_of(double factor) {
  const std::string s = format_decimal(factor);
  const auto dot = s.find('.');
  return dot == std::string::npos ? 0 : static_cast<int>(s.size() - dot - 1);
}

// raw * factor printed with the factor's number of decimals, trailing zeros removed.
std::string format_scaled(std::int64_t raw, double factor) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals_of(factor), static_cast<double>(raw) * factor);
  std::string s = buf;
  if (s.find('.') != std::string::npos) {
    while (!s.empty() && s.back() == '0') s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

std::string quoted(std::string_view s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"')
      out += '\'';
    else
      out += c;
  }
  return out + "\"";
}

std::uint32_t dbc_id(const Endpoint& ep, MessageId id) {
  const std::uint32_t raw = compose_id(ep.layout, ep.node_id, id);
  return ep.layout.mode == IdMode::kExtended ? (raw | 0x80000000u) : raw;
}

// Range written to the DBC: the valid range; for fields with an invalid marker the marker stays
// outside it and is named in a VAL_ table.
void signal_line(std::ostream& o, const SignalDef& s, const char* receiver) {
  o << " SG_ " << s.name << ' ';
  if (s.role == Role::kMultiplexor) {
    o << "M ";
  } else if (s.mux >= 0) {
    o << 'm' << s.mux << ' ';
  }
  o << ": " << s.start << '|' << static_cast<unsigned>(s.length) << "@1"
    << (s.is_signed ? '-' : '+') << " (" << format_decimal(s.factor) << ",0) ["
    << format_scaled(s.raw_min, s.factor) << '|' << format_scaled(s.raw_max, s.factor) << "] "
    << quoted(s.unit) << ' ' << receiver << '\n';
}

}  // namespace

std::string format_decimal(double v) {
  char buf[400];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed);
  return std::string(buf, r.ptr);
}

std::string generate_dbc(const DbcOptions& options) {
  const Endpoint& ep = options.endpoint;
  std::ostringstream o;
  o << "VERSION \"tacse3 protocol " << unsigned{kProtocolVersionMajor} << '.'
    << unsigned{kProtocolVersionMinor} << '.' << unsigned{kProtocolVersionPatch} << " node "
    << unsigned{ep.node_id} << "\"\n\n\n";
  o << "NS_ :\n\tNS_DESC_\n\tCM_\n\tBA_DEF_\n\tBA_\n\tVAL_\n\tBA_DEF_DEF_\n\tVAL_TABLE_\n"
       "\tSIG_VALTYPE_\n\tBO_TX_BU_\n\tSG_MUL_VAL_\n\n";
  o << "BS_:\n\n";
  o << "BU_: " << kGripperNode << ' ' << kControllerNode << "\n\n\n";

  for (const MessageDef& m : kMessages) {
    const bool from_gripper = m.sender == Sender::kGripper;
    o << "BO_ " << dbc_id(ep, m.id) << ' ' << options.message_prefix << m.name << ": "
      << unsigned{m.length} << ' ' << (from_gripper ? kGripperNode : kControllerNode) << '\n';
    for (const SignalDef& s : m.signals) {
      signal_line(o, s, from_gripper ? kControllerNode : kGripperNode);
    }
    o << '\n';
  }
  o << '\n';

  o << "CM_ \"tacse3 gripper CAN protocol, generated from protocol/include/tacse3/protocol/"
       "message_table.hpp by tacse3-dbcgen. Do not edit. See docs/can-protocol.md. Every "
       "frame carries a CRC-8/SAE-J1850 over its 4-byte identifier word and preceding bytes.\";\n";
  o << "CM_ BU_ " << kGripperNode << " \"tacse3 gripper board, node id " << unsigned{ep.node_id}
    << "\";\n";
  o << "CM_ BU_ " << kControllerNode << " \"Arm controller\";\n";
  for (const MessageDef& m : kMessages) {
    o << "CM_ BO_ " << dbc_id(ep, m.id) << ' ' << quoted(m.comment) << ";\n";
    for (const SignalDef& s : m.signals) {
      if (s.comment.empty()) continue;
      o << "CM_ SG_ " << dbc_id(ep, m.id) << ' ' << s.name << ' ' << quoted(s.comment) << ";\n";
    }
  }

  o << "BA_DEF_ \"BusType\" STRING ;\n";
  o << "BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\n";
  o << "BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\","
       "\"J1939PG\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\","
       "\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"StandardCAN_FD\","
       "\"ExtendedCAN_FD\";\n";
  o << "BA_DEF_DEF_ \"BusType\" \"CAN FD\";\n";
  o << "BA_DEF_DEF_ \"GenMsgCycleTime\" 0;\n";
  o << "BA_DEF_DEF_ \"VFrameFormat\" \"StandardCAN\";\n";
  o << "BA_ \"BusType\" \"CAN FD\";\n";
  const bool ext = ep.layout.mode == IdMode::kExtended;
  for (const MessageDef& m : kMessages) {
    if (m.nominal_rate_hz > 0.0) {
      o << "BA_ \"GenMsgCycleTime\" BO_ " << dbc_id(ep, m.id) << ' '
        << static_cast<int>(1000.0 / m.nominal_rate_hz) << ";\n";
    }
    const int format = m.fd_only ? (ext ? 15 : 14) : (ext ? 1 : 0);
    o << "BA_ \"VFrameFormat\" BO_ " << dbc_id(ep, m.id) << ' ' << format << ";\n";
  }
  for (const MessageDef& m : kMessages) {
    for (const SignalDef& s : m.signals) {
      if (s.values.empty()) continue;
      o << "VAL_ " << dbc_id(ep, m.id) << ' ' << s.name;
      for (const ValueName& v : s.values) o << ' ' << v.raw << ' ' << quoted(v.name);
      o << " ;\n";
    }
  }
  return o.str();
}

}  // namespace tacse3::protocol::dbc
