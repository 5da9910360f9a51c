// SPDX-License-Identifier: Apache-2.0
// firmware tests: the DSP loop body on simulated frames: cycles, commands (all or nothing, ACK /
// NACK), degraded mode and fault, status frames, and no heap allocation per iteration.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <memory>
#include <thread>
#include <vector>

#include "alloc/alloc_hooks.hpp"
#include "bus_events.hpp"
#include "tacse3/firmware/engine.hpp"
#include "tacse3/sim/simulator.hpp"

using namespace tacse3;
using namespace tacse3::firmware;

namespace {

constexpr std::int64_t kPeriod = 8'333'333;

// The engine's clock in LatenciesRunFromTheSampleTimeAndTheFramesArrivals.
std::int64_t g_clock_ns = 0;
std::int64_t fake_clock() noexcept {
  return g_clock_ns;
}

// PadThreadsGiveTheSingleThreadedEnginesPairsBitForBit: the left pad thread's clock holds it
// inside a frame's image stages (PadStager reads the clock after taking the DSP thread's requests,
// before the stages) while g_hold is set, and says so in g_in_stages.
std::atomic<bool> g_hold{false};
std::atomic<bool> g_in_stages{false};
thread_local bool tl_left_pad = false;
std::int64_t holding_clock() noexcept {
  if (tl_left_pad && g_hold.load()) {
    g_in_stages.store(true);
    while (g_hold.load()) std::this_thread::yield();
  }
  return 0;
}

// Records sent frames into storage reserved up front (no allocation while the loop runs).
class RecordingChannel final : public hal::can::Channel {
 public:
  RecordingChannel() { frames.reserve(100000); }
  bool send(const protocol::CanFrame& f) override {
    if (frames.size() == frames.capacity()) return false;
    frames.push_back(f);
    return true;
  }
  hal::can::RxResult receive(hal::can::RxFrame&, int) override { return hal::can::RxResult::kEnd; }
  const std::string& last_error() const override { return error_; }
  void service() override { ++services; }
  std::vector<protocol::CanFrame> frames;
  int services = 0;

 private:
  std::string error_;
};

// A grasp-and-rotate rendered once (grey), replayed to the engine frame by frame.
class EngineTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    sim::SimConfig cfg;
    cfg.scenario.axis = sim::MotionAxis::kRz;
    cfg.scenario.magnitude = 3.0;
    cfg.scenario.regime = sim::Regime::kStick;
    cfg.scenario.approach_s = 0.05;
    cfg.scenario.grasp_s = 0.2;
    cfg.scenario.settle_s = 0.05;
    cfg.scenario.hold_s = 0.1;
    std::string e;
    ASSERT_TRUE(sim::object_preset("sphere", &cfg.scenario.object));
    auto s = sim::Simulator::create(cfg, &e);
    ASSERT_TRUE(s) << e;
    separation_m_ = s->finger_separation_mm() * 1e-3;
    const int n = s->scenario().frame_count();
    frames_ = new std::vector<std::vector<std::uint8_t>>();
    for (int i = 0; i < n; ++i) {
      for (sim::Sensor side : {sim::Sensor::kLeft, sim::Sensor::kRight}) {
        std::vector<std::uint8_t> img(s->frame_bytes(1));
        ASSERT_EQ(s->render(side, s->scenario().frame_time_ns(i), img, 1), sim::SimStatus::kOk);
        frames_->push_back(std::move(img));
      }
    }
  }
  static void TearDownTestSuite() { delete frames_; }

  // The engine's pipeline configuration, also for the reference run of the same frames.
  static void configure(dsp::DualPipeline& p) {
    dsp::DualConfig dual;
    dual.finger_separation_m = separation_m_;
    dsp::Calibration cal;
    cal.pixel_pitch_m = 1e-4;
    cal.c_displacement = 2e-4;
    cal.velocity_proxy = dsp::VelocityProxy::kDisplacement;
    ASSERT_EQ(p.configure(dual, {cal, cal}), dsp::Status::kOk);
  }

  void SetUp() override {
    pipeline_ = std::make_unique<dsp::DualPipeline>();
    configure(*pipeline_);
    EngineConfig ec;
    ec.pairing = pairing_config(2000, 50);
    make_engine(ec);
  }

  void make_engine(const EngineConfig& ec) {
    engine_ = std::make_unique<Engine>(ec, *pipeline_, channel_, std::array<hal::Camera*, 2>{},
                                       std::array<FrameRing*, 2>{&rings_[0], &rings_[1]},
                                       std::array<CommandRing*, 2>{&commands_[0], &commands_[1]},
                                       shared_);
    now_ = 1'000'000'000;
    engine_->start(now_);
  }

  static std::size_t frame_count() { return frames_->size() / 2; }

  // Pushes frame i of the sensors asked for (timestamped on the 120 Hz grid), then runs one loop
  // iteration one period later.
  void tick(std::size_t i, bool left = true, bool right = true) {
    push(i, left, right);
    now_ = 1'000'000'000 + static_cast<std::int64_t>(i) * kPeriod + 500'000;
    engine_->step(now_);
  }

  // Queues frame i of the sensors asked for, without running the loop.
  void push(std::size_t i, bool left = true, bool right = true) {
    for (std::size_t s = 0; s < 2; ++s) {
      if (s == 0 ? left : right) push_pad(i, s, 1'000'000'000 + std::int64_t(i) * kPeriod, 0);
    }
  }

  // Queues pad s's frame i stamped t_ns, handed over by its capture thread at arrival_ns.
  void push_pad(std::size_t i, std::size_t s, std::int64_t t_ns, std::int64_t arrival_ns) {
    ArrivedFrame a;
    const auto& img = (*frames_)[2 * (i % frame_count()) + s];
    a.frame.view = {img.data(), img.size(), 320, 240, 0, dsp::PixelFormat::kGrey};
    a.frame.timestamp_ns = t_ns;
    a.frame.sequence = static_cast<std::uint32_t>(i);
    a.arrival_ns = arrival_ns;
    ASSERT_TRUE(rings_[s].push(a));
  }

  void command(const protocol::Command& c) {
    protocol::TxConfig tx;  // controller side, node 1
    protocol::CanFrame f;
    ASSERT_EQ(protocol::encode(c, tx, f), protocol::Status::kOk);
    ASSERT_TRUE(commands_[0].push(protocol::validate_command(f, protocol::Endpoint{})));
  }

  test::BusEvents decode() const {
    test::BusEvents b;
    for (const auto& f : channel_.frames) b.feed(f);
    return b;
  }

  // Steps every ms from first_ms after the last cycle (now_); the left pad is lost at first_ms,
  // the right at second_ms. Times relative to now_; stops at the FAULT Status or after 60 ms.
  struct LossTimes {
    std::int64_t degraded = -1;
    std::int64_t fault = -1;
    std::size_t statuses = 0;
  };
  LossTimes lose_both_pads(int first_ms, int second_ms) {
    LossTimes r;
    const std::int64_t t_last = now_;
    const std::size_t before = decode().statuses.size();
    for (int ms = first_ms; ms < 60; ++ms) {
      if (ms == first_ms) shared_.sensors[0].disconnected.store(true);
      if (ms == second_ms) shared_.sensors[1].disconnected.store(true);
      engine_->step(t_last + ms * 1'000'000LL);
      const auto b = decode();
      r.statuses = b.statuses.size() - before;
      if (r.statuses == 0) continue;
      const protocol::State st = b.statuses.back().state;
      if (st == protocol::State::kDegradedSingleSensor && r.degraded < 0)
        r.degraded = ms * 1'000'000LL;
      if (st == protocol::State::kFault) {
        r.fault = ms * 1'000'000LL;
        break;
      }
    }
    return r;
  }

  static inline std::vector<std::vector<std::uint8_t>>* frames_ = nullptr;
  static inline double separation_m_ = 0.0;
  RecordingChannel channel_;
  std::array<FrameRing, 2> rings_;
  std::array<CommandRing, 2> commands_;
  SharedState shared_;
  std::unique_ptr<dsp::DualPipeline> pipeline_;
  std::unique_ptr<Engine> engine_;
  std::unique_ptr<ViewSlot> view_ = std::make_unique<ViewSlot>();
  std::int64_t now_ = 0;
};

}  // namespace

