// SPDX-License-Identifier: Apache-2.0
// tacse3 canmon: CSV, JSON-lines and live terminal outputs.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

#include "monitor.hpp"

namespace tacse3::canmon {

// Fixed-point text of a value with `decimals` digits; "" for NaN (CSV) — callers map it to null
// in JSON. The decimals match each field's LSB, so the text is exact.
std::string fixed(double v, int decimals);

// A unit quaternion as one rotation: angle in [0, 180] degrees about a unit axis (q and -q give
// the same rotation). A rotation under 1e-9 rad has the axis (0, 0, 0).
struct AngleAxisDeg {
  double angle_deg = 0.0;
  double axis[3] = {0.0, 0.0, 0.0};
};
AngleAxisDeg angle_axis_deg(const tp::Quaternion& q);

// Cycle rows (one per complete cycle) with the node's latest Status appended.
class CsvSink final : public Sink {
 public:
  CsvSink(std::FILE* out, const Monitor& m) : out_(out), monitor_(m) {}
  void header();
  void on_cycle(std::uint8_t node, std::uint64_t rx_time_us, const tp::Cycle& c) override;
  void on_message(std::uint8_t, std::uint64_t, const tp::Decoded&) override {}
  void on_error(std::uint64_t, const tp::CanFrame&, tp::Status) override {}
  void on_window(std::uint64_t) override {}

 private:
  std::FILE* out_;
  const Monitor& monitor_;
};

// One JSON object per line: cycle, status, status_contact, status_timing, status_counters,
// command, ack, error, and a stats object per bus-load window and at the end.
class JsonSink final : public Sink {
 public:
  JsonSink(std::FILE* out, const Monitor& m) : out_(out), monitor_(m) {}
  void on_cycle(std::uint8_t node, std::uint64_t rx_time_us, const tp::Cycle& c) override;
  void on_message(std::uint8_t node, std::uint64_t rx_time_us, const tp::Decoded& d) override;
  void on_error(std::uint64_t rx_time_us, const tp::CanFrame& f, tp::Status s) override;
  void on_window(std::uint64_t rx_time_us) override;
  void stats(const char* type);

 private:
  std::FILE* out_;
  const Monitor& monitor_;
};

// Live view: redraws the whole screen (ANSI) at most every `period_ms` of wall time.
class TtySink final : public Sink {
 public:
  TtySink(std::FILE* out, const Monitor& m, std::string source, int period_ms = 100)
      : out_(out), monitor_(m), source_(std::move(source)), period_ms_(period_ms) {}
  void on_cycle(std::uint8_t, std::uint64_t, const tp::Cycle&) override { maybe_draw(); }
  void on_message(std::uint8_t, std::uint64_t, const tp::Decoded&) override { maybe_draw(); }
  void on_error(std::uint64_t, const tp::CanFrame&, tp::Status) override { maybe_draw(); }
  void on_window(std::uint64_t) override {}
  void maybe_draw();
  void draw();

 private:
  std::FILE* out_;
  const Monitor& monitor_;
  std::string source_;
  int period_ms_;
  std::int64_t last_draw_ms_ = -1;
};

// Human summary (stderr at the end of a CSV / JSON run).
void print_summary(std::FILE* out, const Monitor& m);

}  // namespace tacse3::canmon
