// SPDX-License-Identifier: Apache-2.0
// firmware tests: tacse3d --http on the sim board, through real sockets: /api/state holds a live
// cycle (counting up, unit quaternion, a known state), the pads' JPEGs decode to real images,
// /api/stream delivers events, and the CAN stream keeps its rate and the engine its latency while
// four clients are connected, one of which never reads. Plus the usage and start errors of --http.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <turbojpeg.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "bus_events.hpp"
#include "free_port.hpp"
#include "run_cmd.hpp"

namespace fs = std::filesystem;
using tacse3::test::free_port;
using tacse3::test::read_all;
using tacse3::test::run_cmd;
using tacse3::test::RunResult;

namespace {

// The number after "key": in a flat JSON text (the fields used here are unique keys).
double json_number(const std::string& j, const std::string& key, std::size_t from = 0) {
  const std::size_t at = j.find("\"" + key + "\":", from);
  if (at == std::string::npos) return NAN;
  return std::strtod(j.c_str() + at + key.size() + 3, nullptr);
}

std::string json_string(const std::string& j, const std::string& key) {
  const std::size_t at = j.find("\"" + key + "\":\"");
  if (at == std::string::npos) return {};
  const std::size_t b = at + key.size() + 4;
  return j.substr(b, j.find('"', b) - b);
}

std::vector<double> json_array(const std::string& j, const std::string& key) {
  std::vector<double> v;
  std::size_t at = j.find("\"" + key + "\":[");
  if (at == std::string::npos) return v;
  const char* p = j.c_str() + at + key.size() + 4;
  while (*p != ']' && *p != '\0') {
    char* end = nullptr;
    v.push_back(std::strtod(p, &end));
    p = *end == ',' ? end + 1 : end;
  }
  return v;
}

// Wall-clock seconds scale: the ASan+UBSan build's loop manages only ~20-30 cycles/s on a 2-core
// machine (test_run.cpp), so the daemon runs longer there and the waits are longer.
#if defined(__SANITIZE_ADDRESS__)
constexpr int kTimeScale = 5;
constexpr bool kSanitized = true;
#else
constexpr int kTimeScale = 1;
constexpr bool kSanitized = false;
#endif

// Runs a daemon command on its own thread, its result into *out. Joined on every way out of a
// test (a failed ASSERT returns early, and a joinable std::thread left behind would terminate
// the test program).
struct DaemonThread {
  DaemonThread(std::string cmd, RunResult* out)
      : t([this, cmd = std::move(cmd), out] {
          *out = run_cmd(cmd);
          exited = true;
        }) {}
  ~DaemonThread() {
    if (t.joinable()) t.join();
  }
  void join() { t.join(); }
  std::atomic<bool> exited{false};  // before t: set by the thread t starts
  std::thread t;
};

// Polls /api/state until it answers 200 (its body in *body) or the daemon has exited. The
// daemon's run is bounded (--seconds counts from its first frame), so a loaded machine that is
// slow to start it delays the test instead of failing it. False, with the last answer in *why,
// if the daemon exited first.
bool wait_live(httplib::Client& cli, const DaemonThread& run, std::string* body, std::string* why) {
  while (!run.exited.load()) {
    if (auto r = cli.Get("/api/state"); r && r->status == 200) {
      if (body != nullptr) *body = r->body;
      return true;
    } else {
      *why = r ? "HTTP " + std::to_string(r->status) : httplib::to_string(r.error());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  *why = "the daemon exited before /api/state answered 200; the last try: " + *why;
  return false;
}

class ViewerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tacse3-fw-viewer-" + std::to_string(getpid()));
    fs::create_directories(dir_);
    // The sim board unpaced, with stale/lost raised, as in test_run.cpp: the shared machine must
    // not turn the rate check into a single-sensor run.
    std::string text = read_all(fs::path(TACSE3_SOURCE_BOARDS_DIR) / "sim/board.toml");
    text.replace(text.find("realtime = true"), 15, "realtime = false");
    text.replace(text.find("stale_ms = 50"), 13, "stale_ms = 1000");
    text.replace(text.find("lost_ms = 500"), 13, "lost_ms = 2000");
    std::ofstream(dir_ / "board.toml") << text;
    port_ = free_port();
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string daemon(const std::string& http, int seconds) const {
    return std::string(TACSE3D_BIN) + " --board " + (dir_ / "board.toml").string() +
           " --calibration " + TACSE3_SIM_CALIBRATION + " --can-log " +
           (dir_ / "bus.log").string() + " --http " + http + " --seconds " +
           std::to_string(seconds) + " 2>&1";
  }

  fs::path dir_;
  int port_ = 0;
};

// A client that asks for /api/stream and never reads: a 4 KiB receive buffer that the stream
// fills within a second. The socket, or -errno of the last attempt when it cannot connect. A loaded
// machine can refuse a connection for a moment (a full accept backlog while the server's thread
// waits for a core), so it tries for up to 5 s.
int mute_client(int port) {
  int err = 0;
  for (int attempt = 0; attempt < 50; ++attempt) {
    if (attempt > 0) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    const int small = 4096;
    setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof(small));
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    const std::string req = "GET /api/stream HTTP/1.1\r\nHost: test\r\n\r\n";
    if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0 &&
        send(fd, req.data(), req.size(), 0) == static_cast<ssize_t>(req.size())) {
      return fd;
    }
    err = errno;
    close(fd);
  }
  return err > 0 ? -err : -EIO;
}

}  // namespace