TEST_F(EngineTest, EveryPairBecomesOneCompleteCycle) {
  for (std::size_t i = 0; i < frame_count(); ++i) tick(i);
  const auto b = decode();
  EXPECT_EQ(engine_->stats().pairs, frame_count());
  EXPECT_EQ(engine_->stats().singles, 0u);
  ASSERT_EQ(b.cycles.size(), frame_count());
  EXPECT_EQ(b.reassembly.counter_gaps, 0u);
  EXPECT_EQ(b.reassembly.incomplete, 0u);
  EXPECT_EQ(b.undecodable, 0u);
  // Cycle timestamps are the frames' (microseconds), one period apart.
  EXPECT_EQ(b.cycles[1].timestamp_us - b.cycles[0].timestamp_us, 8333u);
  // The sphere turns +3 deg about z while the contact sticks: with the exact-kinematics proxy the
  // sent orientation follows it with the right sign and size (the replay test's bounds).
  const auto& q = b.cycles.back().orientation;
  const double angle_z_deg = 2.0 * std::atan2(q.z, q.w) * 180.0 / M_PI;
  EXPECT_GT(angle_z_deg, 1.0);
  EXPECT_LT(angle_z_deg, 9.0);
  // 10 Hz status: one group per 12 cycles (+ the first one at start), with the state.
  EXPECT_GE(b.timings.size(), frame_count() / 12);
  EXPECT_EQ(b.statuses.back().state, protocol::State::kTracking);
  EXPECT_EQ(channel_.services, static_cast<int>(frame_count()));
}

TEST_F(EngineTest, CommandsAreAnsweredAndAppliedAllOrNothing) {
  for (std::size_t i = 0; i < 40; ++i) tick(i);
  protocol::Command c;
  c.code = protocol::CommandCode::kSetRateDivider;
  c.rate_divider = 3;
  c.sequence = 5;
  command(c);
  tick(40);
  protocol::Command q;
  q.code = protocol::CommandCode::kQuery;
  q.query = protocol::QueryItem::kStream;
  q.sequence = 6;
  command(q);
  // Out of range on the wire (finger separation 0.3 m > 0.25): NACKed, nothing applied.
  protocol::Command bad;
  bad.code = protocol::CommandCode::kSetFingerSeparation;
  bad.finger_separation_m = 0.1;
  bad.sequence = 7;
  protocol::CanFrame f;
  ASSERT_EQ(protocol::encode(bad, protocol::TxConfig{}, f), protocol::Status::kOk);
  f.data[2] = 0xFF;  // raw 0xFFxx * 1e-5 m > 0.25 m
  f.data[3] = 0xFF;
  protocol::finish_frame(f);
  ASSERT_TRUE(commands_[0].push(protocol::validate_command(f, protocol::Endpoint{})));
  for (std::size_t i = 41; i < 71; ++i) tick(i);
  protocol::Command reset;
  reset.code = protocol::CommandCode::kResetPose;
  reset.sequence = 8;
  command(reset);
  for (std::size_t i = 71; i < 77; ++i) tick(i);
  protocol::Command off;
  off.code = protocol::CommandCode::kSetStream;
  off.stream_enabled = false;
  off.sequence = 9;
  command(off);
  for (std::size_t i = 77; i < 100; ++i) tick(i);

  const auto b = decode();
  ASSERT_EQ(b.acks.size(), 5u);
  EXPECT_EQ(b.acks[0].command, protocol::CommandCode::kSetRateDivider);
  EXPECT_EQ(b.acks[0].result, protocol::AckCode::kAck);
  EXPECT_EQ(b.acks[0].sequence, 5);
  protocol::QueryReply r;
  ASSERT_EQ(protocol::decode_query_reply(b.acks[1], r), protocol::Status::kOk);
  EXPECT_EQ(r.rate_divider, 3);
  EXPECT_TRUE(r.stream_enabled);
  EXPECT_EQ(b.acks[2].result, protocol::AckCode::kOutOfRange);
  EXPECT_EQ(b.acks[2].sequence, 7);
  EXPECT_DOUBLE_EQ(pipeline_->config().finger_separation_m, separation_m_)
      << "NACK applied nothing";
  EXPECT_EQ(b.acks[3].command, protocol::CommandCode::kResetPose);
  EXPECT_EQ(b.acks[4].command, protocol::CommandCode::kSetStream);
  // Samples 0..39 at divider 1; the divider applies before sample 40, so samples 42, 45, .., 75
  // are sent (12); SET_STREAM off applies before sample 77.
  std::size_t with_reset = 0;
  for (const auto& cy : b.cycles) with_reset += cy.pose_reset ? 1 : 0;
  EXPECT_EQ(with_reset, 1u);
  ASSERT_EQ(b.cycles.size(), 40u + 12u);
  for (std::size_t i = 40; i < b.cycles.size(); ++i) {
    EXPECT_NEAR(static_cast<double>(b.cycles[i].timestamp_us - b.cycles[i - 1].timestamp_us),
                25000.0, 1.0)
        << "cycle " << i;
  }
  EXPECT_EQ(b.reassembly.counter_gaps, 0u) << "a divider does not create counter gaps";
  EXPECT_FALSE(b.statuses.back().stream_enabled);
  EXPECT_EQ(b.statuses.back().rate_divider, 3);
}

