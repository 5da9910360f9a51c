// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: dsp::SlipPayback (kAuto payback in the fused twist) against hand-computed
// sequences and against dsp_ref::SlipPaybackRef.
#include <gtest/gtest.h>

#include <random>

#include "tacse3/dsp/slip_payback.hpp"
#include "tacse3/dsp_ref/motion_ref.hpp"

namespace tacse3::dsp {
namespace {

constexpr double kDt = 1.0 / 120.0;

Vector6d twist(double wz, double vx) {
  Vector6d xi = Vector6d::Zero();
  xi(2) = wz;
  xi(3) = vx;
  return xi;
}

SlipPayback::Frame stuck(const Vector6d& chosen, const Vector6d& velocity) {
  SlipPayback::Frame f;
  f.chosen = chosen;
  f.velocity = velocity;
  f.differs = true;
  f.contact = true;
  return f;
}

// 30 stuck frames read 0.5 rad/s and 2 mm/s more with the velocity proxy; the onset frame is the
// last of them. The deficit is paid as D/left per frame over the next k frames, from the onset.
TEST(SlipPayback, PaysTheDeficitBackOverCatchupFramesFromTheOnset) {
  SlipPayback p;
  p.configure(12);
  const Vector6d chosen = twist(0.1, 0.0), velocity = twist(0.6, 2e-3);
  for (int k = 0; k < 29; ++k) EXPECT_EQ(p.update(stuck(chosen, velocity), kDt), chosen);
  SlipPayback::Frame onset = stuck(chosen, velocity);
  onset.onset = true;
  const Vector6d d = 30 * kDt * (velocity - chosen);
  Vector6d paid = p.update(onset, kDt) - chosen;
  EXPECT_NEAR(paid(2), d(2) / 12 / kDt, 1e-12);
  EXPECT_EQ(p.frames_left(), 11);
  SlipPayback::Frame slipping;
  slipping.contact = true;
  slipping.chosen = velocity;
  slipping.velocity = velocity;
  for (int k = 0; k < 11; ++k) paid += p.update(slipping, kDt) - velocity;
  // Every frame paid the same share (D/12); the total is the deficit, rate × Δt.
  EXPECT_NEAR(paid(2) * kDt, d(2), 1e-12);
  EXPECT_NEAR(paid(3) * kDt, d(3), 1e-15);
  EXPECT_EQ(p.frames_left(), 0);
  EXPECT_NEAR(p.deficit().norm(), 0.0, 1e-15);
  EXPECT_EQ(p.update(slipping, kDt), velocity);  // nothing left to pay
}

TEST(SlipPayback, AConfirmedStickContactLossOrResetDropsTheDeficit) {
  const Vector6d chosen = Vector6d::Zero(), velocity = twist(1.0, 0.0);
  for (int how = 0; how < 3; ++how) {
    SlipPayback p;
    p.configure(4);
    for (int k = 0; k < 10; ++k) (void)p.update(stuck(chosen, velocity), kDt);
    ASSERT_GT(p.deficit()(2), 0.0);
    SlipPayback::Frame f = stuck(chosen, velocity);
    if (how == 0) f.confirmed = true;
    if (how == 1) f.contact = false;
    if (how == 2) p.reset();
    const Vector6d out = p.update(f, kDt);
    if (how < 2) {
      EXPECT_EQ(out, chosen) << how;
      EXPECT_EQ(p.deficit(), Vector6d::Zero()) << how;
    }
    // A later onset has nothing (or only the frames after the drop) to pay.
    SlipPayback::Frame onset = stuck(chosen, chosen);
    onset.onset = true;
    const Vector6d after = p.update(onset, kDt);
    const double left = how == 2 ? 1.0 * kDt : 0.0;  // reset keeps the frame booked after it
    EXPECT_NEAR(after(2) * kDt * 4, left, 1e-12) << how;
  }
}

// A stick confirmed while a payback is under way (an unloaded contact settles within the catch-up
// window after a short slide) does not cut the payback: the slide was already detected.
TEST(SlipPayback, AStickConfirmedDuringAPaybackDoesNotCutIt) {
  for (const bool ref_side : {false, true}) {
    SlipPayback p;
    p.configure(8);
    dsp_ref::SlipPaybackRef r(8);
    const Vector6d chosen = Vector6d::Zero(), velocity = twist(0.9, 1e-3);
    double paid = 0.0;
    auto step = [&](const SlipPayback::Frame& f) {
      const Vector6d out = ref_side ? r.update(f.chosen, f.velocity, f.differs, f.contact, f.onset,
                                               f.confirmed, false, kDt)
                                    : p.update(f, kDt);
      paid += (out(2) - f.chosen(2)) * kDt;
    };
    for (int k = 0; k < 20; ++k) step(stuck(chosen, velocity));
    SlipPayback::Frame onset = stuck(chosen, chosen);
    onset.onset = true;
    step(onset);
    for (int k = 0; k < 7; ++k) {
      SlipPayback::Frame f = stuck(chosen, chosen);
      f.confirmed = k >= 2;  // confirmed from the third frame after the onset on
      step(f);
    }
    EXPECT_NEAR(paid, 20 * kDt * velocity(2), 1e-12) << (ref_side ? "reference" : "fixed");
    // Once the payback is over, a confirmation drops what was booked: a later onset pays nothing.
    SlipPayback::Frame late = stuck(chosen, velocity);
    late.confirmed = true;
    step(late);
    step(onset);
    for (int k = 0; k < 8; ++k) step(stuck(chosen, chosen));
    EXPECT_NEAR(paid, 20 * kDt * velocity(2), 1e-12) << (ref_side ? "reference" : "fixed");
  }
}

// A second sensor's onset during a payback spreads what is left over a full window again.
TEST(SlipPayback, ASecondOnsetRestartsTheSpread) {
  SlipPayback p;
  p.configure(10);
  const Vector6d velocity = twist(1.2, 0.0);
  for (int k = 0; k < 20; ++k) (void)p.update(stuck(Vector6d::Zero(), velocity), kDt);
  SlipPayback::Frame onset;
  onset.contact = true;
  onset.onset = true;
  (void)p.update(onset, kDt);
  (void)p.update(SlipPayback::Frame{Vector6d::Zero(), Vector6d::Zero(), false, true, false, false},
                 kDt);
  const double remaining = p.deficit()(2);
  EXPECT_EQ(p.frames_left(), 8);
  const Vector6d second = p.update(onset, kDt);
  EXPECT_EQ(p.frames_left(), 9);
  EXPECT_NEAR(second(2), remaining / 10 / kDt, 1e-12);
}

// The fixed pipeline's class and the reference's take the same decisions on any sequence.
TEST(SlipPayback, MatchesTheReferenceOnRandomSequences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> val(-1.0, 1.0);
  std::bernoulli_distribution rare(0.04), often(0.6), almost(0.97);
  for (int trial = 0; trial < 20; ++trial) {
    const int k = 1 + trial % 13;
    SlipPayback p;
    p.configure(k);
    dsp_ref::SlipPaybackRef r(k);
    for (int frame = 0; frame < 400; ++frame) {
      SlipPayback::Frame f;
      for (int i = 0; i < 6; ++i) {
        f.chosen(i) = val(rng);
        f.velocity(i) = val(rng);
      }
      f.differs = often(rng);
      f.contact = almost(rng);
      f.onset = rare(rng);
      f.confirmed = rare(rng);
      if (!f.differs) f.velocity = f.chosen;
      const Vector6d a = p.update(f, kDt);
      const Vector6d b =
          r.update(f.chosen, f.velocity, f.differs, f.contact, f.onset, f.confirmed, false, kDt);
      ASSERT_LT((a - b).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial << " frame " << frame;
    }
  }
}

}  // namespace
}  // namespace tacse3::dsp