TEST_F(ViewerTest, ServesLiveStateImagesAndStreamWhileTheCanStreamKeepsItsRate) {
  RunResult d;
  DaemonThread run(daemon("127.0.0.1:" + std::to_string(port_), 6 * kTimeScale), &d);
  httplib::Client cli("127.0.0.1", port_);
  cli.set_connection_timeout(1);
  cli.set_read_timeout(2 * kTimeScale);
  std::string first, why;
  if (!wait_live(cli, run, &first, &why)) run.join();
  ASSERT_FALSE(first.empty()) << why << "\n" << d.out;
  // The board leaves the controls off: the command endpoint says which key turns them on.
  const auto refused = cli.Post("/api/command", R"({"command":"tare"})", "application/json");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 403);
  EXPECT_NE(refused->body.find((dir_ / "board.toml").string() + ": [viewer] controls is not true"),
            std::string::npos)
      << refused->body;
  EXPECT_NE(cli.Get("/api/info")->body.find("\"controls\":false,"), std::string::npos);

  // The client that never reads: its stream fills the socket buffers and must stall nothing.
  const int mute = mute_client(port_);
  ASSERT_GE(mute, 0) << std::strerror(-mute);

  // Three reading clients on the stream.
  std::atomic<bool> stop{false};
  std::vector<std::vector<long long>> ids(3);
  std::vector<std::thread> readers;
  for (int k = 0; k < 3; ++k) {
    readers.emplace_back([&, k] {
      httplib::Client c("127.0.0.1", port_);
      c.set_read_timeout(3 * kTimeScale);
      std::string buf;
      c.Get("/api/stream", [&](const char* data, std::size_t n) {
        buf.append(data, n);
        for (std::size_t at; (at = buf.find("\n\n")) != std::string::npos; buf.erase(0, at + 2)) {
          const std::size_t id = buf.find("id: ");
          if (id < at) ids[k].push_back(std::stoll(buf.substr(id + 4)));
        }
        return !stop.load();
      });
    });
  }

  // Two fetches 300 ms apart: the cycle counts up, the pose is a unit quaternion.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  auto second = cli.Get("/api/state");
  ASSERT_TRUE(second && second->status == 200);
  const std::string& s = second->body;
  EXPECT_GT(json_number(s, "cycle"), json_number(first, "cycle"));
  EXPECT_GT(json_number(s, "t_us"), json_number(first, "t_us"));
  const std::set<std::string> states{"BOOTING", "NO_CONTACT", "TRACKING", "DEGRADED_SINGLE_SENSOR",
                                     "FAULT"};
  EXPECT_EQ(states.count(json_string(s, "state")), 1u) << s;
  const std::vector<double> q = json_array(s, "q");
  ASSERT_EQ(q.size(), 4u) << s;
  EXPECT_NEAR(std::hypot(std::hypot(q[0], q[1]), std::hypot(q[2], q[3])), 1.0, 1e-6) << s;
  EXPECT_EQ(json_array(s, "w").size(), 3u);
  EXPECT_EQ(json_array(s, "p").size(), 3u);
  const double conf = json_number(s, "confidence");
  EXPECT_TRUE(conf >= 0.0 && conf <= 1.0) << s;
  EXPECT_NE(s.find("\"left\":{\"configured\":true"), std::string::npos) << s;

  // Both images decode to 160 x 120 grey with the gel's texture in them.
  tjhandle tj = tjInitDecompress();
  for (const char* pad : {"left", "right"}) {
    auto r = cli.Get(std::string("/api/image/") + pad + ".jpg");
    ASSERT_TRUE(r && r->status == 200) << pad;
    EXPECT_EQ(r->get_header_value("Content-Type"), "image/jpeg");
    int w = 0, h = 0, sub = 0, cs = 0;
    const auto* jpg = reinterpret_cast<const unsigned char*>(r->body.data());
    ASSERT_EQ(tjDecompressHeader3(tj, jpg, r->body.size(), &w, &h, &sub, &cs), 0) << pad;
    ASSERT_EQ(w, 160);
    ASSERT_EQ(h, 120);
    std::vector<unsigned char> px(static_cast<std::size_t>(w * h));
    ASSERT_EQ(tjDecompress2(tj, jpg, r->body.size(), px.data(), w, 0, h, TJPF_GRAY, 0), 0);
    double sum = 0, sum2 = 0;
    for (unsigned char v : px) {
      sum += v;
      sum2 += static_cast<double>(v) * v;
    }
    const double mean = sum / px.size();
    const double sd = std::sqrt(sum2 / px.size() - mean * mean);
    EXPECT_GT(sd, 5.0) << pad << ": a blank image (mean " << mean << ")";
  }
  tjDestroy(tj);
  auto fields = cli.Get("/api/fields");
  ASSERT_TRUE(fields && fields->status == 200);
  EXPECT_EQ(json_array(fields->body, "mask").size(), 1200u);
  EXPECT_EQ(cli.Get("/etc/passwd")->status, 404);
  EXPECT_EQ(cli.Get("/api/image/../../x.jpg")->status, 404);

  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  stop.store(true);
  for (auto& t : readers) t.join();
  run.join();
  close(mute);
  ASSERT_EQ(d.status, 0) << "the daemon did not stop cleanly with a client that never reads\n"
                         << d.out;
  EXPECT_NE(d.out.find("viewer: http://127.0.0.1:" + std::to_string(port_) + "/"),
            std::string::npos)
      << d.out;
  for (const auto& v : ids) {
    // ~1.8 s of stream at 20 Hz; at least a few events, in order. The id is the cycle, so two
    // snapshots with no cycle between them (at boot, or a stalled loop under the sanitizers)
    // share it; the ids still move on.
    ASSERT_GE(v.size(), 5u);
    for (std::size_t i = 1; i < v.size(); ++i) EXPECT_GE(v[i], v[i - 1]);
    EXPECT_GT(v.back(), v.front());
  }

  // The CAN stream with the clients connected: every frame pair one cycle, at the sensor rate
  // (the same bound as test_run.cpp's run without the viewer).
  tacse3::test::BusEvents b;
  ASSERT_TRUE(b.feed_log(read_all(dir_ / "bus.log")));
  ASSERT_GE(b.cycles.size(), 240u);
  const double t0 = static_cast<double>(b.cycles.front().timestamp_us);
  const double t1 = static_cast<double>(b.cycles.back().timestamp_us);
  const double rate = static_cast<double>(b.cycles.size() - 1) / ((t1 - t0) * 1e-6);
  EXPECT_NEAR(rate, 120.0, 1.2) << "cycle rate " << rate << " Hz";
}

