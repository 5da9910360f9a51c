// SPDX-License-Identifier: Apache-2.0
// tools tests: SimSource keeps the frames it rendered, and a later pass over them (a
// calibration's) gives the same frames and labels as a source that simulates them afresh.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tacse3/tools/bench.hpp"
#include "tacse3/tools/sim_source.hpp"

namespace tt = tacse3::tools;

namespace {

// A short slide (the slide regime integrates a lag: its frames depend on every earlier step).
std::unique_ptr<tt::SimSource> short_slide() {
  const tt::SimCase c{.motion = "rz",
                      .magnitude = 20.0,
                      .seed = 3,
                      .hold_s = 0.1,
                      .approach_s = 0.05,
                      .grasp_s = 0.2,
                      .settle_s = 0.05};
  tacse3::sim::SimConfig sc;
  std::string err = tt::make_sim_config(c, &sc);
  EXPECT_EQ(err, "");
  auto s = tt::SimSource::create(sc, c.label(), 1, &err);
  EXPECT_TRUE(s) << err;
  return s;
}

using Frames = std::vector<std::array<std::vector<std::uint8_t>, 2>>;

// Reads the frames at `indices` in that order and copies both pads' pixels.
Frames read_all(tt::SimSource& s, const std::vector<std::size_t>& indices) {
  Frames out;
  for (const std::size_t i : indices) {
    std::array<const tacse3::dsp::FrameView*, 2> v{};
    EXPECT_EQ(s.read(i, &v), "") << i;
    auto& f = out.emplace_back();
    for (std::size_t k = 0; k < 2; ++k) {
      if (v[k] != nullptr) f[k].assign(v[k]->data, v[k]->data + v[k]->size_bytes);
    }
  }
  return out;
}

std::vector<std::size_t> in_order(std::size_t n) {
  std::vector<std::size_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = i;
  return v;
}

bool same_labels(const tt::SourceInfo& a, const tt::SourceInfo& b) {
  if (a.labels.size() != b.labels.size()) return false;
  for (std::size_t i = 0; i < a.labels.size(); ++i) {
    const auto &x = a.labels[i], &y = b.labels[i];
    if (x.index != y.index || x.t_ns != y.t_ns || x.sensor != y.sensor ||
        x.in_contact != y.in_contact || x.slipping != y.slipping || x.area_mm2 != y.area_mm2)
      return false;
  }
  return true;
}

TEST(SimSource, ASecondPassReadsTheKeptFramesUnchanged) {
  auto kept = short_slide();
  auto fresh = short_slide();
  ASSERT_TRUE(kept && fresh);
  const std::size_t n = kept->info().frame_count();
  ASSERT_GT(n, 40u);
  const Frames first = read_all(*kept, in_order(n));
  EXPECT_EQ(kept->cache_hits(), 0u);
  const Frames second = read_all(*kept, in_order(n));
  EXPECT_EQ(kept->cache_hits(), n) << "every frame of the second pass comes from the cache";
  const Frames reference = read_all(*fresh, in_order(n));
  ASSERT_EQ(second.size(), reference.size());
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_EQ(first[i], reference[i]) << "frame " << i;
    ASSERT_EQ(second[i], reference[i]) << "frame " << i;
  }
  EXPECT_FALSE(kept->info().labels.empty());
  EXPECT_TRUE(same_labels(kept->info(), fresh->info())) << "the labels of the whole recording";
}

// Frames skipped by the caller are simulated but not rendered, so not kept: reading one later
// restarts the simulation, and its pixels are still those of a fresh source.
TEST(SimSource, AFrameSkippedThenReadIsTheFreshSourcesFrame) {
  auto s = short_slide();
  auto fresh = short_slide();
  ASSERT_TRUE(s && fresh);
  const std::size_t n = s->info().frame_count();
  std::vector<std::size_t> evens, odds;
  for (std::size_t i = 0; i < n; ++i) (i % 2 == 0 ? evens : odds).push_back(i);
  (void)read_all(*s, evens);
  const Frames late = read_all(*s, odds);  // each odd frame restarts from 0 or continues
  const Frames all = read_all(*fresh, in_order(n));
  for (std::size_t j = 0; j < odds.size(); ++j) ASSERT_EQ(late[j], all[odds[j]]) << odds[j];
  const Frames again = read_all(*s, in_order(n));  // everything kept now
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(again[i], all[i]) << i;
}

}  // namespace
