// SPDX-License-Identifier: Apache-2.0
// tacse3-truth: clock sync from a candump log and by angular-speed cross-correlation, on
// constructed signals whose offset is known exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "tacse3/protocol/protocol.hpp"
#include "tacse3/tools/truth/clock_sync.hpp"

namespace {

namespace tr = tacse3::tools::truth;
namespace proto = tacse3::protocol;
constexpr double kPi = std::numbers::pi;

std::string line(std::uint64_t time_us, const proto::CanFrame& f) {
  proto::LogRecord rec;
  rec.time_us = time_us;
  std::memcpy(rec.iface.data(), "can1", 5);
  rec.frame = f;
  char buf[proto::kCandumpLineMax + 2];
  const std::size_t n = proto::format_candump_line(rec, buf, sizeof(buf));
  return std::string(buf, n) + "\n";
}

// A controller-side log: cycles every 8333 µs from sample time 1 s; each cycle's frames arrive
// offset + latency + (+-100 µs alternating) later; StatusTiming every 12 cycles reporting
// `reported_p50_us` (negative: not available).
std::string can_log(std::int64_t offset_us, std::int64_t latency_us, double reported_p50_us,
                    int cycles) {
  std::string text;
  proto::TxConfig tx;
  for (int k = 0; k < cycles; ++k) {
    proto::Cycle c;
    c.timestamp_us = 1'000'000 + static_cast<std::uint64_t>(k) * 8333;
    proto::CycleFrames out;
    EXPECT_EQ(proto::encode_cycle(c, static_cast<std::uint8_t>(k), tx, out), proto::Status::kOk);
    const std::int64_t arrival = static_cast<std::int64_t>(c.timestamp_us) + offset_us +
                                 latency_us + (k % 2 == 0 ? 100 : -100);
    for (std::size_t i = 0; i < out.count; ++i) {
      text += line(static_cast<std::uint64_t>(arrival) + i * 130, out.frames[i]);
    }
    if (k % 12 == 0) {
      proto::TimingMsg m;
      m.dsp_time_s = 0.002;
      m.latency_p50_s = reported_p50_us < 0 ? std::nan("") : reported_p50_us * 1e-6;
      m.latency_p99_s = std::nan("");
      proto::CanFrame f;
      EXPECT_EQ(proto::encode(m, tx, f), proto::Status::kOk);
      text += line(static_cast<std::uint64_t>(arrival) + 700, f);
    }
  }
  return text;
}

TEST(CanSync, OffsetIsTheMedianArrivalLagLessTheReportedLatency) {
  // Arrival of the Timestamp (first) frame = sample + offset + 4500 µs +- 100 µs.
  const std::string text = can_log(7'250'000, 4500, 4500.0, 121);
  tr::CanSync s;
  ASSERT_EQ(tr::sync_by_can_log(text, "c.log", 1'000'000'000, 1'995'000'000, &s), "");
  EXPECT_EQ(s.cycles, 120u);  // sample times 1.000 .. 1.992 s; the 121st is past the recording
  EXPECT_EQ(s.latency_reports, 11u);
  EXPECT_NEAR(s.latency_s, 4.5e-3, 1e-9);
  // 60 lags at +100 µs and 60 at -100 µs: the median is their mean.
  EXPECT_EQ(s.offset_ns, (7'250'000) * std::int64_t{1000});
  EXPECT_NEAR(s.spread_s, 1.4826 * 100e-6, 1e-9);
}

TEST(CanSync, WithoutALatencyReportTheLatencyIsTakenAsZero) {
  tr::CanSync s;
  ASSERT_EQ(tr::sync_by_can_log(can_log(-900'000, 4500, -1.0, 120), "c.log", 0, 3'000'000'000, &s),
            "");
  EXPECT_EQ(s.latency_reports, 0u);
  EXPECT_EQ(s.offset_ns, (-900'000 + 4500) * std::int64_t{1000});
}

TEST(CanSync, ALogOfAnotherRecordingOrGarbageIsRefused) {
  tr::CanSync s;
  const std::string e =
      tr::sync_by_can_log(can_log(0, 0, -1.0, 20), "c.log", 5'000'000'000, 6'000'000'000, &s);
  EXPECT_NE(e.find("c.log: no complete tacse3 cycle"), std::string::npos) << e;
  EXPECT_NE(e.find("(20 outside it)"), std::string::npos) << e;
  EXPECT_EQ(tr::sync_by_can_log("(1.0) can0 021#00\nhello\n", "c.log", 0, 1, &s),
            "c.log line 2: not a candump -L line (\"(seconds.micros) iface id#data\")");
}

// A smooth rotation profile: angle(t) about a fixed axis, three bumps of different sizes so that
// the speed pattern does not repeat.
double profile(double t) {
  const auto bump = [](double x, double c, double w) {
    const double u = (x - c) / w;
    return std::abs(u) >= 1 ? (u > 0 ? 1.0 : 0.0) : 0.5 * (1 + u + std::sin(kPi * u) / kPi);
  };
  return 0.3 * bump(t, 2.0, 0.4) - 0.5 * bump(t, 3.1, 0.3) + 0.2 * bump(t, 4.0, 0.5);
}

struct Signals {
  std::vector<std::int64_t> t;
  std::vector<Eigen::Quaterniond> q;
  tr::PoseLog log;
};

// The recording: frames at 120 Hz from 1.5 s to 4.8 s, the pipeline's orientation at 0.6x the
// true angle about another axis. The log: 125 Hz with +-1 ms jitter from `offset` on, noise
// `noise_deg` per sample, the true angle at robot time = recording time + offset.
Signals signals(std::int64_t offset_ns, double noise_deg, double motion = 1.0,
                double (*f)(double) = profile) {
  Signals s;
  for (std::int64_t t = 1'500'000'000; t <= 4'800'000'000; t += 8'333'333) {
    s.t.push_back(t);
    s.q.emplace_back(Eigen::AngleAxisd(0.6 * motion * f(static_cast<double>(t) * 1e-9),
                                       Eigen::Vector3d(0, 1, 0)));
  }
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> jitter(-1'000'000, 1'000'000);
  std::normal_distribution<double> noise(0.0, noise_deg * kPi / 180.0);
  s.log.name = "g.csv";
  for (std::int64_t k = 0; k * 8'000'000 < 7'000'000'000; ++k) {
    const std::int64_t tl = offset_ns + k * 8'000'000 + jitter(rng);
    const double rec_time = static_cast<double>(tl - offset_ns) * 1e-9;
    tr::Pose p;
    p.q = Eigen::AngleAxisd(motion * f(rec_time), Eigen::Vector3d(1, 2, 2).normalized()) *
          Eigen::AngleAxisd(noise(rng), Eigen::Vector3d(1, 0, 0)) *
          Eigen::AngleAxisd(noise(rng), Eigen::Vector3d(0, 1, 0));
    s.log.t_ns.push_back(tl);
    s.log.pose.push_back(p);
  }
  return s;
}

TEST(AutoSync, RecoversAnOffsetBetweenGridPoints) {
  for (const std::int64_t offset : {std::int64_t{3'141'592'653}, std::int64_t{-1'234'567}}) {
    const Signals s = signals(offset, 0.0);
    tr::AutoSync a;
    ASSERT_EQ(tr::sync_by_correlation(s.t, tr::interval_speed(s.t, s.q), s.log, &a), "");
    EXPECT_NEAR(static_cast<double>(a.offset_ns - offset) * 1e-9, 0.0, 0.3e-3) << offset;
    EXPECT_GT(a.correlation, 0.99);
    EXPECT_LT(a.runner_up, 0.9 * a.correlation);
  }
}

// 0.01 deg per sample over 8 ms intervals is ~2 deg/s of speed noise against a 40 deg/s peak:
// about 1 ms of error (-0.90 ms in the x86-64 host build, -1.05 ms in the aarch64 build).
TEST(AutoSync, NoiseOfARealArmCostsAboutAMillisecond) {
  const Signals s = signals(5'500'000'000, 0.01);
  tr::AutoSync a;
  ASSERT_EQ(tr::sync_by_correlation(s.t, tr::interval_speed(s.t, s.q), s.log, &a), "");
  std::printf("offset error with arm noise: %.3f ms\n",
              static_cast<double>(a.offset_ns - 5'500'000'000) * 1e-6);
  EXPECT_NEAR(static_cast<double>(a.offset_ns - 5'500'000'000) * 1e-9, 0.0, 2e-3);
}

TEST(AutoSync, TooLittleMotionIsRefused) {
  const Signals s = signals(2'000'000'000, 0.01, 1e-5);
  tr::AutoSync a;
  const std::string e = tr::sync_by_correlation(s.t, tr::interval_speed(s.t, s.q), s.log, &a);
  EXPECT_NE(e.find("too little rotation"), std::string::npos) << e;
}

TEST(AutoSync, ARepeatingMotionIsAmbiguous) {
  const Signals s = signals(2'000'000'000, 0.0, 1.0, [](double t) {
    return 0.2 * std::sin(2 * kPi * t / 0.7) + 0.05 * std::sin(2 * kPi * t / 0.35);
  });
  tr::AutoSync a;
  const std::string e = tr::sync_by_correlation(s.t, tr::interval_speed(s.t, s.q), s.log, &a);
  EXPECT_NE(e.find("ambiguous"), std::string::npos) << e;
}

TEST(AutoSync, ALogShorterThanTheRecordingIsRefused) {
  Signals s = signals(0, 0.0);
  s.log.t_ns.resize(100);
  s.log.pose.resize(100);
  tr::AutoSync a;
  const std::string e = tr::sync_by_correlation(s.t, tr::interval_speed(s.t, s.q), s.log, &a);
  EXPECT_NE(e.find("cannot cover it at any clock offset"), std::string::npos) << e;
}

TEST(AutoSync, DifferenceNoiseIgnoresASmoothRamp) {
  std::vector<double> v;
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 0.5);
  for (int i = 0; i < 4000; ++i) v.push_back(0.01 * i + n(rng));
  EXPECT_NEAR(tr::difference_noise(v), 0.5, 0.05);
}

}  // namespace