// [viewer] controls = true: a tare posted to the page's endpoint does what the CAN TARE does
// (test_engine.cpp): the next cycle on the bus carries PoseReset and the identity pose. Its ACK
// is the HTTP answer and stays off the bus. Paced and looping, so cycles flow while it runs.
TEST_F(ViewerTest, TareOverHttpIsTheCanTareWithItsAckAsTheAnswer) {
  std::string text = read_all(dir_ / "board.toml");
  // Paced where the loop keeps up; unpaced under the sanitizers, where pacing would drop most
  // frames and the estimate would not follow the turn.
  if (!kSanitized) text.replace(text.find("realtime = false"), 16, "realtime = true");
  text.replace(text.find("repeat = false"), 14, "repeat = true");
  std::ofstream(dir_ / "board.toml") << text << "\n[viewer]\ncontrols = true\n";
  RunResult d;
  DaemonThread run(daemon("127.0.0.1:" + std::to_string(port_), 4 * kTimeScale), &d);
  httplib::Client cli("127.0.0.1", port_);
  cli.set_connection_timeout(1);
  cli.set_read_timeout(2 * kTimeScale);
  std::string why;
  const bool live = wait_live(cli, run, nullptr, &why);
  if (!live) run.join();
  ASSERT_TRUE(live) << why << "\n" << d.out;
  EXPECT_NE(cli.Get("/api/info")->body.find("\"controls\":true,\"controls_off\":null"),
            std::string::npos);
  // The pose moves away from identity first (the object turns once the pads are in contact).
  double turned_deg = 0;
  for (int i = 0; i < 100 * kTimeScale && turned_deg < 5; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (auto r = cli.Get("/api/state"); r && r->status == 200) {
      const std::vector<double> q = json_array(r->body, "q");
      if (q.size() == 4) turned_deg = 2 * std::acos(std::min(1.0, std::abs(q[0]))) * 180 / M_PI;
    }
  }
  ASSERT_GE(turned_deg, 5) << "the pose did not turn within " << 5 * kTimeScale << " s";
  const auto tare = cli.Post("/api/command", R"({"command":"tare"})", "application/json");
  ASSERT_TRUE(tare);
  EXPECT_EQ(tare->status, 200);
  EXPECT_EQ(tare->body,
            "{\"command\":\"TARE\",\"ack\":true,\"code\":0,\"result\":\"ACK\",\"sequence\":0}\n");
  const auto bad = cli.Post("/api/command", R"({"command":"tare","x":1})", "application/json");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  run.join();
  ASSERT_EQ(d.status, 0) << d.out;

  tacse3::test::BusEvents b;
  ASSERT_TRUE(b.feed_log(read_all(dir_ / "bus.log")));
  EXPECT_TRUE(b.acks.empty()) << "the web command's ACK went on the bus";
  std::vector<std::size_t> flagged;
  for (std::size_t i = 0; i < b.cycles.size(); ++i) {
    if (b.cycles[i].pose_reset) flagged.push_back(i);
  }
  ASSERT_EQ(flagged.size(), 1u) << "one tare, one PoseReset cycle";
  const std::size_t i = flagged[0];
  EXPECT_NEAR(b.cycles[i].orientation.w, 1.0, 1e-3);
  const double before_deg =
      2 * std::acos(std::min(1.0, std::abs(b.cycles[i - 1].orientation.w))) * 180 / M_PI;
  EXPECT_GE(before_deg, 5) << "the pose before the tare, on the bus";
}

