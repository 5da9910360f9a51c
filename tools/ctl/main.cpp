// SPDX-License-Identifier: Apache-2.0
// tacse3 ctl: tacse3-ctl, sends a command frame to a gripper and waits for its ACK/NACK.
#include <linux/can.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <variant>

#include "tacse3/hal/can/log_channel.hpp"
#include "tacse3/hal/can/socketcan.hpp"
#include "tacse3/hal/can/unix_channel.hpp"
#include "tacse3/protocol/protocol.hpp"
#include "tacse3/tools/cli.hpp"

namespace {

namespace can = tacse3::hal::can;
namespace tp = tacse3::protocol;

// Exit codes (documented in docs/can-protocol.md).
constexpr int kExitOk = 0;
constexpr int kExitError = 1;  // I/O, no CAN, bad log
constexpr int kExitUsage = 2;  // a bad option or argument (parse_command_line returns it too)
constexpr int kExitNack = 3;
constexpr int kExitNoAck = 4;

std::int64_t monotonic_ms() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000 + ts.tv_nsec / 1000000;
}

std::string describe_reply(const tp::Ack& a) {
  char buf[160];
  if (a.command == tp::CommandCode::kQuery) {
    tp::QueryReply r;
    if (tp::decode_query_reply(a, r) != tp::Status::kOk) return "query reply not understood";
    switch (r.item) {
      case tp::QueryItem::kProtocolVersion:
      case tp::QueryItem::kFirmwareVersion:
        std::snprintf(
            buf, sizeof buf, "%s %u.%u.%u",
            r.item == tp::QueryItem::kProtocolVersion ? "protocol version" : "firmware version",
            unsigned{r.version.major}, unsigned{r.version.minor}, unsigned{r.version.patch});
        return buf;
      case tp::QueryItem::kFingerSeparation:
        std::snprintf(buf, sizeof buf, "finger separation %.5f m", r.finger_separation_m);
        return buf;
      case tp::QueryItem::kFusion:
        std::snprintf(buf, sizeof buf, "fusion %s, velocity mode %s",
                      tp::to_string(r.fusion) ? tp::to_string(r.fusion) : "?",
                      tp::to_string(r.velocity_mode) ? tp::to_string(r.velocity_mode) : "?");
        return buf;
      case tp::QueryItem::kStream:
        std::snprintf(buf, sizeof buf,
                      "stream %s, rate divider %u (%.1f Hz), %s frames, %s identifiers",
                      r.stream_enabled ? "enabled" : "disabled", unsigned{r.rate_divider},
                      r.rate_divider > 0 ? 120.0 / r.rate_divider : 0.0,
                      r.fd_mode ? "CAN FD" : "classic", r.extended_ids ? "29-bit" : "11-bit");
        return buf;
    }
    return "unknown query item";
  }
  if (a.command == tp::CommandCode::kStartRecording) {
    std::snprintf(buf, sizeof buf, "acknowledged: recording rec-%05u",
                  a.data[0] | (static_cast<unsigned>(a.data[1]) << 8));
    return buf;
  }
  return "acknowledged";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Send a command to a tacse3 gripper and wait for its ACK.\n"
      "Examples:\n  tacse3-ctl --iface can0 --node 1 tare\n"
      "  tacse3-ctl --iface can0 --node 2 finger-separation 0.085\n"
      "  tacse3-ctl --socket /tmp/tacse3-can.sock --node 1 reset-pose   (tacse3d --can-socket)\n"
      "  tacse3-ctl --log-out - --node 1 tare            (print the frame as candump -L)\n"
      "  tacse3-ctl --log-out cmd.log --ack-from replies.log --node 1 query stream\n"
      "  tacse3-ctl --iface can0 --node 1 record-start 7   (then: record-stop)\n"
      "Exit status: 0 ACK, 1 error, 2 usage, 3 NACK, 4 no ACK before the timeout.",
      "tacse3-ctl"};
  std::string iface, socket_path, log_out, ack_from, base = "0x1ACE0000";
  unsigned node = 1;
  int timeout_ms = 250;
  int seq = -1;
  bool extended = false, fd = false, no_wait = false;
  auto* dst = app.add_option_group("destination");
  dst->add_option("--iface", iface, "SocketCAN interface, e.g. can0");
  dst->add_option("--socket", socket_path,
                  "Unix socket of a tacse3d started with --can-socket PATH (host without CAN)")
      ->check(tacse3::tools::non_empty_path());
  dst->add_option("--log-out", log_out, "Write the command as a candump -L line (file or -)")
      ->check(tacse3::tools::non_empty_path());
  dst->require_option(1);
  app.add_option("--ack-from", ack_from,
                 "With --log-out: read the gripper's reply from this candump -L log (or -)")
      ->check(tacse3::tools::non_empty_path());
  app.add_option("--node", node, "Node id of the gripper")
      ->check(CLI::Range(1u, 63u))
      ->capture_default_str();
  app.add_flag("--extended", extended, "29-bit identifiers");
  app.add_option("--extended-base", base, "Base of the 29-bit identifiers")->capture_default_str();
  app.add_flag("--fd", fd, "Send as a CAN FD frame (8 bytes, BRS)");
  app.add_option("--timeout-ms", timeout_ms, "How long to wait for the ACK")
      ->check(CLI::Range(1, 60000))
      ->capture_default_str();
  app.add_option("--seq", seq, "Sequence number 0..15 (default: from the clock)")
      ->check(CLI::Range(0, 15));
  app.add_flag("--no-wait", no_wait, "Send only, do not wait for the ACK");
  app.require_subcommand(1);

  tp::Command cmd;
  app.add_subcommand("tare", "Re-take the reference (tare both sensors)")->callback([&] {
    cmd.code = tp::CommandCode::kTare;
  });
  app.add_subcommand("reset-pose", "Reset the integrated pose to identity")->callback([&] {
    cmd.code = tp::CommandCode::kResetPose;
  });
  double separation = 0.0;
  auto* sep = app.add_subcommand("finger-separation", "Set the finger separation");
  // In metres, like the protocol: "85" is most likely millimetres, so the error says so. The
  // message is appended piecewise ("lit" + std::string trips GCC 12's -Wrestrict at -O3).
  const CLI::Validator metres(
      [](std::string& v) {
        double m = 0.0;
        std::string msg;
        if (!CLI::detail::lexical_cast(v, m)) {
          msg.append("not a number of metres: ").append(v);
          return msg;
        }
        if (m >= 0.001 && m <= 0.25) return msg;
        msg.append("finger-separation takes metres, 0.001 .. 0.25; got ").append(v);
        if (m > 1.0 && m <= 250.0) {
          char buf[32];
          std::snprintf(buf, sizeof(buf), "%g", m / 1000.0);
          msg.append(" (for ").append(v).append(" mm give ").append(buf).append(")");
        }
        return msg;
      },
      "METRES");
  sep->add_option("metres", separation, "Distance between the pads, 0.001 .. 0.25 m")
      ->required()
      ->check(metres);
  sep->callback([&] {
    cmd.code = tp::CommandCode::kSetFingerSeparation;
    cmd.finger_separation_m = separation;
  });
  std::string method, mode;
  auto* fus = app.add_subcommand("fusion", "Set the fusion method and the velocity-proxy mode");
  fus->add_option("method", method, "joint | paper")
      ->required()
      ->check(CLI::IsMember({"joint", "paper"}));
  fus->add_option("mode", mode, "auto | velocity | displacement")
      ->required()
      ->check(CLI::IsMember({"auto", "velocity", "displacement"}));
  fus->callback([&] {
    cmd.code = tp::CommandCode::kSetFusion;
    cmd.fusion = method == "paper" ? tp::FusionMethod::kPaper : tp::FusionMethod::kJoint;
    cmd.velocity_mode = mode == "velocity"       ? tp::VelocityMode::kVelocity
                        : mode == "displacement" ? tp::VelocityMode::kDisplacement
                                                 : tp::VelocityMode::kAuto;
  });
  unsigned divider = 1;
  auto* div = app.add_subcommand("rate-divider", "Stream at 120 Hz / N");
  div->add_option("N", divider, "1 .. 120")->required()->check(CLI::Range(1u, 120u));
  div->callback([&] {
    cmd.code = tp::CommandCode::kSetRateDivider;
    cmd.rate_divider = static_cast<std::uint8_t>(divider);
  });
  std::string onoff;
  auto* str = app.add_subcommand("stream", "Enable or disable the cyclic stream");
  str->add_option("state", onoff, "on | off")->required()->check(CLI::IsMember({"on", "off"}));
  str->callback([&] {
    cmd.code = tp::CommandCode::kSetStream;
    cmd.stream_enabled = onoff == "on";
  });
  std::string item;
  auto* q = app.add_subcommand("query", "Query version or configuration");
  q->add_option("item", item,
                "protocol-version | firmware-version | finger-separation | fusion | stream")
      ->required()
      ->check(CLI::IsMember(
          {"protocol-version", "firmware-version", "finger-separation", "fusion", "stream"}));
  q->callback([&] {
    cmd.code = tp::CommandCode::kQuery;
    cmd.query = item == "firmware-version"    ? tp::QueryItem::kFirmwareVersion
                : item == "finger-separation" ? tp::QueryItem::kFingerSeparation
                : item == "fusion"            ? tp::QueryItem::kFusion
                : item == "stream"            ? tp::QueryItem::kStream
                                              : tp::QueryItem::kProtocolVersion;
  });
  unsigned recording = 0;
  auto* rec = app.add_subcommand("record-start",
                                 "Start recording to the board's record directory, rec-NNNNN");
  rec->add_option("N", recording, "Recording number 0 .. 65535")
      ->required()
      ->check(CLI::Range(0u, 65535u));
  rec->callback([&] {
    cmd.code = tp::CommandCode::kStartRecording;
    cmd.recording_number = static_cast<std::uint16_t>(recording);
  });
  app.add_subcommand("record-stop", "Stop the recording")->callback([&] {
    cmd.code = tp::CommandCode::kStopRecording;
  });
  if (const int rc = tacse3::tools::parse_command_line(app, argc, argv); rc >= 0) return rc;

  tp::TxConfig tx;
  tx.endpoint.node_id = static_cast<std::uint8_t>(node);
  tx.frame_mode = fd ? tp::FrameMode::kFd : tp::FrameMode::kClassic;
  if (extended) {
    tx.endpoint.layout.mode = tp::IdMode::kExtended;
    unsigned long b = 1;
    try {
      b = std::stoul(base, nullptr, 0);
    } catch (const std::exception&) {
    }
    if (b > tp::kExtendedIdMask || !tp::is_valid_extended_base(static_cast<std::uint32_t>(b))) {
      std::cerr << "tacse3-ctl: --extended-base must have bits 0..10 clear and fit 29 bits\n";
      return kExitUsage;
    }
    tx.endpoint.layout.extended_base = static_cast<std::uint32_t>(b);
  }
  cmd.sequence = static_cast<std::uint8_t>(seq >= 0 ? seq : (monotonic_ms() & 0x0F));
  const char* name = tp::to_string(cmd.code);

  tp::CanFrame frame;
  if (tp::encode(cmd, tx, frame) != tp::Status::kOk) {
    std::cerr << "tacse3-ctl: " << name << ": the protocol cannot encode this argument\n";
    return kExitUsage;
  }

  std::string error;
  std::unique_ptr<can::Channel> out;
  std::unique_ptr<can::Channel> in;
  if (!iface.empty()) {
    can::SocketCanOptions so;
    so.fd = fd;
    // Only this node's Ack identifier, as a data frame: the mask includes the EFF and RTR flags,
    // so the kernel passes neither the other id length nor remote frames.
    const std::uint32_t ack_id =
        tp::compose_id(tx.endpoint.layout, tx.endpoint.node_id, tp::MessageId::kAck);
    so.filters.push_back(
        extended ? can::SocketCanFilter{ack_id | CAN_EFF_FLAG,
                                        CAN_EFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG}
                 : can::SocketCanFilter{ack_id, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG});
    auto s = can::SocketCanChannel::open(iface, so, error);
    if (!s) {
      std::cerr << "tacse3-ctl: " << error << '\n';
      return kExitError;
    }
    out = std::move(s);
  } else if (!socket_path.empty()) {
    auto s = can::UnixSocketChannel::connect(socket_path, error);
    if (!s) {
      std::cerr << "tacse3-ctl: " << error << '\n';
      return kExitError;
    }
    out = std::move(s);
  } else {
    auto w = can::LogChannel::open("", log_out, error);
    if (!w) {
      std::cerr << "tacse3-ctl: " << error << '\n';
      return kExitError;
    }
    out = std::move(w);
    if (!ack_from.empty()) {
      auto r = can::LogChannel::open(ack_from, "", error);
      if (!r) {
        std::cerr << "tacse3-ctl: " << error << '\n';
        return kExitError;
      }
      in = std::move(r);
    }
  }
  if (!out->send(frame)) {
    std::cerr << "tacse3-ctl: sending " << name << " failed: " << out->last_error() << '\n';
    return kExitError;
  }
  can::Channel& rx_channel = in ? *in : *out;
  const bool live = !iface.empty() || !socket_path.empty();  // else: logs, read to their end
  if (no_wait || (!live && in == nullptr)) {
    std::cerr << "tacse3-ctl: sent " << name << " to node " << node << " (seq "
              << unsigned{cmd.sequence} << ")\n";
    if (!no_wait) {
      std::cerr << "tacse3-ctl: not waiting for the ACK: a log file carries no replies (talk to "
                   "tacse3d --can-socket PATH with --socket PATH, or use --iface)\n";
    }
    return kExitOk;
  }

  const std::int64_t deadline = monotonic_ms() + timeout_ms;
  std::uint64_t replies_from_node = 0;  // any ACK/NACK of this node, for the message below
  for (;;) {
    const std::int64_t left = deadline - monotonic_ms();
    if (live && left <= 0) break;  // a log is read to its end, no timeout
    can::RxFrame rx;
    const can::RxResult r = rx_channel.receive(rx, static_cast<int>(left > 0 ? left : 0));
    if (r == can::RxResult::kEnd && !socket_path.empty()) {
      std::cerr << "tacse3-ctl: tacse3d closed the connection on " << socket_path
                << " before answering " << name << " (stopped, or too many peers connected)\n";
      return kExitError;
    }
    if (r == can::RxResult::kTimeout || r == can::RxResult::kEnd) break;
    if (r == can::RxResult::kError) {
      std::cerr << "tacse3-ctl: " << rx_channel.last_error() << '\n';
      return kExitError;
    }
    tp::Decoded d;
    if (tp::decode(rx.frame, tx.endpoint.layout, d) != tp::Status::kOk) continue;
    const auto* a = std::get_if<tp::Ack>(&d.payload);
    if (a == nullptr || d.node_id != node) continue;
    ++replies_from_node;
    if (a->command != cmd.code || a->sequence != cmd.sequence) continue;
    if (a->result == tp::AckCode::kAck) {
      std::cout << "node " << node << ": " << name << ' ' << describe_reply(*a) << " (seq "
                << unsigned{cmd.sequence} << ")\n";
      return kExitOk;
    }
    const char* why = tp::to_string(a->result);
    std::cerr << "tacse3-ctl: node " << node << " rejected " << name << ": "
              << (why != nullptr ? why : "reason unknown") << " ("
              << static_cast<unsigned>(a->result) << ", seq " << unsigned{cmd.sequence} << ")\n";
    return kExitNack;
  }
  std::cerr << "tacse3-ctl: no ACK from node " << node << " for " << name << " (seq "
            << unsigned{cmd.sequence} << ")";
  if (!iface.empty()) {
    std::cerr << " within " << timeout_ms
              << " ms: is the gripper powered, on this bus, with this node id and bit rate?\n";
  } else if (!socket_path.empty()) {
    std::cerr << " within " << timeout_ms << " ms on " << socket_path
              << ": does that tacse3d use node id " << node << "?\n";
  } else if (replies_from_node == 0) {
    // The usual case: the log is what a tacse3d --can-log wrote, and that daemon never saw the
    // command, because a log file only carries frames one way.
    std::cerr << " in " << ack_from << ": it holds no ACK or NACK from node " << node
              << " at all. A log carries no replies: the gripper must receive the command "
                 "(tacse3d --can-log reads none). Talk to it live: tacse3d --can-socket PATH "
                 "with tacse3-ctl --socket PATH, or --iface on a CAN or vcan bus\n";
  } else {
    std::cerr << " in " << ack_from << '\n';
  }
  return kExitNoAck;
}