TEST_F(EngineTest, UnpluggedSensorDegradesAtOnceAndRecovers) {
  for (std::size_t i = 0; i < 40; ++i) tick(i);
  const std::size_t before = decode().cycles.size();
  shared_.sensors[1].disconnected.store(true);
  for (std::size_t i = 40; i < 60; ++i) tick(i, true, false);
  EXPECT_EQ(engine_->state().state, protocol::State::kDegradedSingleSensor);
  shared_.sensors[1].disconnected.store(false);
  for (std::size_t i = 60; i < 80; ++i) tick(i);
  const auto b = decode();
  ASSERT_EQ(b.cycles.size(), 80u) << "no cycle lost while degraded";
  EXPECT_EQ(b.reassembly.counter_gaps + b.reassembly.incomplete, 0u);
  EXPECT_TRUE(b.cycles[before].single_sensor);
  EXPECT_FALSE(b.cycles[79].single_sensor);
  // The change-triggered Status says DEGRADED, right LOST, right after the first single cycle:
  // count the single-sensor cycles in a row just before it (a cycle is also flagged single when
  // only one pad has contact, so the run, not the first flag in the log, is what counts).
  int run = 0;
  bool degraded = false;
  for (const auto& ev : b.order) {
    if (ev.kind == test::BusEvents::Event::kCycle) {
      run = b.cycles[ev.index].single_sensor ? run + 1 : 0;
    } else if (ev.kind == test::BusEvents::Event::kStatus &&
               b.statuses[ev.index].state == protocol::State::kDegradedSingleSensor) {
      EXPECT_EQ(b.statuses[ev.index].health_right, protocol::SensorHealth::kLost);
      EXPECT_EQ(b.statuses[ev.index].fault, protocol::FaultCode::kRightSensorLost);
      degraded = true;
      break;
    }
  }
  EXPECT_TRUE(degraded);
  EXPECT_EQ(run, 1) << "Status follows the first single-sensor cycle";
  EXPECT_NE(b.statuses.back().state, protocol::State::kDegradedSingleSensor);
  EXPECT_EQ(b.statuses.back().health_right, protocol::SensorHealth::kOk);
}

TEST_F(EngineTest, TareFromCommandOrButtonRestartsThePoseAndFlagsTheCycle) {
  for (std::size_t i = 0; i < 40; ++i) tick(i);
  protocol::Command tare;
  tare.code = protocol::CommandCode::kTare;
  tare.sequence = 3;
  command(tare);
  for (std::size_t i = 40; i < 60; ++i) tick(i);
  shared_.tare_requests.fetch_add(1);  // the debounced tare button
  for (std::size_t i = 60; i < 80; ++i) tick(i);

  const auto b = decode();
  ASSERT_EQ(b.acks.size(), 1u);
  EXPECT_EQ(b.acks[0].command, protocol::CommandCode::kTare);
  EXPECT_EQ(b.acks[0].result, protocol::AckCode::kAck);
  ASSERT_EQ(b.cycles.size(), 80u);
  std::vector<std::size_t> flagged;
  for (std::size_t i = 0; i < b.cycles.size(); ++i) {
    if (b.cycles[i].pose_reset) flagged.push_back(i);
  }
  // Exactly the first cycle after each tare, and the pose restarts there from identity.
  ASSERT_EQ(flagged.size(), 2u);
  EXPECT_EQ(flagged[0], 40u);
  EXPECT_EQ(flagged[1], 60u);
  for (std::size_t i : flagged) {
    EXPECT_NEAR(b.cycles[i].orientation.w, 1.0, 1e-3) << "cycle " << i;
    EXPECT_NEAR(b.cycles[i].position.x, 0.0, 1e-4) << "cycle " << i;
  }
}

// The viewer's controls: the web side validates the command as this node's CAN frame (as
// ViewServer does) and the engine applies it like the CAN tare above; the ACK comes back to the
// mailbox, not on the bus (no CAN controller asked).
TEST_F(EngineTest, TareFromTheViewerIsTheCanTareAnsweredToTheMailbox) {
  CommandMailbox box;
  engine_->set_web_commands(&box);
  const auto web = [&](const protocol::Command& c) {
    protocol::TxConfig tx;
    protocol::CanFrame f;
    EXPECT_EQ(protocol::encode(c, tx, f), protocol::Status::kOk);
    EXPECT_TRUE(box.submit(protocol::validate_command(f, tx.endpoint)));
  };
  for (std::size_t i = 0; i < 40; ++i) tick(i);
  protocol::Command tare;
  tare.code = protocol::CommandCode::kTare;
  tare.sequence = 5;
  web(tare);
  protocol::Ack ack;
  EXPECT_FALSE(box.poll(&ack)) << "answered only by the DSP thread's step";
  tick(40);
  ASSERT_TRUE(box.poll(&ack));
  EXPECT_EQ(ack.command, protocol::CommandCode::kTare);
  EXPECT_EQ(ack.result, protocol::AckCode::kAck);
  EXPECT_EQ(ack.sequence, 5);
  for (std::size_t i = 41; i < 50; ++i) tick(i);

  protocol::Command stop;
  stop.code = protocol::CommandCode::kSetStream;
  stop.stream_enabled = false;
  web(stop);
  tick(50);
  ASSERT_TRUE(box.poll(&ack));
  EXPECT_EQ(ack.command, protocol::CommandCode::kSetStream);
  EXPECT_EQ(ack.result, protocol::AckCode::kAck);
  EXPECT_EQ(ack.data[0], 0) << "the argument is echoed";
  EXPECT_FALSE(engine_->stream_enabled());
  for (std::size_t i = 51; i < 60; ++i) tick(i);

  protocol::Command record;  // not a web command: refused, never half started
  record.code = protocol::CommandCode::kStartRecording;
  web(record);
  tick(60);
  ASSERT_TRUE(box.poll(&ack));
  EXPECT_EQ(ack.result, protocol::AckCode::kBusy);
  EXPECT_EQ(engine_->stats().commands, 3u);

  const auto b = decode();
  EXPECT_TRUE(b.acks.empty()) << "web answers stay off the bus";
  ASSERT_EQ(b.cycles.size(), 50u) << "the stream stopped after cycle 50";
  std::vector<std::size_t> flagged;
  for (std::size_t i = 0; i < b.cycles.size(); ++i) {
    if (b.cycles[i].pose_reset) flagged.push_back(i);
  }
  ASSERT_EQ(flagged.size(), 1u);
  EXPECT_EQ(flagged[0], 40u);
  EXPECT_NEAR(b.cycles[40].orientation.w, 1.0, 1e-3);
  EXPECT_NEAR(b.cycles[40].position.x, 0.0, 1e-4);
}