TEST_F(ViewerTest, BadAddressIsAUsageErrorAndABusyPortAStartError) {
  for (const char* bad : {"127.0.0.1:0", "127.0.0.1:99999", "board:80", "x"}) {
    const RunResult r = run_cmd(daemon(bad, 1));
    EXPECT_EQ(r.status, 2) << bad << "\n" << r.out;
    EXPECT_NE(r.out.find("--http \""), std::string::npos) << r.out;
  }
  // Someone else listens on the port.
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port_));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(s, reinterpret_cast<sockaddr*>(&a), sizeof(a)), 0);
  ASSERT_EQ(listen(s, 1), 0);
  const RunResult r = run_cmd(daemon(std::to_string(port_), 1));
  close(s);
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_NE(r.out.find("--http " + std::to_string(port_) + ": 127.0.0.1:" + std::to_string(port_) +
                       ": cannot listen: address already in use"),
            std::string::npos)
      << r.out;
}

namespace {

// The engine's timing from the daemon's summary line ("latency p50 A us p99 B us, dsp p50 C us"):
// frame timestamp -> last CAN frame of the cycle handed to the channel, and the DSP time per
// sample, each over the engine's window of the last 256 cycles.
struct EngineTiming {
  double latency_p50_us = NAN;
  double latency_p99_us = NAN;
  double dsp_p50_us = NAN;
};

EngineTiming summary_timing(const std::string& out) {
  EngineTiming t;
  const std::size_t at = out.find("latency p50 ");
  long long a = 0, b = 0, c = 0;
  if (at != std::string::npos &&
      std::sscanf(out.c_str() + at, "latency p50 %lld us p99 %lld us, dsp p50 %lld us", &a, &b,
                  &c) == 3) {
    t = EngineTiming{static_cast<double>(a), static_cast<double>(b), static_cast<double>(c)};
  }
  return t;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];  // odd sizes only here
}

