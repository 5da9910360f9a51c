// SPDX-License-Identifier: Apache-2.0
// firmware tests: decode a sequence of sent CAN frames into cycles, status frames and acks, in
// order, the way a controller sees them (CycleReassembler + decode).
#pragma once

#include <string>
#include <variant>
#include <vector>

#include "tacse3/protocol/candump.hpp"
#include "tacse3/protocol/codec.hpp"
#include "tacse3/protocol/reassembler.hpp"

namespace tacse3::test {

struct BusEvents {
  struct Event {
    enum Kind { kCycle, kStatus, kAck, kOther } kind = kOther;
    std::size_t index = 0;  // into cycles / statuses / acks
  };
  std::vector<Event> order;
  std::vector<protocol::Cycle> cycles;
  std::vector<protocol::StatusMsg> statuses;  // every Status (0x08) frame
  std::vector<protocol::Ack> acks;
  std::vector<protocol::TimingMsg> timings;
  protocol::ReassemblerStats reassembly;
  std::size_t undecodable = 0;

  void feed(const protocol::CanFrame& f) {
    protocol::Cycle c;
    if (reassembler_.feed(f, c) == protocol::CycleReassembler::Result::kComplete) {
      order.push_back({Event::kCycle, cycles.size()});
      cycles.push_back(c);
    }
    protocol::Decoded d;
    if (protocol::decode(f, protocol::IdLayout{}, d) != protocol::Status::kOk) {
      ++undecodable;
    } else if (const auto* s = std::get_if<protocol::StatusMsg>(&d.payload)) {
      order.push_back({Event::kStatus, statuses.size()});
      statuses.push_back(*s);
    } else if (const auto* a = std::get_if<protocol::Ack>(&d.payload)) {
      order.push_back({Event::kAck, acks.size()});
      acks.push_back(*a);
    } else if (const auto* t = std::get_if<protocol::TimingMsg>(&d.payload)) {
      timings.push_back(*t);
    }
    reassembly = reassembler_.stats();
  }
  // Feeds every line of a candump -L log; false if a line does not parse.
  bool feed_log(const std::string& text) {
    std::size_t pos = 0;
    while (pos < text.size()) {
      std::size_t end = text.find('\n', pos);
      if (end == std::string::npos) end = text.size();
      if (end > pos) {
        protocol::LogRecord r;
        if (protocol::parse_candump_line(std::string_view(text).substr(pos, end - pos), r) !=
            protocol::Status::kOk) {
          return false;
        }
        feed(r.frame);
      }
      pos = end + 1;
    }
    return true;
  }

 private:
  protocol::CycleReassembler reassembler_;
};

}  // namespace tacse3::test