TEST_F(EngineTest, BothSensorsLostIsAFault) {
  for (std::size_t i = 0; i < 20; ++i) tick(i);
  shared_.sensors[0].disconnected.store(true);
  shared_.sensors[1].disconnected.store(true);
  engine_->step(now_ + 1'000'000);
  EXPECT_EQ(engine_->state().state, protocol::State::kFault);
  EXPECT_EQ(engine_->state().fault, protocol::FaultCode::kBothSensorsLost);
  // Status keeps coming at 10 Hz with no frames at all.
  const std::size_t groups = engine_->stats().status_groups;
  for (int k = 1; k <= 10; ++k) engine_->step(now_ + k * 100'000'000LL);
  EXPECT_GE(engine_->stats().status_groups, groups + 9);
  EXPECT_LE(engine_->stats().status_groups, groups + 10);
}

// The two pads of one board go a few ms apart (a sysfs unbind removes them one after the other)
// with no cycle in between, here after the stream has already stopped for two frame periods and
// the last cycle's slot went to the 10 Hz group: holding either change for the next group would
// delay it by up to 100 ms. With no cycle running, one change Status per frame period.
TEST_F(EngineTest, SecondSensorLostWithoutACycleBetweenIsReportedAtOnce) {
  // 13 ticks: the last one (at 100.5 ms) carries the periodic group, the next is due at 200 ms.
  for (std::size_t i = 0; i < 13; ++i) tick(i);
  const std::uint64_t groups = engine_->stats().status_groups;
  // The left pad goes 20 ms after the last cycle (two frame periods: the stream has stopped),
  // the right 1 ms later.
  const LossTimes r = lose_both_pads(20, 21);
  ASSERT_EQ(engine_->stats().status_groups, groups) << "a periodic group fell in the window";
  // The left's loss at once, the right's one frame period after that, not at the 10 Hz group
  // 80 ms later.
  EXPECT_EQ(r.degraded, 20'000'000);
  ASSERT_GE(r.fault, 0) << "no FAULT Status within 60 ms of the second loss";
  EXPECT_GE(r.fault - r.degraded, kPeriod);
  EXPECT_LE(r.fault - r.degraded, kPeriod + 1'000'000);
  const auto b = decode();
  EXPECT_EQ(b.statuses.back().fault, protocol::FaultCode::kBothSensorsLost);
  EXPECT_EQ(b.statuses.back().health_left, protocol::SensorHealth::kLost);
  EXPECT_EQ(r.statuses, 2u) << "two Status frames in the window, not one per step";
}

// The case of the VM's sysfs unbind: the first pad's loss goes out in the last cycle's own slot
// (no periodic group in it), then the second pad goes 3 ms later with no cycle after it. Held
// for the 10 Hz group, that FAULT would wait up to 100 ms.
TEST_F(EngineTest, FaultAfterADegradedStatusInTheLastCyclesSlotIsNotHeld) {
  // 14 ticks: the group went out with tick 12 (at 100.5 ms), tick 13 (108.8 ms) has its slot free.
  for (std::size_t i = 0; i < 14; ++i) tick(i);
  const std::uint64_t groups = engine_->stats().status_groups;
  const LossTimes r = lose_both_pads(2, 5);
  ASSERT_EQ(engine_->stats().status_groups, groups) << "a periodic group fell in the window";
  EXPECT_EQ(r.degraded, 2'000'000) << "in the last cycle's slot";
  ASSERT_GE(r.fault, 0) << "no FAULT Status within 60 ms of the second loss";
  // Two frame periods after the last cycle (the stream has stopped), not at the group 90 ms on.
  EXPECT_GE(r.fault, 2 * kPeriod);
  EXPECT_LE(r.fault, 2 * kPeriod + 1'000'000);
  EXPECT_EQ(r.statuses, 2u);
}

// A slow core with a backlog of frames must not hold the 10 Hz Status back: one step processes
// at most one cycle, then the Status check runs.
TEST_F(EngineTest, BacklogDoesNotStarveTheStatus) {
  for (std::size_t i = 0; i < 20; ++i) tick(i);
  for (std::size_t i = 20; i < 26; ++i) push(i);  // six pairs queued, nobody stepping
  const std::uint64_t samples = engine_->stats().samples;
  const std::uint64_t groups = engine_->stats().status_groups;
  const std::int64_t late = now_ + 250'000'000;  // a Status is due
  ASSERT_TRUE(engine_->step(late));
  EXPECT_EQ(engine_->stats().samples, samples + 1);
  EXPECT_EQ(engine_->stats().status_groups, groups + 1);
  for (int k = 1; k <= 5; ++k) ASSERT_TRUE(engine_->step(late + k));
  EXPECT_EQ(engine_->stats().samples, samples + 6);
  EXPECT_FALSE(engine_->step(late + 10));  // drained: nothing left to do
}

