// SPDX-License-Identifier: Apache-2.0
// tools tests: the pixel pitch fitted from stick translations (tacse3-calibrate) recovers the
// simulator's pitch when the recordings' rig block claims another one.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
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

// The source with a robot's pose noise on its truth (rms 0.05 mm, as tacse3-truth's rebuilt
// truth from an arm's log, docs/truth.md), in every row but the first (the reference).
class NoisyTruthSource final : public tt::FrameSource {
 public:
  NoisyTruthSource(tt::FrameSource& inner, unsigned seed) : inner_(inner), info_(inner.info()) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 0.05e-3 / std::sqrt(3.0));
    for (std::size_t i = 1; i < info_.truth.size(); ++i) {
      info_.truth[i].px += n(rng);
      info_.truth[i].py += n(rng);
      info_.truth[i].pz += n(rng);
    }
  }
  const tt::SourceInfo& info() const noexcept override { return info_; }
  std::string read(std::size_t index, std::array<const tacse3::dsp::FrameView*, 2>* v) override {
    return inner_.read(index, v);
  }

 private:
  tt::FrameSource& inner_;
  tt::SourceInfo info_;
};

}  // namespace

// A stick translation's truth with a robot's noise: the motion's start is found where the truth
// leaves the start position for good, not at the first noisy row, and the pitch comes out.
TEST(PitchFit, NoisyTruthFindsTheMotionsStart) {
  constexpr double kTrue = 0.08;
  auto tx = stick_translation("tx", 0.5, kTrue, 3);
  ASSERT_TRUE(tx);
  NoisyTruthSource noisy(*tx, 7);
  tt::StickShift shift;
  ASSERT_EQ(tt::measure_stick_shift(noisy, &shift), "");
  EXPECT_GT(shift.shift_px.size(), 30u);
  // Within 10 %: the noise of the truth rows (0.05 mm on 0.5 mm) enters the ratio.
  EXPECT_NEAR(shift.pitch_mm() / kTrue, 1.0, 0.1);
}

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