// One paced run (the frames stamped on CLOCK_MONOTONIC, so the latency is real) with --http.
// With `clients`, four stay connected from the first /api/state to the daemon's exit: three
// reading /api/stream (the ids of the events each received in *events) and the one that never
// reads.
RunResult paced_run(const std::string& daemon_cmd, int port, bool clients,
                    std::vector<std::vector<long>>* events) {
  RunResult d;
  DaemonThread run(daemon_cmd, &d);
  httplib::Client cli("127.0.0.1", port);
  cli.set_connection_timeout(1);
  std::string why;
  const bool live = wait_live(cli, run, nullptr, &why);
  int mute = -1;
  std::vector<std::thread> readers;
  events->assign(3, {});
  if (live && clients) {
    mute = mute_client(port);
    for (std::size_t k = 0; k < 3; ++k) {
      readers.emplace_back([port, k, events] {
        httplib::Client c("127.0.0.1", port);
        c.set_read_timeout(3 * kTimeScale);
        std::string buf;
        c.Get("/api/stream", [&](const char* data, std::size_t n) {
          buf.append(data, n);
          for (std::size_t at; (at = buf.find("\n\n")) != std::string::npos; buf.erase(0, at + 2)) {
            long id = 0;
            if (std::sscanf(buf.c_str(), "event: state\nid: %ld", &id) == 1) {
              (*events)[k].push_back(id);
            }
          }
          return true;  // until the daemon closes the stream at its exit
        });
      });
    }
  }
  run.join();
  for (auto& t : readers) t.join();
  if (mute >= 0) close(mute);
  if (!live) {
    d.status = -1;
    d.out += why + "\n";
  }
  if (live && clients && mute < 0) {
    d.status = -2;
    d.out += std::string("mute client: ") + std::strerror(-mute) + "\n";
  }
  return d;
}

}  // namespace

