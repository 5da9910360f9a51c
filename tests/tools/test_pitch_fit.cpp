// SPDX-License-Identifier: Apache-2.0
// tools tests: the pixel pitch fitted from stick translations (tacse3-calibrate) recovers the
// simulator's pitch when the recordings' rig block claims another one.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "tacse3/tools/bench.hpp"
#include "tacse3/tools/pitch_fit.hpp"
#include "tacse3/tools/sim_source.hpp"

namespace tt = tacse3::tools;

namespace {

// A short stick translation (tacse3-sim --motion MOTION --magnitude MM --regime stick) rendered
// at `pitch_mm`.
std::unique_ptr<tt::SimSource> stick_translation(const char* motion, double mm, double pitch_mm,
                                                 std::uint64_t seed) {
  tt::SimCase c;
  c.motion = motion;
  c.magnitude = mm;
  c.seed = seed;
  c.approach_s = 0.05;
  c.grasp_s = 0.2;
  c.settle_s = 0.05;
  c.hold_s = 0.2;
  tacse3::sim::SimConfig sc;
  std::string err = tt::make_sim_config(c, &sc);
  EXPECT_EQ(err, "");
  sc.scenario.regime = tacse3::sim::Regime::kStick;
  sc.rig.pixel_pitch_mm = pitch_mm;
  auto s = tt::SimSource::create(sc, c.label(), 1, &err);
  EXPECT_TRUE(s) << err;
  return s;
}

}  // namespace

TEST(PitchFit, RecoversTheRenderedPitchNotTheClaimedOne) {
  constexpr double kTrue = 0.08, kClaimed = 0.10;
  auto tx = stick_translation("tx", 0.5, kTrue, 3);
  auto ty = stick_translation("ty", -0.6, kTrue, 4);
  ASSERT_TRUE(tx && ty);
  tt::PitchOverrideSource tx_claim(*tx, kClaimed), ty_claim(*ty, kClaimed);
  EXPECT_TRUE(tt::is_stick_translation(tx_claim.info()));
  tt::PitchFit fit;
  ASSERT_EQ(tt::fit_pixel_pitch({&tx_claim, &ty_claim}, 2, false, &fit), "");
  std::printf("%s", tt::format_pitch(fit).c_str());
  EXPECT_EQ(fit.claimed_mm, kClaimed);
  EXPECT_EQ(fit.recordings.size(), 2u);
  // Within three of the fit's own standard errors (the scatter of the two recordings' pitches),
  // which must itself be small: 0.16 % off with a 0.28 % error when this was written.
  EXPECT_LT(fit.relative_se, 0.01);
  EXPECT_NEAR(fit.pitch_mm / kTrue, 1.0, 3.0 * fit.relative_se);
}

// Only pure translations below kExciteTranslationMm count; a set without one is refused with what
// to record.
TEST(PitchFit, ASetWithoutStickTranslationsIsRefused) {
  auto slide = stick_translation("tx", 1.5, 0.1, 5);
  ASSERT_TRUE(slide);
  EXPECT_FALSE(tt::is_stick_translation(slide->info()));
  tt::PitchFit fit;
  const std::string e = tt::fit_pixel_pitch({slide.get()}, 1, false, &fit);
  EXPECT_NE(e.find("the recordings do not determine pixel_pitch_m: no stick translation"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("record a translation along x or y of 0.2-1.0 mm without rotation"),
            std::string::npos)
      << e;
  EXPECT_EQ(e.find("rotation_scale"), std::string::npos) << e;
  EXPECT_NE(e.find("--pixel-pitch MM"), std::string::npos) << e;
}