TEST_F(EngineTest, LoopDoesNotAllocate) {
  for (std::size_t i = 0; i < 30; ++i) tick(i);  // warm-up: first status, first cycle
  protocol::Command tare;
  tare.code = protocol::CommandCode::kTare;
  protocol::Command query;
  query.code = protocol::CommandCode::kQuery;
  query.query = protocol::QueryItem::kFusion;
  protocol::Command fusion;
  fusion.code = protocol::CommandCode::kSetFusion;
  fusion.fusion = protocol::FusionMethod::kPaper;
  fusion.velocity_mode = protocol::VelocityMode::kVelocity;
  // Commands are encoded before counting; the engine only pops and answers them.
  std::vector<protocol::CommandResult> pending;
  for (const auto& c : {tare, query, fusion}) {
    protocol::CanFrame f;
    ASSERT_EQ(protocol::encode(c, protocol::TxConfig{}, f), protocol::Status::kOk);
    pending.push_back(protocol::validate_command(f, protocol::Endpoint{}));
  }
  shared_.calibration = {pipeline_->sensor(dsp::SensorSlot::kLeft).calibration(),
                         pipeline_->sensor(dsp::SensorSlot::kRight).calibration()};
  engine_->set_view(view_.get());  // the live viewer's publication is on
  CommandMailbox web;              // and its controls
  engine_->set_web_commands(&web);
  protocol::Ack web_ack;
  test::reset_allocation_count();
  for (std::size_t i = 30; i < 150; ++i) {
    if (i % 20 == 0) commands_[0].push(pending[(i / 20) % pending.size()]);
    if (i == 70) web.submit(pending[0]);
    if (i == 100) shared_.calibration_flag.store(SharedState::kPending);
    if (i == 120) shared_.sensors[1].disconnected.store(true);
    tick(i, true, i < 120);
  }
  const std::uint64_t allocations = test::allocation_count();
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(shared_.calibration_flag.load(), SharedState::kApplied);
  EXPECT_TRUE(web.poll(&web_ack));
  EXPECT_EQ(web_ack.result, protocol::AckCode::kAck);
  EXPECT_EQ(engine_->stats().commands, 7u);
  EXPECT_EQ(engine_->state().state, protocol::State::kDegradedSingleSensor);
  // At most one publication per 50 ms: on the 120 Hz ticks, the 7th after the last (6 periods
  // are 49.99998 ms), so 120 ticks publish 17 or 18 times.
  EXPECT_GE(view_->published(), 17u);
  EXPECT_LE(view_->published(), 18u);
}