// The engine's timing holds with four clients connected, one of them never reading: the same
// paced run with and without the clients, side by side, five times (three under the sanitizers,
// where a run takes 20 s); their medians compared.
// Side by side and by medians, because on a shared test machine the latency's tail follows the
// machine's load from second to second: the two runs see the same load, so what differs is what
// serving the clients costs the engine.
//
// The bound: the viewer takes nothing from the DSP thread but one copy into a lock-free slot per
// cycle; encoding and sending run on the server's threads, and the client that never reads
// blocks only its own. What the clients can cost the engine is CPU: on a 2-core machine their
// threads share a core with the DSP and camera threads. If they took half of it in the slowest
// cycles, those cycles' latency would double, hence p99 <= 2 x p99 without clients; and at least
// 1 ms above it, the scheduler's wake-up granularity on a loaded machine, so a short baseline
// does not turn noise into a failure. The DSP time's median gets the same bound. A DSP thread
// that waited on a client (a lock held while encoding, a blocking send) would add frame periods
// to its cycles, and a stalled stream's whole time to the tail. Under the sanitizers every step
// is ~5 times slower, and so are the runs, the waits and the 1 ms.
TEST_F(ViewerTest, EngineTimingHoldsWithFourClientsOneNeverReading) {
  std::string text = read_all(dir_ / "board.toml");
  text.replace(text.find("realtime = false"), 16, "realtime = true");
  std::ofstream(dir_ / "board.toml") << text;
  constexpr int kPairs = kSanitized ? 3 : 5;
  std::vector<double> p99[2], p50[2], dsp[2];
  for (int pair = 0; pair < kPairs; ++pair) {
    RunResult d[2];
    std::vector<std::vector<long>> events[2];
    std::vector<std::thread> runs;
    for (int clients = 0; clients < 2; ++clients) {
      const int port = free_port();
      std::string cmd = daemon("127.0.0.1:" + std::to_string(port), 4 * kTimeScale);
      cmd.replace(cmd.find("bus.log"), 7, "bus-" + std::to_string(clients) + ".log");
      runs.emplace_back([&, cmd, port, clients] {
        d[clients] = paced_run(cmd, port, clients == 1, &events[clients]);
      });
    }
    for (auto& t : runs) t.join();
    for (int clients = 0; clients < 2; ++clients) {
      const RunResult& r = d[clients];
      ASSERT_EQ(r.status, 0)
          << (clients ? "with" : "without")
          << " clients (-1: no /api/state, -2: the mute client could not connect, "
             "128 + N: signal N)\n"
          << r.out;
      const EngineTiming t = summary_timing(r.out);
      ASSERT_TRUE(t.latency_p99_us > 0 && t.dsp_p50_us > 0) << "no timing in the summary\n"
                                                            << r.out;
      p99[clients].push_back(t.latency_p99_us);
      p50[clients].push_back(t.latency_p50_us);
      dsp[clients].push_back(t.dsp_p50_us);
      std::printf("pair %d, %d clients: latency p50 %.0f us p99 %.0f us, dsp p50 %.0f us\n", pair,
                  4 * clients, t.latency_p50_us, t.latency_p99_us, t.dsp_p50_us);
    }
    // Each reader saw most of what was streamed once all three were connected (after the last
    // reader's first event): a reader held up by the mute client would see a few at most.
    // Against what the readers saw, not a nominal 20 Hz: on a loaded machine the nice'd sampler
    // renders fewer, and the readers connect only once /api/state answers.
    long from = LONG_MIN;
    for (const auto& ids : events[1]) {
      ASSERT_FALSE(ids.empty()) << "a reader received no event\n" << d[1].out;
      from = std::max(from, ids.front());
    }
    std::set<long> streamed;
    for (const auto& ids : events[1])
      streamed.insert(std::upper_bound(ids.begin(), ids.end(), from), ids.end());
    for (const auto& ids : events[1]) {
      const auto n =
          static_cast<std::size_t>(ids.end() - std::upper_bound(ids.begin(), ids.end(), from));
      EXPECT_GE(2 * n, streamed.size()) << "a reader's events of " << streamed.size() << "\n"
                                        << d[1].out;
    }
    EXPECT_NE(d[1].out.find("0 streams refused"), std::string::npos) << d[1].out;
  }
  const double slack_us = 1000.0 * kTimeScale;
  const auto bound = [&](double base) { return std::max(2.0 * base, base + slack_us); };
  const double p99_0 = median(p99[0]), p99_4 = median(p99[1]);
  const double dsp_0 = median(dsp[0]), dsp_4 = median(dsp[1]);
  std::printf(
      "medians: latency p50 %.0f -> %.0f us, p99 %.0f -> %.0f us, dsp p50 %.0f -> %.0f us\n",
      median(p50[0]), median(p50[1]), p99_0, p99_4, dsp_0, dsp_4);
  EXPECT_LE(p99_4, bound(p99_0)) << "latency p99 with four clients against none (us)";
  EXPECT_LE(dsp_4, bound(dsp_0)) << "DSP time p50 with four clients against none (us)";
}
