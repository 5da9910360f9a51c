// SPDX-License-Identifier: Apache-2.0
// tacse3 viewer: what a view shows of one cycle: one fixed-size copy of its scalars, the per-pad
// grid fields and the working luma image (docs/viewer.md). tacse3d's DSP thread fills one at
// most every kViewPeriodNs; tacse3-replay --view fills one per frame.
#pragma once

#include <array>
#include <cstdint>

#include "tacse3/dsp/geometry.hpp"
#include "tacse3/dsp/pipeline.hpp"
#include "tacse3/viewer/snapshot_slot.hpp"

namespace tacse3::viewer {

// The DSP thread publishes at most once per this period (docs/viewer.md: 20 Hz).
inline constexpr std::int64_t kViewPeriodNs = 50'000'000;

struct ViewPad {
  bool configured = false;
  bool present = false;           // this pad took part in the last processed cycle
  bool contact = false;           // Ω is not empty
  bool slipping = false;          // the stick/slip detector's decision (kAuto proxy)
  std::uint8_t health = 0;        // protocol::SensorHealth
  double contact_area_m2 = 0.0;   // |Ω| times the area of one grid cell
  double tracked_fraction = 0.0;  // valid block-flow points / grid points
  std::uint64_t frames = 0;       // frames the capture thread handed over
  std::uint64_t dropped = 0;      // frames lost: camera sequence gaps, full ring, late for pairing
  std::array<std::uint8_t, dsp::kWorkPixels> luma{};  // working image, 8-bit (160 x 120)
  std::array<std::uint8_t, dsp::kGridCount> mask{};   // Ω, 0/1, row-major 40 x 30
  std::array<float, dsp::kGridCount> shear_x{};       // calibrated shear, shear units
  std::array<float, dsp::kGridCount> shear_y{};
  std::array<float, dsp::kGridCount> fz{};  // normal response f^z, f^z units
};

// The engine's counters since the start (the CAN Status carries them modulo 2^16).
struct ViewCounters {
  std::uint64_t cycles_sent = 0;
  std::uint64_t can_send_failures = 0;  // Channel::send refused a frame
  std::uint64_t can_tx_dropped = 0;     // the channel's own count of dropped frames
  std::uint64_t commands = 0;           // commands answered
  std::uint32_t rejected_commands = 0;  // commands refused by validation
};

struct ViewSnapshot {
  std::uint64_t cycle = 0;   // processed samples so far
  std::int64_t t_us = 0;     // sample time of the last cycle (CLOCK_MONOTONIC)
  std::uint8_t state = 0;    // protocol::State
  bool have_result = false;  // at least one cycle was processed
  bool valid = false;        // the last cycle's estimate is valid
  bool single_sensor = false;
  bool calibrated = false;
  std::array<double, 3> w{};                    // rad/s in G
  std::array<double, 3> v{};                    // m/s in G
  std::array<double, 4> q{1.0, 0.0, 0.0, 0.0};  // w, x, y, z
  std::array<double, 3> p{};                    // m
  double confidence = 0.0;
  std::int64_t dsp_us = -1;      // pipeline time of the last cycle
  std::int64_t latency_us = -1;  // frame timestamp -> cycle sent, last cycle (-1: none)
  ViewCounters counters{};
  std::array<ViewPad, 2> pads{};
};

using ViewSlot = SnapshotSlot<ViewSnapshot>;

// Contact area of one sensor: |Ω| flow-grid cells of (320 / kGridWidth) sensor pixels squared.
double contact_area_m2(const dsp::SensorPipeline& p) noexcept;
// The same for |Ω| = contact_cells under calibration cal.
double contact_area_m2(const dsp::Calibration& cal, int contact_cells) noexcept;

// Fills *out's per-cycle fields (all but configured, health, frames and dropped) from one
// sensor's pipeline and its last result (bounded copy, no allocation).
void fill_view_pad(const dsp::SensorPipeline& p, const dsp::SensorResult& r, bool present,
                   ViewPad* out) noexcept;
// fill_view_pad's grid fields and image (luma, mask, shear, fz), from a frame's fields.
void fill_view_pad_fields(const dsp::SensorFields& f, ViewPad* out) noexcept;

}  // namespace tacse3::viewer