// StatusTiming's latency runs from the cycle's SampleTime (the later frame's stamp, which the
// Timestamp frame carries and tacse3-truth subtracts); the arrival latencies from the moments the
// capture threads handed the later and the earlier frame over. Right pad 1.5 ms after the left
// (within the 2 ms pair tolerance), each arriving 0.3 ms after its stamp, the cycle sent 0.7 ms
// after the right frame's arrival (the injected clock).
TEST_F(EngineTest, LatenciesRunFromTheSampleTimeAndTheFramesArrivals) {
  EngineConfig ec;
  ec.pairing = pairing_config(2000, 50);
  ec.clock = &fake_clock;
  make_engine(ec);
  for (std::size_t i = 0; i < 30; ++i) {
    const std::int64_t t_left = 1'000'000'000 + static_cast<std::int64_t>(i) * kPeriod;
    const std::int64_t t_right = t_left + 1'500'000;
    push_pad(i, 0, t_left, t_left + 300'000);
    push_pad(i, 1, t_right, t_right + 300'000);
    g_clock_ns = t_right + 300'000 + 700'000;
    now_ = g_clock_ns;
    engine_->step(now_);
  }
  ASSERT_EQ(engine_->stats().pairs, 30u);
  const CycleLatency& l = engine_->latency();
  EXPECT_EQ(l.later_arrival().percentile(50), 700);
  EXPECT_EQ(l.later_arrival().percentile(99), 700);
  EXPECT_EQ(l.earlier_arrival().percentile(50), 1500 + 300 + 700 - 300);
  EXPECT_EQ(l.sample().percentile(50), 300 + 700);
  EXPECT_EQ(engine_->latency_percentile_us(99), 1000);
  EXPECT_EQ(engine_->dsp_time_percentile_us(50), 0);  // the clock stood still
  const auto b = decode();
  ASSERT_EQ(b.timings.size(), 3u);  // 10 Hz over 30 periods, the first after the first cycle
  for (const protocol::TimingMsg& t : b.timings) {
    EXPECT_NEAR(t.latency_p50_s, 1000e-6, 1e-9);
    EXPECT_NEAR(t.latency_p99_s, 1000e-6, 1e-9);
    EXPECT_NEAR(t.dsp_time_s, 0.0, 1e-9);
  }
  // The right pad lost: one pad alone, its arrival both the later and the earlier.
  shared_.sensors[1].disconnected.store(true);
  for (std::size_t i = 30; i < 30 + 256; ++i) {
    const std::int64_t t_left = 1'000'000'000 + static_cast<std::int64_t>(i) * kPeriod;
    push_pad(i, 0, t_left, t_left + 300'000);
    g_clock_ns = t_left + 300'000 + 900'000;
    now_ = g_clock_ns;
    engine_->step(now_);
  }
  EXPECT_EQ(engine_->stats().singles, 256u);
  EXPECT_EQ(l.later_arrival().percentile(50), 900);
  EXPECT_EQ(l.earlier_arrival().percentile(1), 900);
  EXPECT_EQ(l.sample().percentile(99), 1200);
}

// Pads 1.5 ms apart, the later one arriving first on every other sample and each arriving after
// a loop iteration found the other alone: the engine waits for the pair, then sends exactly what
// the dual pipeline gives for the two frames at the later timestamp.
TEST_F(EngineTest, OffsetPadsGiveTheDualPipelinesOutputBitForBit) {
  auto reference = std::make_unique<dsp::DualPipeline>();
  configure(*reference);
  dsp::DualResult want;
  for (std::size_t i = 0; i < frame_count(); ++i) {
    const std::int64_t t_left = 1'000'000'000 + static_cast<std::int64_t>(i) * kPeriod;
    const std::int64_t t_right = t_left + 1'500'000;
    const std::size_t first = i % 2;  // the pad whose frame is handed over first
    const std::int64_t t_first = first == 0 ? t_left : t_right;
    const std::int64_t t_second = first == 0 ? t_right : t_left;
    push_pad(i, first, t_first, t_right + 100'000);
    engine_->step(t_right + 100'000);
    ASSERT_EQ(engine_->stats().samples, i) << "processed without its partner";
    push_pad(i, 1 - first, t_second, t_right + 200'000);
    engine_->step(t_right + 200'000);
    ASSERT_EQ(engine_->stats().pairs, i + 1);
    const auto& l = (*frames_)[2 * i];
    const auto& r = (*frames_)[2 * i + 1];
    const dsp::FrameView lv{l.data(), l.size(), 320, 240, 0, dsp::PixelFormat::kGrey};
    const dsp::FrameView rv{r.data(), r.size(), 320, 240, 0, dsp::PixelFormat::kGrey};
    reference->process(&lv, &rv, t_right, want);
    const dsp::DualResult& got = engine_->last_result();
    ASSERT_EQ(got.t_ns, t_right);
    for (int k = 0; k < 6; ++k) ASSERT_EQ(got.twist[k], want.twist[k]) << i;
    ASSERT_EQ(got.pose.q.coeffs(), want.pose.q.coeffs()) << i;
    ASSERT_EQ(got.pose.p, want.pose.p) << i;
    ASSERT_EQ(got.confidence, want.confidence) << i;
  }
  const auto b = decode();
  ASSERT_EQ(b.cycles.size(), frame_count());
  EXPECT_EQ(b.cycles.back().timestamp_us,
            static_cast<std::uint64_t>(engine_->last_result().t_ns / 1000));
  EXPECT_FALSE(b.cycles.back().single_sensor);
}

// The earlier pad's image stages run when the loop takes its frame, before the later frame is
// there: the left pad's image state is that of its newest frame while the right pad's is still
// the previous one's.
TEST_F(EngineTest, EarlierPadsImageStagesRunBeforeTheLaterFrameArrives) {
  auto reference = std::make_unique<dsp::DualPipeline>();
  configure(*reference);
  auto stages = std::make_unique<dsp::PadStages>();
  const auto view = [](std::size_t i, std::size_t s) {
    const auto& img = (*frames_)[2 * i + s];
    return dsp::FrameView{img.data(), img.size(), 320, 240, 0, dsp::PixelFormat::kGrey};
  };
  const auto same_work = [&](dsp::SensorSlot s) {
    return pipeline_->sensor(s).fields().work.px == reference->sensor(s).fields().work.px;
  };
  for (std::size_t i = 0; i < 3; ++i) {
    const std::int64_t t_left = 1'000'000'000 + static_cast<std::int64_t>(i) * kPeriod;
    push_pad(i, 0, t_left, t_left + 100'000);
    engine_->step(t_left + 100'000);
    ASSERT_EQ(engine_->stats().samples, i);
    EXPECT_EQ(pipeline_->sensor(dsp::SensorSlot::kLeft).has_reference(), true);
    EXPECT_EQ(pipeline_->sensor(dsp::SensorSlot::kRight).has_reference(), i > 0);
    reference->process_pad(dsp::SensorSlot::kLeft, view(i, 0), *stages);
    EXPECT_TRUE(same_work(dsp::SensorSlot::kLeft)) << "left frame " << i << " not through stage 1";
    if (i > 0) {
      EXPECT_TRUE(same_work(dsp::SensorSlot::kRight)) << "right moved before its frame";
    }
    push_pad(i, 1, t_left + 1'500'000, t_left + 1'600'000);
    engine_->step(t_left + 1'600'000);
    ASSERT_EQ(engine_->stats().pairs, i + 1);
    reference->process_pad(dsp::SensorSlot::kRight, view(i, 1), *stages);
    EXPECT_TRUE(same_work(dsp::SensorSlot::kRight));
  }
}

// A tare (or a calibration reload) between the earlier frame's image stages and the later
// frame. A pad takes it when its next frame's stages start: the later pad at this cycle's frame,
// the earlier pad at the next cycle's. A reload applies to that frame; a tare makes that frame
// the reference once handed on, and the pad's motion restarts at its following frame. The pose
// and the pair's filters restart at once. Each applies once: the cycles equal the reference
// run's with the same tare and reload, bit for bit.
TEST_F(EngineTest, TareOrReloadDuringACycleAppliesToEachPadsNextFrameOnce) {
  auto reference = std::make_unique<dsp::DualPipeline>();
  configure(*reference);
  auto stages = std::make_unique<std::array<dsp::PadStages, 2>>();
  dsp::Calibration reloaded = pipeline_->sensor(dsp::SensorSlot::kLeft).calibration();
  reloaded.c_displacement *= 2.0;
  constexpr std::size_t kTareAt = 30, kReloadAt = 12, kEnd = 60;
  dsp::DualResult want;
  for (std::size_t i = 0; i < kEnd; ++i) {
    const std::int64_t t_left = 1'000'000'000 + static_cast<std::int64_t>(i) * kPeriod;
    const std::int64_t t_right = t_left + 1'500'000;
    const auto& li = (*frames_)[2 * i];
    const auto& ri = (*frames_)[2 * i + 1];
    const dsp::FrameView lv{li.data(), li.size(), 320, 240, 0, dsp::PixelFormat::kGrey};
    const dsp::FrameView rv{ri.data(), ri.size(), 320, 240, 0, dsp::PixelFormat::kGrey};
    push_pad(i, 0, t_left, t_left + 100'000);
    engine_->step(t_left + 100'000);
    if (i == kTareAt) shared_.tare_requests.fetch_add(1);  // the button, mid-cycle
    if (i == kReloadAt) {
      shared_.calibration = {reloaded, reloaded};
      shared_.calibration_flag.store(SharedState::kPending);
    }
    push_pad(i, 1, t_right, t_right + 100'000);
    engine_->step(t_right + 100'000);
    ASSERT_EQ(engine_->stats().pairs, i + 1);
    if (i == kReloadAt) {
      // Answered at once: no cycle waits for it.
      EXPECT_EQ(shared_.calibration_flag.load(), SharedState::kApplied);
    }
    if (i == kTareAt) {
      reference->process_pad(dsp::SensorSlot::kLeft, lv, (*stages)[0]);
      reference->restart_filters();
      reference->reset_pose();
      reference->process_pad(dsp::SensorSlot::kRight, rv, (*stages)[1]);
      reference->finish(&(*stages)[0], &(*stages)[1], t_right, want);
      for (dsp::SensorSlot s : {dsp::SensorSlot::kLeft, dsp::SensorSlot::kRight}) {
        reference->sensor_mut(s).run_deferred();
      }
      reference->sensor_mut(dsp::SensorSlot::kRight).tare_image();
      reference->sensor_mut(dsp::SensorSlot::kRight).reset_motion();  // from frame i + 1
    } else if (i == kTareAt + 1) {
      reference->process(&lv, &rv, t_right, want);
      reference->sensor_mut(dsp::SensorSlot::kLeft).tare_image();
      reference->sensor_mut(dsp::SensorSlot::kLeft).reset_motion();  // from frame i + 2
    } else if (i == kReloadAt) {
      reference->process_pad(dsp::SensorSlot::kLeft, lv, (*stages)[0]);
      ASSERT_EQ(reference->set_pair_calibration({reloaded, reloaded}), dsp::Status::kOk);
      ASSERT_EQ(reference->sensor_mut(dsp::SensorSlot::kRight).set_calibration(reloaded),
                dsp::Status::kOk);
      reference->process_pad(dsp::SensorSlot::kRight, rv, (*stages)[1]);
      reference->finish(&(*stages)[0], &(*stages)[1], t_right, want);
      ASSERT_EQ(reference->sensor_mut(dsp::SensorSlot::kLeft).set_calibration(reloaded),
                dsp::Status::kOk);
    } else {
      reference->process(&lv, &rv, t_right, want);
    }
    const dsp::DualResult& got = engine_->last_result();
    for (int k = 0; k < 6; ++k) ASSERT_EQ(got.twist[k], want.twist[k]) << i;
    ASSERT_EQ(got.pose.q.coeffs(), want.pose.q.coeffs()) << i;
    ASSERT_EQ(got.pose.p, want.pose.p) << i;
  }
  const auto b = decode();
  ASSERT_EQ(b.cycles.size(), kEnd);
  for (std::size_t i = 0; i < kEnd; ++i) EXPECT_EQ(b.cycles[i].pose_reset, i == kTareAt) << i;
}

// Each pad's image stages and deferred work on its own thread, as the daemon's capture threads
// run them, with a tare and a calibration reload requested while the left pad's thread is in a
// frame's stages (the left pad takes them at its next frame, the right at this one): every pair
// equals the single-threaded engine's (stages on the stepping thread, the requests between the
// two frames) bit for bit.
TEST_F(EngineTest, PadThreadsGiveTheSingleThreadedEnginesPairsBitForBit) {
  auto pipeline = std::make_unique<dsp::DualPipeline>();
  configure(*pipeline);
  auto channel = std::make_unique<RecordingChannel>();
  auto shared = std::make_unique<SharedState>();
  auto inputs = std::make_unique<std::array<FrameRing, 2>>();
  auto staged = std::make_unique<std::array<StagedRing, 2>>();
  auto commands = std::make_unique<std::array<CommandRing, 2>>();
  EngineConfig ec;
  ec.pairing = pairing_config(2000, 50);
  ec.clock = &holding_clock;
  auto threaded = std::make_unique<Engine>(
      ec, *pipeline, *channel, std::array<hal::Camera*, 2>{}, std::array<FrameRing*, 2>{},
      std::array<CommandRing*, 2>{&(*commands)[0], &(*commands)[1]}, *shared);
  threaded->set_staged_rings({&(*staged)[0], &(*staged)[1]});
  threaded->start(now_);
  std::atomic<bool> stop{false};
  const auto pad = [&](std::size_t s) {
    tl_left_pad = s == 0;
    ArrivedFrame a;
    while (!stop.load()) {
      StagedFrame* slot = (*staged)[s].back();
      if (slot == nullptr || !(*inputs)[s].pop(a)) {
        std::this_thread::yield();
        continue;
      }
      threaded->stager(s).stage(a, *slot);
      (*staged)[s].commit();
      threaded->stager(s).run_deferred();
    }
  };
  std::thread left(pad, 0), right(pad, 1);

  dsp::Calibration reloaded = pipeline_->sensor(dsp::SensorSlot::kLeft).calibration();
  reloaded.c_displacement *= 2.0;
  constexpr std::size_t kTareAt = 20, kReloadAt = 12, kEnd = 40;
  const auto arrived = [&](std::size_t i, std::size_t s, std::int64_t t_ns) {
    ArrivedFrame a;
    const auto& img = (*frames_)[2 * (i % frame_count()) + s];
    a.frame.view = {img.data(), img.size(), 320, 240, 0, dsp::PixelFormat::kGrey};
    a.frame.timestamp_ns = t_ns;
    a.arrival_ns = t_ns + 100'000;
    return a;
  };
  const auto request = [&](std::size_t i, SharedState& sh) {
    if (i == kTareAt) sh.tare_requests.fetch_add(1);
    if (i == kReloadAt) {
      sh.calibration = {reloaded, reloaded};
      sh.calibration_flag.store(SharedState::kPending);
    }
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  for (std::size_t i = 0; i < kEnd; ++i) {
    const std::int64_t t_left = 1'000'000'000 + static_cast<std::int64_t>(i) * kPeriod;
    const std::int64_t t_right = t_left + 1'500'000;
    // The single-threaded engine: the requests between the left frame's stages and the right.
    push_pad(i, 0, t_left, t_left + 100'000);
    engine_->step(t_left + 100'000);
    request(i, shared_);
    push_pad(i, 1, t_right, t_right + 100'000);
    engine_->step(t_right + 100'000);
    ASSERT_EQ(engine_->stats().pairs, i + 1);
    // The threaded one: the requests while the left pad's thread is in the frame's stages.
    const bool hold = i == kTareAt || i == kReloadAt;
    g_in_stages.store(false);
    g_hold.store(hold);
    ASSERT_TRUE((*inputs)[0].push(arrived(i, 0, t_left)));
    while (hold && !g_in_stages.load()) std::this_thread::yield();
    request(i, *shared);
    threaded->step(t_left + 100'000);
    if (i == kReloadAt) {
      EXPECT_EQ(shared->calibration_flag.load(), SharedState::kApplied);
    }
    g_hold.store(false);
    ASSERT_TRUE((*inputs)[1].push(arrived(i, 1, t_right)));
    while (threaded->stats().pairs < i + 1 && std::chrono::steady_clock::now() < deadline) {
      threaded->step(t_right + 100'000);
      std::this_thread::yield();
    }
    ASSERT_EQ(threaded->stats().pairs, i + 1);
    const dsp::DualResult& want = engine_->last_result();
    const dsp::DualResult& got = threaded->last_result();
    for (int k = 0; k < 6; ++k) ASSERT_EQ(got.twist[k], want.twist[k]) << i;
    ASSERT_EQ(got.pose.q.coeffs(), want.pose.q.coeffs()) << i;
    ASSERT_EQ(got.pose.p, want.pose.p) << i;
  }
  stop.store(true);
  left.join();
  right.join();
  threaded->release_all();
  EXPECT_EQ(threaded->stats().dropped_late, 0u);
  EXPECT_EQ(threaded->last_cycle().pose_reset, false);
}

// A frame already late when the loop takes it (its pad's partner went alone at a later sample
// time) is dropped without its image stages: the pad's image state is as if it never came, and
// the following pairs equal the dual pipeline's on the frames that entered a cycle.
TEST_F(EngineTest, ALateFrameIsDroppedWithoutItsImageStages) {
  auto reference = std::make_unique<dsp::DualPipeline>();
  configure(*reference);
  dsp::DualResult want;
  constexpr std::size_t kLate = 10;
  std::int64_t t = 0;
  for (std::size_t i = 0; i < 20; ++i) {
    // After the late frame the loop's clock has run 60 ms ahead: so do the frames.
    t = 1'000'000'000 + static_cast<std::int64_t>(i) * kPeriod + (i > kLate ? 70'000'000 : 0);
    const auto& li = (*frames_)[2 * i];
    const auto& ri = (*frames_)[2 * i + 1];
    const dsp::FrameView lv{li.data(), li.size(), 320, 240, 0, dsp::PixelFormat::kGrey};
    const dsp::FrameView rv{ri.data(), ri.size(), 320, 240, 0, dsp::PixelFormat::kGrey};
    if (i != kLate) {
      push_pad(i, 0, t, t + 100'000);
      push_pad(i, 1, t, t + 100'000);
      engine_->step(t + 100'000);
      reference->process(&lv, &rv, t, want);
    } else {
      push_pad(i, 0, t, t + 100'000);
      engine_->step(t + 100'000);
      engine_->step(t + 60'000'000);  // past the pairing's 50 ms wait: left alone
      ASSERT_EQ(engine_->stats().singles, 1u);
      reference->process(&lv, nullptr, t, want);
      const auto right = pipeline_->sensor(dsp::SensorSlot::kRight).fields().work.px;
      const auto switches = pipeline_->sensor(dsp::SensorSlot::kRight).flow().keyframe_switches();
      push_pad(i, 1, t, t + 60'100'000);
      engine_->step(t + 60'100'000);
      ASSERT_EQ(engine_->stats().dropped_late, 1u);
      EXPECT_TRUE(pipeline_->sensor(dsp::SensorSlot::kRight).fields().work.px == right);
      EXPECT_EQ(pipeline_->sensor(dsp::SensorSlot::kRight).flow().keyframe_switches(), switches);
    }
    const dsp::DualResult& got = engine_->last_result();
    for (int k = 0; k < 6; ++k) ASSERT_EQ(got.twist[k], want.twist[k]) << i;
    ASSERT_EQ(got.pose.q.coeffs(), want.pose.q.coeffs()) << i;
  }
  EXPECT_EQ(engine_->stats().pairs, 19u);
}

// What the viewer reads is the cycle as processed: the counters, the pose as a unit quaternion
// equal to the pipeline's, the pads' images and contact.
TEST_F(EngineTest, ViewSnapshotCarriesTheLastCycle) {
  engine_->set_view(view_.get());
  for (std::size_t i = 0; i < 40; ++i) tick(i);
  ASSERT_TRUE(view_->take());
  const ViewSnapshot& v = view_->front();
  EXPECT_GT(v.cycle, 30u);
  EXPECT_LE(v.cycle, engine_->stats().samples);
  EXPECT_TRUE(v.have_result);
  EXPECT_EQ(v.state, static_cast<std::uint8_t>(engine_->state().state));
  const double n = v.q[0] * v.q[0] + v.q[1] * v.q[1] + v.q[2] * v.q[2] + v.q[3] * v.q[3];
  EXPECT_NEAR(n, 1.0, 1e-9);
  EXPECT_GE(v.dsp_us, 0);
  for (const viewer::ViewPad& pad : v.pads) {
    EXPECT_TRUE(pad.configured);
    EXPECT_TRUE(pad.present);
    int lo = 255, hi = 0;
    for (std::uint8_t px : pad.luma) {
      lo = std::min<int>(lo, px);
      hi = std::max<int>(hi, px);
    }
    EXPECT_GT(hi - lo, 20) << "a flat image";
    int cells = 0;
    for (std::uint8_t m : pad.mask) cells += m;
    EXPECT_EQ(pad.contact, cells > 0);
    EXPECT_EQ(pad.contact_area_m2 > 0.0, cells > 0);
  }
  // Each tick processes one cycle; the tick that publishes publishes that cycle's pose.
  bool published = false;
  for (std::size_t i = 40; i < 50 && !published; ++i) {
    tick(i);
    published = view_->take();
  }
  ASSERT_TRUE(published) << "no publication within 10 periods (83 ms)";
  const auto& r = engine_->last_result();
  EXPECT_EQ(view_->front().cycle, engine_->stats().samples);
  EXPECT_DOUBLE_EQ(view_->front().q[0], r.pose.q.w());
  EXPECT_DOUBLE_EQ(view_->front().w[2], r.twist[2]);
  EXPECT_DOUBLE_EQ(view_->front().p[2], r.pose.p.z());
  EXPECT_EQ(view_->front().counters.cycles_sent, engine_->stats().cycles_sent);
  EXPECT_GT(view_->front().counters.cycles_sent, 30u);
}
