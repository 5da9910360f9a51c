// SPDX-License-Identifier: Apache-2.0
// viewer tests: the viewer's HTTP server in-process on a synthetic snapshot: the exact JSON of
// /api/state, the answers to a table of well-formed, hostile and malformed raw requests, the
// stream's events and its client limit.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "free_port.hpp"
#include "tacse3/protocol/commands.hpp"
#include "tacse3/protocol/types.hpp"
#include "tacse3/viewer/view_json.hpp"
#include "tacse3/viewer/view_server.hpp"

namespace fs = std::filesystem;
using namespace tacse3;
using namespace tacse3::viewer;

using tacse3::test::free_port;

namespace {

int connect_to(int port) {
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(s, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) {
    close(s);
    return -1;
  }
  timeval tv{3, 0};
  setsockopt(s, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
  return s;
}

// Sends `request` as is on a new connection and returns everything the server sent until it
// closed the connection (requests here say "Connection: close") or 3 s passed.
std::string exchange(int port, const std::string& request) {
  const int s = connect_to(port);
  if (s < 0) return {};
  send(s, request.data(), request.size(), MSG_NOSIGNAL);
  std::string out;
  char buf[4096];
  for (ssize_t n; (n = recv(s, buf, sizeof(buf), 0)) > 0;) out.append(buf, static_cast<size_t>(n));
  close(s);
  return out;
}

int status_of(const std::string& response) {
  if (response.rfind("HTTP/1.1 ", 0) != 0) return -1;
  return std::atoi(response.c_str() + 9);
}

std::string body_of(const std::string& response) {
  const std::size_t at = response.find("\r\n\r\n");
  return at == std::string::npos ? std::string() : response.substr(at + 4);
}

std::string get(const std::string& path) {
  return "GET " + path + " HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n";
}

void fill(ViewSnapshot* v, std::uint64_t cycle) {
  *v = ViewSnapshot{};
  v->cycle = cycle;
  v->t_us = 123456;
  v->state = static_cast<std::uint8_t>(protocol::State::kTracking);
  v->have_result = true;
  v->valid = true;
  v->calibrated = true;
  v->w = {0.5, -0.25, 0.0};
  v->v = {0.001, std::numeric_limits<double>::quiet_NaN(), 0.0};
  v->q = {0.5, 0.5, 0.5, 0.5};
  v->p = {0.01, 0.0, -0.002};
  v->confidence = 0.75;
  v->dsp_us = 900;
  v->latency_us = 4100;
  v->counters = {40, 1, 2, 3, 4};
  ViewPad& l = v->pads[0];
  l.configured = l.present = l.contact = true;
  l.health = static_cast<std::uint8_t>(protocol::SensorHealth::kOk);
  l.contact_area_m2 = 5e-5;
  l.tracked_fraction = 0.5;
  l.frames = 100;
  l.dropped = 5;
  for (std::size_t i = 0; i < l.luma.size(); ++i) l.luma[i] = static_cast<std::uint8_t>(i * 7);
  v->pads[1].health = static_cast<std::uint8_t>(protocol::SensorHealth::kNotAvailable);
}

class ViewServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    assets_ = fs::temp_directory_path() / ("tacse3-view-server-" + std::to_string(getpid()));
    fs::create_directories(assets_);
    std::ofstream(assets_ / "index.html") << "<p>page</p>";
    std::ofstream(assets_ / "viewer.js") << "js";
    std::ofstream(assets_ / "viewer.css") << "css";
    config_.listen = {"127.0.0.1", free_port()};
    config_.assets = assets_;
    config_.info_json = view_info_json({"0.1.0", "sim", "board.toml", "", "", ""});
    std::string e;
    server_ = ViewServer::start(config_, slot_, &e);
    ASSERT_TRUE(server_) << e;
  }
  void TearDown() override {
    server_.reset();
    fs::remove_all(assets_);
  }
  // Publishes a snapshot and waits until the server serves it.
  void publish(std::uint64_t cycle) {
    fill(&slot_.back(), cycle);
    slot_.publish();
    const std::string want = "\"cycle\":" + std::to_string(cycle) + ",";
    for (int i = 0; i < 300; ++i) {
      if (body_of(exchange(port(), get("/api/state"))).find(want) != std::string::npos) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    FAIL() << "cycle " << cycle << " not served within 3 s";
  }
  int port() const { return config_.listen.port; }

  fs::path assets_;
  ViewServerConfig config_;
  ViewSlot slot_;
  std::unique_ptr<ViewServer> server_;
};

std::string post(const std::string& path, const std::string& body,
                 const std::string& type = "application/json") {
  return "POST " + path + " HTTP/1.1\r\nHost: t\r\nContent-Type: " + type +
         "\r\nContent-Length: " + std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" +
         body;
}

// The server with its controls on; a thread plays the DSP thread's part of the mailbox: it keeps
// what it was given and answers with make_ack (the engine's answer before applying), or with
// `nack`, or not at all while `silent`.
class ViewControlsTest : public ViewServerTest {
 protected:
  void SetUp() override {
    ViewServerTest::SetUp();
    server_.reset();
    config_.commands = &box_;
    config_.endpoint.node_id = 5;
    config_.command_timeout_ms = 300;
    dsp_ = std::thread([this] {
      while (!stop_) {
        protocol::CommandResult r;
        if (!silent_ && box_.take(&r)) {
          protocol::Ack a = protocol::make_ack(r);
          if (nack_ != 0) a.result = static_cast<protocol::AckCode>(nack_.load());
          {
            std::lock_guard<std::mutex> lock(mutex_);
            taken_.push_back(r);
          }
          box_.answer(a);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    });
    std::string e;
    server_ = ViewServer::start(config_, slot_, &e);
    ASSERT_TRUE(server_) << e;
  }
  void TearDown() override {
    stop_ = true;
    dsp_.join();
    ViewServerTest::TearDown();
  }
  std::vector<protocol::CommandResult> taken() {
    std::lock_guard<std::mutex> lock(mutex_);
    return taken_;
  }

  CommandMailbox box_;
  std::thread dsp_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> silent_{false};
  std::atomic<int> nack_{0};
  std::mutex mutex_;
  std::vector<protocol::CommandResult> taken_;
};

}  // namespace

TEST(ViewJson, StateIsTheDocumentedDocument) {
  ViewSnapshot v;
  fill(&v, 42);
  EXPECT_EQ(view_state_json(v),
            "{\"cycle\":42,\"t_us\":123456,\"state\":\"TRACKING\",\"valid\":true,"
            "\"single_sensor\":false,\"calibrated\":true,"
            "\"twist\":{\"w\":[0.5,-0.25,0],\"v\":[0.001,null,0]},"
            "\"pose\":{\"q\":[0.5,0.5,0.5,0.5],\"p\":[0.01,0,-0.002]},\"confidence\":0.75,"
            "\"dsp_us\":900,\"latency_us\":4100,\"counters\":{\"cycles_sent\":40,"
            "\"can_send_failures\":1,\"can_tx_dropped\":2,\"commands\":3,\"rejected_commands\":4},"
            "\"sensors\":{"
            "\"left\":{\"configured\":true,\"present\":true,\"health\":\"OK\",\"contact\":true,"
            "\"slipping\":false,\"contact_area_m2\":5e-05,\"tracked_fraction\":0.5,\"frames\":100,"
            "\"dropped\":5},"
            "\"right\":{\"configured\":false,\"present\":false,\"health\":\"NOT_AVAILABLE\","
            "\"contact\":false,\"slipping\":false,\"contact_area_m2\":0,\"tracked_fraction\":0,"
            "\"frames\":0,\"dropped\":0}}}");
  const std::string f = view_fields_json(v);
  EXPECT_EQ(f.rfind("{\"cycle\":42,\"grid\":{\"width\":40,\"height\":30,\"image_width\":160,"
                    "\"image_height\":120},\"left\":{\"mask\":[0,0,",
                    0),
            0u)
      << f.substr(0, 200);
}

TEST(ViewJson, InfoQuotesEveryString) {
  EXPECT_EQ(json_quote("a\"b\\c\n\x01\xc3\xa9"), "\"a\\\"b\\\\c\\u000a\\u0001\xc3\xa9\"");
  ViewInfo info{"0.1.0", "sim", "/etc/tacse3/boards/sim \"x\"/board.toml", "", "", ""};
  EXPECT_EQ(view_info_json(info),
            "{\"version\":\"0.1.0\",\"board\":\"sim\","
            "\"board_file\":\"/etc/tacse3/boards/sim \\\"x\\\"/board.toml\",\"calibration\":null,"
            "\"controls\":true,\"controls_off\":null}");
  info.calibration = "/etc/tacse3/calibration.toml";
  EXPECT_NE(view_info_json(info).find("\"calibration\":\"/etc/tacse3/calibration.toml\","),
            std::string::npos);
  info.controls_off = "b.toml: [viewer] controls is not true";
  EXPECT_NE(view_info_json(info).find(
                "\"controls\":false,\"controls_off\":\"b.toml: [viewer] controls is not true\"}"),
            std::string::npos)
      << view_info_json(info);
}

TEST(ViewJson, ARecordingsFrameCarriesItsTruthAndTheInfoNamesTheRecording) {
  ViewSnapshot v;
  fill(&v, 3);
  const ViewTruth truth{{0.25, 0.5, -0.5, 0.625}, {0.001, std::nan(""), 0.0}};
  const std::string live = view_state_json(v);
  EXPECT_EQ(view_state_json(v, &truth),
            live.substr(0, live.size() - 1) +
                ",\"truth\":{\"q\":[0.25,0.5,-0.5,0.625],\"p\":[0.001,null,0]}}");
  ViewInfo info{"0.1.0", "recording", "/tmp/rec", "", "no controls", "/tmp/rec \"2\""};
  const std::string j = view_info_json(info);
  EXPECT_EQ(j.substr(j.size() - 30), ",\"recording\":\"/tmp/rec \\\"2\\\"\"}") << j;
}

// A recording's three frames: each endpoint serves ?frame=N, and only the documented ones exist.
TEST_F(ViewServerTest, ARecordingIsServedFrameByFrame) {
  server_.reset();
  RecordedViews views;
  std::vector<std::string> states;
  for (std::uint64_t i = 0; i < 3; ++i) {
    ViewSnapshot v;
    fill(&v, i + 1);
    const ViewTruth truth{{1.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.001 * static_cast<double>(i)}};
    views.add(v, &truth);
    states.push_back(view_state_json(v, &truth));
  }
  std::string e;
  server_ = ViewServer::start(config_, std::move(views), &e);
  ASSERT_TRUE(server_) << e;
  for (int i = 0; i < 3; ++i) {
    const std::string q = std::string("?frame=").append(std::to_string(i));
    EXPECT_EQ(body_of(exchange(port(), get(std::string("/api/state").append(q)))),
              states[static_cast<size_t>(i)]);
    const std::string image = exchange(port(), get(std::string("/api/image/left.jpg").append(q)));
    EXPECT_EQ(status_of(image), 200);
    EXPECT_NE(image.find(std::string("X-Cycle: ").append(std::to_string(i + 1)).append("\r\n")),
              std::string::npos);
    EXPECT_NE(body_of(exchange(port(), get(std::string("/api/fields").append(q))))
                  .find(std::string("{\"cycle\":").append(std::to_string(i + 1)).append(",")),
              std::string::npos);
  }
  EXPECT_EQ(body_of(exchange(port(), get("/api/frames"))),
            std::string("{\"frames\":3,\"states\":[") + states[0] + "," + states[1] + "," +
                states[2] + "]}");
  const std::string none = exchange(port(), get("/api/state"));
  EXPECT_EQ(status_of(none), 400);
  EXPECT_EQ(body_of(none), "{\"error\":\"give the frame: ?frame=N, N in 0..2\"}\n");
  for (const char* bad : {"?frame=-1", "?frame=1x", "?frame=", "?frame=%2B1"})
    EXPECT_EQ(status_of(exchange(port(), get(std::string("/api/fields") + bad))), 400) << bad;
  const std::string past = exchange(port(), get("/api/image/left.jpg?frame=3"));
  EXPECT_EQ(status_of(past), 404);
  EXPECT_EQ(body_of(past), "{\"error\":\"frame 3 is not in the recording (0..2)\"}\n");
  EXPECT_EQ(status_of(exchange(port(), get("/api/image/right.jpg?frame=0"))), 404);
  EXPECT_EQ(status_of(exchange(port(), get("/api/stream"))), 404);
  EXPECT_EQ(status_of(exchange(port(), post("/api/command", "{\"command\":\"tare\"}"))), 404);
  EXPECT_EQ(status_of(exchange(port(), get("/"))), 200);
}

TEST_F(ViewServerTest, AnEmptyRecordingIsRefused) {
  server_.reset();
  std::string e;
  EXPECT_FALSE(ViewServer::start(config_, RecordedViews{}, &e));
  EXPECT_EQ(e, "the recording has no frame to show");
}

TEST_F(ViewServerTest, NothingButTheDocumentedEndpoints) {
  EXPECT_EQ(status_of(exchange(port(), get("/api/state"))), 503) << "before the first snapshot";
  publish(7);
  struct Case {
    std::string request;
    int status;
  };
  const std::string long_uri = "/api/state?" + std::string(9000, 'a');
  const std::vector<Case> cases = {
      {get("/"), 200},
      {get("/viewer.js"), 200},
      {get("/viewer.css"), 200},
      {get("/api/state"), 200},
      {get("/api/state?x=1"), 200},
      {get("/api/fields"), 200},
      {get("/api/info"), 200},
      {get("/api/image/left.jpg"), 200},
      {get("/api/image/right.jpg"), 404},  // not configured in the snapshot
      {get("/api/image/centre.jpg"), 404},
      {get("/api/image/left.jpgx"), 404},
      {get("/viewerXjs"), 404},          // the dot is literal
      {get("/uPlot.iife.min.js"), 404},  // an optional asset that is absent
      {get("/index.html/../../etc/passwd"), 404},
      {get("/%2e%2e/%2e%2e/etc/passwd"), 404},
      {get("/api/../../etc/passwd"), 404},
      {"POST /api/state HTTP/1.1\r\nHost: t\r\nContent-Length: 2\r\nConnection: close\r\n\r\n{}",
       404},
      {"PUT / HTTP/1.1\r\nHost: t\r\nContent-Length: 0\r\nConnection: close\r\n\r\n", 404},
      {"DELETE /api/state HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n", 404},
      {"BREW / HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n", 400},
      {"GET / HTTP/9.9\r\nHost: t\r\nConnection: close\r\n\r\n", 400},
      {"\x01\x02\x03 garbage\r\n\r\n", 400},
      {get(long_uri), 414},
      {"POST / HTTP/1.1\r\nHost: t\r\nContent-Length: 100000\r\nConnection: close\r\n\r\n", 413},
  };
  for (const Case& c : cases) {
    const std::string r = exchange(port(), c.request);
    EXPECT_EQ(status_of(r), c.status) << c.request.substr(0, 60) << "\n" << r.substr(0, 200);
  }
  const std::string page = exchange(port(), get("/"));
  EXPECT_EQ(body_of(page), "<p>page</p>");
  EXPECT_NE(page.find("Content-Type: text/html"), std::string::npos);
  EXPECT_EQ(body_of(exchange(port(), get("/api/info"))), config_.info_json);
  // Still serving after all that.
  EXPECT_EQ(status_of(exchange(port(), get("/api/state"))), 200);
}

TEST_F(ViewServerTest, StreamsEverySnapshotAndRefusesAFifthClient) {
  publish(1);
  std::vector<int> streams;
  for (int i = 0; i < config_.max_streams; ++i) {
    streams.push_back(connect_to(port()));
    const std::string req = get("/api/stream");
    send(streams.back(), req.data(), req.size(), MSG_NOSIGNAL);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // all four are streaming
  EXPECT_EQ(status_of(exchange(port(), get("/api/stream"))), 503);
  EXPECT_EQ(server_->stats().streams_refused, 1u);
  // The first stream got the snapshot it found and each one published after, in order. A
  // stream sends the latest snapshot (a slow client skips, never queues), so each is published
  // once the stream has sent the one before.
  std::string got;
  char buf[4096];
  const auto read_until = [&](std::uint64_t c) {
    const std::string id = "id: " + std::to_string(c) + "\n";
    for (int i = 0; i < 50 && got.find(id) == std::string::npos; ++i) {
      const ssize_t n = recv(streams[0], buf, sizeof(buf), 0);
      if (n <= 0) break;
      got.append(buf, static_cast<size_t>(n));
    }
  };
  read_until(1);
  for (std::uint64_t c = 2; c <= 4; ++c) {
    publish(c);
    read_until(c);
  }
  EXPECT_NE(got.find("Content-Type: text/event-stream"), std::string::npos) << got;
  std::size_t at = 0;
  for (const char* id : {"id: 1\n", "id: 2\n", "id: 3\n", "id: 4\n"}) {
    const std::size_t next = got.find(id, at);
    ASSERT_NE(next, std::string::npos) << id << " missing or out of order in\n" << got;
    EXPECT_EQ(got.compare(next - 13, 13, "event: state\n"), 0);
    at = next;
  }
  EXPECT_NE(got.find("data: {\"cycle\":4,"), std::string::npos);
  // A stream that ends frees its place.
  close(streams[0]);
  streams.erase(streams.begin());
  bool admitted = false;
  for (int i = 0; i < 40 && !admitted; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const int s = connect_to(port());
    const std::string req = get("/api/stream");
    send(s, req.data(), req.size(), MSG_NOSIGNAL);
    const ssize_t n = recv(s, buf, sizeof(buf), 0);
    admitted = n > 0 && status_of(std::string(buf, static_cast<size_t>(n))) == 200;
    if (admitted) {
      streams.push_back(s);
    } else {
      close(s);
    }
  }
  EXPECT_TRUE(admitted) << "the closed stream's place was not freed within 4 s";
  for (int s : streams) close(s);
}

// Two served, two waiting (one of them held by the listener): every further connection is answered
// 503 at once, and once the idle ones are gone the endpoints answer again.
TEST_F(ViewServerTest, ConnectionsBeyondTheLimitAreRefusedAtOnce) {
  server_.reset();
  config_.threads = 2;
  config_.max_waiting = 2;
  std::string e;
  server_ = ViewServer::start(config_, slot_, &e);
  ASSERT_TRUE(server_) << e;
  publish(1);
  std::vector<int> idle;  // connected, never send a byte: each holds its place up to 2 s
  for (int i = 0; i < config_.threads + config_.max_waiting; ++i) {
    idle.push_back(connect_to(port()));
    ASSERT_GE(idle.back(), 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // accepted and placed
  }
  constexpr int kExtra = 5;
  for (int i = 0; i < kExtra; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::string answer = exchange(port(), get("/api/state"));
    const auto ms =
        std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0)
            .count();
    EXPECT_EQ(status_of(answer), 503) << answer;
    EXPECT_NE(body_of(answer).find("too many connections"), std::string::npos) << answer;
    EXPECT_LT(ms, 500) << "extra connection " << i << " answered after " << ms << " ms";
  }
  EXPECT_EQ(server_->stats().connections_refused, static_cast<std::uint64_t>(kExtra));
  for (int s : idle) close(s);
  // The server frees each idle connection's place when its thread reads the close, one after
  // another, so on a loaded machine a place may still be held for a moment after the first 200.
  const auto served_within_2s = [&](const char* path) {
    for (int i = 0; i < 40; ++i) {
      if (status_of(exchange(port(), get(path))) == 200) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  };
  EXPECT_TRUE(served_within_2s("/api/state")) << "not served within 2 s of the idle ones closing";
  EXPECT_TRUE(served_within_2s("/api/image/left.jpg")) << "not served within 2 s";
}

TEST_F(ViewServerTest, CommandsAreRefusedNamingTheBoardKeyWhenTheControlsAreOff) {
  const std::string r = exchange(port(), post("/api/command", "{\"command\":\"tare\"}"));
  EXPECT_EQ(status_of(r), 403) << r;
  EXPECT_EQ(body_of(r), std::string("{\"error\":\"").append(config_.controls_off).append("\"}\n"));
  EXPECT_NE(config_.controls_off.find("[viewer] controls = true"), std::string::npos);
  EXPECT_EQ(status_of(exchange(port(), get("/api/command"))), 404) << "POST only";
}

TEST_F(ViewControlsTest, EachCommandIsThisNodesCanCommandAndTheAckIsTheAnswer) {
  struct Case {
    const char* body;
    protocol::CommandCode code;
    std::uint8_t arg0;  // the argument byte as the CAN frame carries it
    const char* answer;
  };
  const Case cases[] = {
      {R"({"command":"tare"})", protocol::CommandCode::kTare, 0,
       R"({"command":"TARE","ack":true,"code":0,"result":"ACK","sequence":0})"},
      {R"({"command": "reset_pose"})", protocol::CommandCode::kResetPose, 0,
       R"({"command":"RESET_POSE","ack":true,"code":0,"result":"ACK","sequence":1})"},
      {R"({"command":"stream","on":false})", protocol::CommandCode::kSetStream, 0,
       R"({"command":"SET_STREAM","ack":true,"code":0,"result":"ACK","sequence":2})"},
      {R"({"on":true,"command":"stream"})", protocol::CommandCode::kSetStream, 1,
       R"({"command":"SET_STREAM","ack":true,"code":0,"result":"ACK","sequence":3})"},
  };
  for (const Case& c : cases) {
    const std::string r = exchange(port(), post("/api/command", c.body));
    EXPECT_EQ(status_of(r), 200) << c.body << "\n" << r;
    EXPECT_EQ(body_of(r), std::string(c.answer) + "\n") << c.body;
  }
  const auto got = taken();
  ASSERT_EQ(got.size(), 4u);
  for (std::size_t i = 0; i < got.size(); ++i) {
    // Validated by validate_command as a frame addressed to node 5: the CAN path's checks.
    EXPECT_TRUE(got[i].addressed);
    EXPECT_EQ(got[i].code, protocol::AckCode::kAck);
    EXPECT_EQ(got[i].command.code, cases[i].code);
    EXPECT_EQ(got[i].command.target_node, 5);
    EXPECT_EQ(got[i].echo_args[0], cases[i].arg0) << cases[i].body;
  }
  EXPECT_FALSE(got[2].command.stream_enabled);
  EXPECT_TRUE(got[3].command.stream_enabled);
}

TEST_F(ViewControlsTest, ANackIsA409CarryingTheReason) {
  nack_ = static_cast<int>(protocol::AckCode::kBusy);
  const std::string r = exchange(port(), post("/api/command", R"({"command":"tare"})"));
  EXPECT_EQ(status_of(r), 409) << r;
  EXPECT_EQ(body_of(r),
            "{\"command\":\"TARE\",\"ack\":false,\"code\":7,\"result\":\"BUSY\",\"sequence\":0}\n");
}

TEST_F(ViewControlsTest, NoAnswerFromTheDspThreadIsA504AndTheNextCommandStillWorks) {
  silent_ = true;
  const std::string r = exchange(port(), post("/api/command", R"({"command":"tare"})"));
  EXPECT_EQ(status_of(r), 504) << r;
  EXPECT_NE(body_of(r).find("did not answer within 300 ms"), std::string::npos) << r;
  // The late command is still waiting: the next one is refused until it is answered.
  EXPECT_EQ(status_of(exchange(port(), post("/api/command", R"({"command":"tare"})"))), 503);
  silent_ = false;
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(status_of(exchange(port(), post("/api/command", R"({"command":"tare"})"))), 200);
  EXPECT_EQ(taken().size(), 2u);
}

TEST_F(ViewControlsTest, BadBodiesAreRefusedWithTheExpectedForms) {
  struct Case {
    std::string request;
    int status;
    const char* message;  // part of the error, as the JSON body spells it
  };
  const Case cases[] = {
      {post("/api/command", ""), 400, "not a JSON object"},
      {post("/api/command", "tare"), 400, "not a JSON object"},
      {post("/api/command", "[\"tare\"]"), 400, "not a JSON object"},
      {post("/api/command", R"({"command":"tare")"), 400, "not a JSON object"},
      {post("/api/command", R"({})"), 400, R"(\"command\" is missing)"},
      {post("/api/command", R"({"command":1})"), 400, R"(\"command\" is missing or not a string)"},
      {post("/api/command", R"({"command":"TARE"})"), 400, R"(unknown command \"TARE\")"},
      {post("/api/command", R"({"command":"start_recording"})"), 400, "unknown command"},
      {post("/api/command", R"({"command":"stream"})"), 400, R"(needs \"on\": true or false)"},
      {post("/api/command", R"({"command":"stream","on":1})"), 400, R"(needs \"on\")"},
      {post("/api/command", R"({"command":"tare","on":true})"), 400, "unknown key"},
      {post("/api/command", R"({"command":"stream","on":true,"x":0})"), 400, "unknown key"},
      {post("/api/command", R"({"command":"tare"})", "application/x-www-form-urlencoded"), 415,
       "Content-Type: application/json"},
      {post("/api/command", R"({"command":"tare"})", "text/plain"), 415, "must be JSON"},
      {post("/api/command", "{\"command\":\"" + std::string(5000, 'a') + "\"}"), 413, ""},
  };
  for (const Case& c : cases) {
    const std::string r = exchange(port(), c.request);
    EXPECT_EQ(status_of(r), c.status) << c.request.substr(0, 120) << "\n" << r.substr(0, 300);
    EXPECT_NE(body_of(r).find(c.message), std::string::npos) << r.substr(0, 300);
  }
  EXPECT_TRUE(taken().empty()) << "nothing reached the DSP thread";
}
