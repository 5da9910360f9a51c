// SPDX-License-Identifier: Apache-2.0
// tacse3 canmon: tacse3-canmon, decode a tacse3 CAN bus or candump -L log (live view, CSV, JSON).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "monitor.hpp"
#include "output.hpp"
#include "tacse3/hal/can/log_channel.hpp"
#include "tacse3/hal/can/socketcan.hpp"
#include "tacse3/tools/cli.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) {
  g_stop = 1;
}

}  // namespace

int main(int argc, char** argv) {
  namespace can = tacse3::hal::can;
  namespace tp = tacse3::protocol;
  using tacse3::canmon::Monitor;

  CLI::App app{
      "Decode tacse3 gripper CAN traffic: twist, pose, status, ACKs; counter gaps, CRC failures "
      "and bus load.\nExamples:\n  tacse3-canmon --iface can0\n  candump -L can0 | "
      "tacse3-canmon --log -\n  tacse3-canmon --log run.log --format json > run.jsonl",
      "tacse3-canmon"};
  std::string iface, log_path, format = "auto", base = "0x1ACE0000";
  int node = 0;
  bool extended = false, fd = false;
  double bitrate = 500000.0, data_bitrate = 2000000.0, duration_s = 0.0;
  auto* src = app.add_option_group("source");
  src->add_option("--iface", iface, "SocketCAN interface, e.g. can0");
  src->add_option("--log", log_path, "candump -L log file, - for stdin")
      ->check(tacse3::tools::non_empty_path());
  src->require_option(1);
  app.add_option("--node", node, "Only this node id (default: every node)")
      ->check(CLI::Range(0, 63));
  app.add_flag("--extended", extended, "29-bit identifiers");
  app.add_option("--extended-base", base, "Base of the 29-bit identifiers")->capture_default_str();
  app.add_flag("--fd", fd, "Open the SocketCAN interface with CAN FD frames enabled");
  app.add_option("--format", format, "auto (tty on a terminal, else csv), tty, csv or json")
      ->check(CLI::IsMember({"auto", "tty", "csv", "json"}))
      ->capture_default_str();
  app.add_option("--bitrate", bitrate, "Nominal bit rate for the bus load")->capture_default_str();
  app.add_option("--data-bitrate", data_bitrate, "CAN FD data-phase bit rate")
      ->capture_default_str();
  app.add_option("--duration", duration_s,
                 "Stop after this many seconds (live interface; 0 = never)");
  if (const int rc = tacse3::tools::parse_command_line(app, argc, argv); rc >= 0) return rc;

  tacse3::canmon::MonitorOptions opt;
  opt.node = node;
  opt.timing.nominal_bps = bitrate;
  opt.timing.data_bps = data_bitrate;
  if (extended) {
    opt.layout.mode = tp::IdMode::kExtended;
    unsigned long b = 0;
    try {
      b = std::stoul(base, nullptr, 0);
    } catch (const std::exception&) {
      b = 1;
    }
    if (b > tp::kExtendedIdMask || !tp::is_valid_extended_base(static_cast<std::uint32_t>(b))) {
      std::cerr << "tacse3-canmon: --extended-base must have bits 0..10 clear and fit 29 bits\n";
      return 2;
    }
    opt.layout.extended_base = static_cast<std::uint32_t>(b);
  }

  std::string error;
  std::unique_ptr<can::Channel> channel;
  std::string source;
  if (!iface.empty()) {
    can::SocketCanOptions so;
    so.fd = fd;
    channel = can::SocketCanChannel::open(iface, so, error);
    source = iface;
  } else {
    channel = can::LogChannel::open(log_path, "", error);
    source = log_path == "-" ? "stdin" : log_path;
  }
  if (!channel) {
    std::cerr << "tacse3-canmon: " << error << '\n';
    return 1;
  }

  if (format == "auto") format = ::isatty(STDOUT_FILENO) != 0 ? "tty" : "csv";
  Monitor monitor(opt);
  std::unique_ptr<tacse3::canmon::Sink> sink;
  tacse3::canmon::JsonSink* json = nullptr;
  tacse3::canmon::TtySink* tty = nullptr;
  if (format == "csv") {
    auto s = std::make_unique<tacse3::canmon::CsvSink>(stdout, monitor);
    s->header();
    sink = std::move(s);
  } else if (format == "json") {
    auto s = std::make_unique<tacse3::canmon::JsonSink>(stdout, monitor);
    json = s.get();
    sink = std::move(s);
  } else {
    auto s = std::make_unique<tacse3::canmon::TtySink>(stdout, monitor, source);
    tty = s.get();
    sink = std::move(s);
  }

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const bool live = !iface.empty();
  std::uint64_t first_us = 0;
  int rc = 0;
  while (g_stop == 0) {
    can::RxFrame rx;
    const can::RxResult r = channel->receive(rx, 100);
    if (r == can::RxResult::kTimeout) {
      if (tty != nullptr) tty->maybe_draw();
      continue;
    }
    if (r == can::RxResult::kEnd) break;
    if (r == can::RxResult::kError) {
      std::cerr << "tacse3-canmon: " << channel->last_error() << '\n';
      rc = 1;
      break;
    }
    if (first_us == 0) first_us = rx.time_us;
    monitor.ingest(rx, *sink);
    if (live && duration_s > 0 && rx.time_us - first_us >= duration_s * 1e6) break;
  }
  if (tty != nullptr) tty->draw();
  if (json != nullptr) json->stats("summary");
  // The decoded frames are the result: a write error on stdout (a full disk) must not exit 0.
  rc = tacse3::tools::finish_stdout("tacse3-canmon", rc);
  if (auto* log = dynamic_cast<can::LogChannel*>(channel.get());
      log != nullptr && log->bad_lines() > 0) {
    std::cerr << "tacse3-canmon: skipped " << log->bad_lines()
              << " lines that are not candump -L\n";
  }
  tacse3::canmon::print_summary(stderr, monitor);
  return rc;
}
