// SPDX-License-Identifier: Apache-2.0
// tacse3 viewer: the live viewer's HTTP server. Two kinds of threads, all at a lower priority
// than the DSP thread: one sampler takes each snapshot from the slot and renders it once (JSON,
// JPEG); the server's pool threads only hand out what was rendered, under a short lock.
#include "tacse3/viewer/view_server.hpp"

#include <fcntl.h>
#include <httplib.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <turbojpeg.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <vector>

#include "tacse3/hal/thread.hpp"
#include "tacse3/protocol/commands.hpp"
#include "tacse3/viewer/view_json.hpp"

namespace tacse3::viewer {

using hal::Thread;

namespace {

constexpr int kJpegQuality = 85;
constexpr auto kSamplePoll = std::chrono::milliseconds(10);
constexpr auto kStreamHeartbeat = std::chrono::seconds(1);
// The longest the refuser and the listener wait for a connection before looking for a stop.
constexpr auto kAcceptPoll = std::chrono::milliseconds(100);
// Stack sizes (docs/performance.md, "Thread stacks"): under the daemon's memory locking a
// touched stack page stays resident. Measured high-water marks while serving the page, every
// endpoint and an event stream: sampler (JSON, JPEG encoding) 12 KiB, listener 12 KiB, pool
// threads 20 KiB; 128 KiB leaves at least 6x.
constexpr std::size_t kSamplerStack = 128 * 1024;
constexpr std::size_t kListenerStack = 128 * 1024;
constexpr std::size_t kPoolStack = 128 * 1024;
constexpr std::size_t kRefuserStack = 64 * 1024;  // poll, accept, a fixed answer

}  // namespace

// A rendered snapshot, shared by every request that serves it.
struct Rendered {
  std::uint64_t seq = 0;
  std::shared_ptr<const ViewSnapshot> snapshot;
  std::string state_json;
  std::array<std::string, 2> jpeg;  // empty: the pad is not configured
};

namespace {

struct Asset {
  std::string body;
  const char* mime;
};

// The files the page is made of: served from memory, read once at start; nothing else on disk is
// reachable. Optional files (the plotting library) may be absent: the page says so.
struct AssetName {
  const char* name;
  const char* mime;
  bool required;
};
constexpr AssetName kAssets[] = {
    {"index.html", "text/html; charset=utf-8", true},
    {"viewer.js", "text/javascript; charset=utf-8", true},
    {"viewer.css", "text/css; charset=utf-8", true},
    {"uPlot.iife.min.js", "text/javascript; charset=utf-8", false},
    {"uPlot.min.css", "text/css; charset=utf-8", false},
};

bool read_file(const std::filesystem::path& p, std::string* out) {
  std::ifstream in(p, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  *out = s.str();
  return static_cast<bool>(in) || in.eof();
}

std::string encode_jpeg(tjhandle tj, const std::array<std::uint8_t, dsp::kWorkPixels>& luma) {
  unsigned char* buf = nullptr;
  unsigned long size = 0;
  std::string out;
  if (tjCompress2(tj, luma.data(), dsp::kWorkWidth, 0, dsp::kWorkHeight, TJPF_GRAY, &buf, &size,
                  TJSAMP_GRAY, kJpegQuality, TJFLAG_FASTDCT) == 0) {
    out.assign(reinterpret_cast<const char*>(buf), size);
  }
  tjFree(buf);
  return out;
}

// The snapshot's JSON and its pads' JPEGs, made once.
std::shared_ptr<const Rendered> render(tjhandle tj, std::shared_ptr<const ViewSnapshot> snap,
                                       std::uint64_t seq, const ViewTruth* truth) {
  auto r = std::make_shared<Rendered>();
  r->seq = seq;
  r->state_json = view_state_json(*snap, truth);
  for (std::size_t s = 0; s < 2; ++s) {
    if (snap->pads[s].configured && tj != nullptr) r->jpeg[s] = encode_jpeg(tj, snap->pads[s].luma);
  }
  r->snapshot = std::move(snap);
  return r;
}

std::string error_json(const std::string& message) {
  std::string s = "{\"error\":";
  s += json_quote(message);
  s += "}\n";
  return s;
}

// The ACK/NACK as the HTTP answer: the same codes as the CAN Ack frame (docs/can-protocol.md).
std::string ack_json(const protocol::Ack& a) {
  std::string s = "{\"command\":";
  s += json_quote(protocol::to_string(a.command));
  s += ",\"ack\":";
  s += a.result == protocol::AckCode::kAck ? "true" : "false";
  s += ",\"code\":";
  s += std::to_string(static_cast<int>(a.result));
  s += ",\"result\":";
  s += json_quote(protocol::to_string(a.result));
  s += ",\"sequence\":";
  s += std::to_string(static_cast<int>(a.sequence));
  s += "}\n";
  return s;
}

// httplib's ThreadPool with sized stacks: the server takes its task queue from us, and httplib's
// own pool starts std::threads with the default 8 MiB stack.
class SizedPool final : public httplib::TaskQueue {
 public:
  // on_full: called when the listener starts waiting for room (under the pool's lock).
  SizedPool(std::size_t n, std::size_t max_waiting, std::size_t stack_bytes,
            std::function<void()> on_full)
      : max_waiting_(max_waiting), on_full_(std::move(on_full)) {
    workers_.reserve(n);
    try {
      for (std::size_t i = 0; i < n; ++i) workers_.emplace_back(stack_bytes, [this] { work(); });
    } catch (...) {
      shutdown();
      throw;
    }
  }
  ~SizedPool() override { shutdown(); }

  // Called by httplib's listener with each accepted connection. With `max_waiting` connections
  // waiting for a worker, it holds the listener here until one is taken: the listener accepts
  // nothing meanwhile, and the Refuser answers the rest (docs/viewer.md, "Limits").
  void enqueue(std::function<void()> fn) override {
    std::unique_lock<std::mutex> lock(mutex_);
    jobs_.push_back(std::move(fn));
    cond_.notify_one();
    if (jobs_.size() < max_waiting_) return;
    full_.store(true);
    on_full_();
    room_.wait(lock, [this] { return jobs_.size() < max_waiting_ || releasing_; });
    full_.store(false);
  }

  // True while the listener waits for room (the Refuser's cue).
  bool full() const noexcept { return full_.load(); }
  // Lets a listener held in enqueue() go: the server is stopping.
  void release() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      releasing_ = true;
    }
    room_.notify_all();
  }

  // Runs the jobs already queued, then joins every worker.
  void shutdown() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    cond_.notify_all();
    for (auto& t : workers_) {
      if (t.joinable()) t.join();
    }
  }

 private:
  void work() {
    for (;;) {
      std::function<void()> fn;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        cond_.wait(lock, [this] { return !jobs_.empty() || stopping_; });
        if (jobs_.empty()) return;
        fn = std::move(jobs_.front());
        jobs_.pop_front();
      }
      room_.notify_one();
      fn();
    }
  }

  const std::size_t max_waiting_;
  const std::function<void()> on_full_;
  std::mutex mutex_;
  std::condition_variable cond_;
  std::condition_variable room_;            // a job was taken, or release()
  std::deque<std::function<void()>> jobs_;  // guarded by mutex_
  bool stopping_ = false;                   // guarded by mutex_
  bool releasing_ = false;                  // guarded by mutex_
  std::atomic<bool> full_{false};
  std::vector<Thread> workers_;  // last: started once the rest exists
};

// Linux: nice is per thread, and threads inherit it from the thread that creates them.
void lower_priority(int nice) {
  setpriority(PRIO_PROCESS, 0, nice);
}

// A connection beyond the limit: a fixed 503 sent without waiting (the socket is non-blocking),
// then closed. What the client sent is drained first, so the close is a FIN, not a reset that
// could discard the answer.
void refuse_connection(int sock) {
  static const char kBody[] =
      "{\"error\":\"too many connections: the viewer serves a fixed number at once; retry\"}\n";
  static const std::string kAnswer =
      std::string("HTTP/1.1 503 Service Unavailable\r\nContent-Type: application/json\r\n") +
      "Content-Length: " + std::to_string(sizeof(kBody) - 1) +
      "\r\nRetry-After: 1\r\nConnection: close\r\n\r\n" + kBody;
  (void)send(sock, kAnswer.data(), kAnswer.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
  shutdown(sock, SHUT_WR);
  char drain[4096];
  for (int i = 0; i < 4 && recv(sock, drain, sizeof(drain), MSG_DONTWAIT) > 0; ++i) {
  }
  close(sock);
}

}  // namespace

bool parse_web_command(const std::string& body, protocol::Command* command, std::string* error) {
  const nlohmann::json j = nlohmann::json::parse(body, nullptr, false);
  const char* forms =
      "expected {\"command\": \"tare\"}, {\"command\": \"reset_pose\"} or "
      "{\"command\": \"stream\", \"on\": true|false}";
  if (j.is_discarded() || !j.is_object()) {
    *error = std::string("the body is not a JSON object: ") + forms;
    return false;
  }
  const auto name = j.find("command");
  if (name == j.end() || !name->is_string()) {
    *error = std::string("\"command\" is missing or not a string: ") + forms;
    return false;
  }
  const std::string n = name->get<std::string>();
  protocol::Command c;
  std::size_t keys = 1;
  if (n == "tare") {
    c.code = protocol::CommandCode::kTare;
  } else if (n == "reset_pose") {
    c.code = protocol::CommandCode::kResetPose;
  } else if (n == "stream") {
    const auto on = j.find("on");
    if (on == j.end() || !on->is_boolean()) {
      *error = "\"stream\" needs \"on\": true or false";
      return false;
    }
    c.code = protocol::CommandCode::kSetStream;
    c.stream_enabled = on->get<bool>();
    keys = 2;
  } else {
    *error = std::string("unknown command \"").append(n).append("\": ").append(forms);
    return false;
  }
  if (j.size() != keys) {
    *error = std::string("unknown key in the body: ").append(forms);
    return false;
  }
  *command = c;
  return true;
}

struct ViewServer::Impl {
  Impl(const ViewServerConfig& c, ViewSlot* s) : config(c), slot(s) {}

  ViewServerConfig config;
  ViewSlot* slot;           // live; null: a recording
  RecordedViews recorded;   // a recording's frames (empty when live)
  std::string frames_json;  // GET /api/frames of a recording
  httplib::Server server;
  std::map<std::string, Asset> assets;
  mutable std::mutex mutex;
  std::condition_variable changed;
  std::shared_ptr<const Rendered> latest;  // guarded by mutex
  bool stopping = false;                   // guarded by mutex
  std::atomic<int> streams{0};
  std::atomic<std::uint64_t> snapshots{0};
  std::atomic<std::uint64_t> refused{0};
  std::atomic<std::uint64_t> dropped{0};
  std::atomic<std::uint64_t> connections_refused{0};
  std::atomic<SizedPool*> pool{nullptr};  // made by httplib's listener thread
  int listen_fd = -1;                     // httplib's listening socket (non-blocking)
  Thread sampler;
  Thread listener;
  Thread refuser;

  // While the pool is full, accepts on the listening socket in the listener's place and answers
  // each connection 503 at once.
  void refuse_loop() {
    lower_priority(config.nice);
    for (;;) {
      {
        std::unique_lock<std::mutex> lock(mutex);
        if (stopping) return;
        const auto full = [this] {
          const SizedPool* p = pool.load();
          return p != nullptr && p->full();
        };
        if (!full()) {
          changed.wait_for(lock, kAcceptPoll, [&] { return stopping || full(); });
          continue;
        }
      }
      pollfd pfd{listen_fd, POLLIN, 0};
      if (poll(&pfd, 1, static_cast<int>(kAcceptPoll.count())) <= 0) continue;
      if (!pool.load()->full()) continue;  // room again: the listener serves it
      const int sock = accept4(listen_fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (sock < 0) continue;  // the listener took it, or nothing was pending
      connections_refused.fetch_add(1, std::memory_order_relaxed);
      refuse_connection(sock);
    }
  }

  std::shared_ptr<const Rendered> current() const {
    std::lock_guard<std::mutex> lock(mutex);
    return latest;
  }

  // What a request asks for: live, the latest snapshot (null before the first); a recording,
  // frame ?frame=N (null with *status and *error set when N is missing or out of range).
  std::shared_ptr<const Rendered> pick(const httplib::Request& req, int* status,
                                       std::string* error) const;

  void sample_loop() {
    lower_priority(config.nice);
    tjhandle tj = tjInitCompress();
    std::uint64_t seq = 0;
    std::unique_lock<std::mutex> lock(mutex);
    while (!stopping) {
      lock.unlock();
      if (slot->take()) {
        auto r = render(tj, std::make_shared<ViewSnapshot>(slot->front()), ++seq, nullptr);
        snapshots.fetch_add(1, std::memory_order_relaxed);
        lock.lock();
        latest = std::move(r);
        changed.notify_all();
      } else {
        lock.lock();
        changed.wait_for(lock, kSamplePoll, [this] { return stopping; });
      }
    }
    lock.unlock();
    if (tj != nullptr) tjDestroy(tj);
  }

  // One Server-Sent Event per rendered snapshot; a comment line every second when nothing is
  // new, so a client that went away is noticed. false ends the stream.
  bool stream_next(std::uint64_t* last, httplib::DataSink& sink) {
    std::shared_ptr<const Rendered> r;
    {
      std::unique_lock<std::mutex> lock(mutex);
      changed.wait_for(lock, kStreamHeartbeat,
                       [&] { return stopping || (latest && latest->seq != *last); });
      if (stopping) return false;
      r = latest;
    }
    std::string ev;
    if (!r || r->seq == *last) {
      ev = ": idle\n\n";
    } else {
      *last = r->seq;
      ev = "event: state\nid: ";
      ev += std::to_string(r->snapshot->cycle);
      ev += "\ndata: ";
      ev += r->state_json;
      ev += "\n\n";
    }
    if (!sink.write(ev.data(), ev.size())) {
      dropped.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    return true;
  }

  // One command at a time: the mailbox holds one, and its answer belongs to this request.
  std::mutex command_mutex;
  std::uint8_t command_sequence = 0;  // guarded by command_mutex

  void command(const httplib::Request& req, httplib::Response& res);
  void routes();
  void data_routes();
  void live_routes();
};

// POST /api/command: built as this node's CAN Command frame and validated by validate_command,
// exactly as the RX thread does, then applied by the DSP thread between two cycles.
void ViewServer::Impl::command(const httplib::Request& req, httplib::Response& res) {
  const auto fail = [&res](int status, const std::string& message) {
    res.status = status;
    res.set_content(error_json(message), "application/json");
  };
  if (config.commands == nullptr) return fail(403, config.controls_off);
  // A JSON content type makes a browser ask first (CORS preflight) before another site's page
  // can post here; the server never allows it.
  if (req.get_header_value("Content-Type").rfind("application/json", 0) != 0)
    return fail(415, "the body must be JSON: send Content-Type: application/json");
  protocol::Command c;
  std::string e;
  if (!parse_web_command(req.body, &c, &e)) return fail(400, e);
  std::lock_guard<std::mutex> lock(command_mutex);
  c.sequence = command_sequence;
  command_sequence = static_cast<std::uint8_t>((command_sequence + 1) & 0x0Fu);
  protocol::TxConfig tx;
  tx.endpoint = config.endpoint;
  protocol::CanFrame f;
  if (protocol::encode(c, tx, f) != protocol::Status::kOk)
    return fail(500, "the command could not be encoded");
  const protocol::CommandResult r = protocol::validate_command(f, config.endpoint);
  if (!r.addressed) return fail(500, "the command is not addressed to this node");
  if (!config.commands->submit(r))
    return fail(503, "the previous command is still waiting for the DSP thread; try again");
  protocol::Ack ack;
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(config.command_timeout_ms);
  while (!config.commands->poll(&ack)) {
    if (std::chrono::steady_clock::now() > deadline)
      return fail(504, std::string("the DSP thread did not answer within ")
                           .append(std::to_string(config.command_timeout_ms))
                           .append(" ms"));
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  res.status = ack.result == protocol::AckCode::kAck ? 200 : 409;
  res.set_content(ack_json(ack), "application/json");
}

std::shared_ptr<const Rendered> ViewServer::Impl::pick(const httplib::Request& req, int* status,
                                                       std::string* error) const {
  if (slot != nullptr) {
    auto r = current();
    if (!r) {
      *status = 503;
      *error = "no cycle yet";
    }
    return r;
  }
  const std::string n = req.get_param_value("frame");
  const std::string range = std::string("0..").append(std::to_string(recorded.size() - 1));
  char* end = nullptr;
  const unsigned long long i = std::strtoull(n.c_str(), &end, 10);
  if (n.empty() || n[0] < '0' || n[0] > '9' || *end != '\0') {
    *status = 400;
    *error = std::string("give the frame: ?frame=N, N in ").append(range);
    return nullptr;
  }
  if (i >= recorded.size()) {
    *status = 404;
    *error = std::string("frame ")
                 .append(n)
                 .append(" is not in the recording (")
                 .append(range)
                 .append(")");
    return nullptr;
  }
  return recorded.at(static_cast<std::size_t>(i));
}

// The page and what does not change.
void ViewServer::Impl::routes() {
  using httplib::Request;
  using httplib::Response;
  server.Get("/", [this](const Request&, Response& res) {
    const Asset& a = assets.at("index.html");
    res.set_content(a.body, a.mime);
  });
  for (const AssetName& n : kAssets) {
    if (assets.count(n.name) == 0) continue;
    std::string pattern = "/";  // the route is a regular expression: escape the dots
    for (const char* c = n.name; *c != '\0'; ++c) {
      if (*c == '.') pattern += '\\';
      pattern += *c;
    }
    const Asset* a = &assets.at(n.name);
    server.Get(pattern, [a](const Request&, Response& res) { res.set_content(a->body, a->mime); });
  }
  server.Get("/api/info", [this](const Request&, Response& res) {
    res.set_content(config.info_json, "application/json");
  });
  data_routes();
  if (slot != nullptr) {
    live_routes();
  } else {
    server.Get("/api/frames", [this](const Request&, Response& res) {
      res.set_content(frames_json, "application/json");
    });
  }
}

// One snapshot's state, fields and images: the latest (live) or ?frame=N (a recording).
void ViewServer::Impl::data_routes() {
  using httplib::Request;
  using httplib::Response;
  const auto get = [this](const Request& req, Response& res) {
    int status = 0;
    std::string e;
    auto r = pick(req, &status, &e);
    if (!r) {
      res.status = status;
      res.set_content(error_json(e), "application/json");
    } else {
      res.set_header("Cache-Control", "no-store");
    }
    return r;
  };
  server.Get("/api/state", [get](const Request& req, Response& res) {
    if (const auto r = get(req, res)) res.set_content(r->state_json, "application/json");
  });
  server.Get("/api/fields", [get](const Request& req, Response& res) {
    if (const auto r = get(req, res))
      res.set_content(view_fields_json(*r->snapshot), "application/json");
  });
  server.Get(R"(/api/image/(left|right)\.jpg)", [get](const Request& req, Response& res) {
    const std::size_t s = req.matches[1] == "left" ? 0 : 1;
    const auto r = get(req, res);
    if (!r) return;
    if (r->jpeg[s].empty()) {
      res.status = 404;
      res.set_content("no such sensor on this board\n", "text/plain");
      return;
    }
    res.set_header("X-Cycle", std::to_string(r->snapshot->cycle));
    res.set_content(r->jpeg[s], "image/jpeg");
  });
}

// What only a running daemon has: the event stream and the controls.
void ViewServer::Impl::live_routes() {
  using httplib::Request;
  using httplib::Response;
  server.Post("/api/command", [this](const Request& req, Response& res) { command(req, res); });
  server.Get("/api/stream", [this](const Request&, Response& res) {
    if (streams.fetch_add(1) >= config.max_streams) {
      streams.fetch_sub(1);
      refused.fetch_add(1, std::memory_order_relaxed);
      res.status = 503;
      res.set_content("too many streams open\n", "text/plain");
      return;
    }
    res.set_header("Cache-Control", "no-store");
    res.set_chunked_content_provider(
        "text/event-stream",
        [this, last = std::uint64_t{0}](std::size_t, httplib::DataSink& sink) mutable {
          return stream_next(&last, sink);
        },
        [this](bool) { streams.fetch_sub(1); });
  });
}

struct RecordedViews::Frames {
  std::vector<std::shared_ptr<const Rendered>> frames;
  tjhandle tj = tjInitCompress();
  ~Frames() {
    if (tj != nullptr) tjDestroy(tj);
  }
};

RecordedViews::RecordedViews() : frames_(std::make_unique<Frames>()) {}
RecordedViews::~RecordedViews() = default;
RecordedViews::RecordedViews(RecordedViews&&) noexcept = default;
RecordedViews& RecordedViews::operator=(RecordedViews&&) noexcept = default;

void RecordedViews::add(const ViewSnapshot& snapshot, const ViewTruth* truth) {
  const std::uint64_t seq = frames_->frames.size();
  frames_->frames.push_back(
      render(frames_->tj, std::make_shared<ViewSnapshot>(snapshot), seq, truth));
}

std::size_t RecordedViews::size() const noexcept {
  return frames_->frames.size();
}

const std::shared_ptr<const Rendered>& RecordedViews::at(std::size_t i) const {
  return frames_->frames.at(i);
}

std::string RecordedViews::frames_json() const {
  std::string s =
      std::string("{\"frames\":").append(std::to_string(size())).append(",\"states\":[");
  for (std::size_t i = 0; i < size(); ++i) {
    if (i > 0) s += ',';
    s += frames_->frames[i]->state_json;
  }
  s += "]}";
  return s;
}

std::filesystem::path find_viewer_assets(const std::filesystem::path& exe_dir) {
  std::error_code ec;
  for (const std::filesystem::path& dir : {exe_dir / ".." / "share" / "tacse3" / "viewer",
                                           std::filesystem::path(TACSE3_BUILD_VIEWER_DIR)}) {
    if (std::filesystem::is_regular_file(dir / "index.html", ec)) {
      return std::filesystem::weakly_canonical(dir, ec);
    }
  }
  return {};
}

ViewServer::ViewServer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

std::unique_ptr<ViewServer> ViewServer::start(const ViewServerConfig& config, ViewSlot& slot,
                                              std::string* error) {
  return serve(std::make_unique<Impl>(config, &slot), error);
}

std::unique_ptr<ViewServer> ViewServer::start(const ViewServerConfig& config,
                                              RecordedViews recording, std::string* error) {
  if (recording.size() == 0) {
    *error = "the recording has no frame to show";
    return nullptr;
  }
  auto impl = std::make_unique<Impl>(config, nullptr);
  impl->recorded = std::move(recording);
  impl->frames_json = impl->recorded.frames_json();
  return serve(std::move(impl), error);
}

std::unique_ptr<ViewServer> ViewServer::serve(std::unique_ptr<Impl> impl, std::string* error) {
  const ViewServerConfig& config = impl->config;
  for (const AssetName& n : kAssets) {
    std::string body;
    if (read_file(config.assets / n.name, &body)) {
      impl->assets.emplace(n.name, Asset{std::move(body), n.mime});
    } else if (n.required) {
      *error = std::string("viewer asset ").append((config.assets / n.name).string());
      *error += " cannot be read";
      return nullptr;
    }
  }
  httplib::Server& sv = impl->server;
  Impl* p = impl.get();
  sv.new_task_queue = [p] {
    auto* pool = new SizedPool(static_cast<std::size_t>(p->config.threads),
                               static_cast<std::size_t>(p->config.max_waiting), kPoolStack, [p] {
                                 { std::lock_guard<std::mutex> lock(p->mutex); }
                                 p->changed.notify_all();
                               });
    p->pool.store(pool);
    return pool;
  };
  // SO_REUSEADDR only: a restart binds at once, but a second daemon on the same port fails
  // (httplib's default adds SO_REUSEPORT, which would let both listen). Non-blocking, so that the
  // refuser and the listener can both accept on it (whoever loses gets EAGAIN); the listener
  // waits for a connection in select() first (the idle interval below).
  sv.set_socket_options([p](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
    fcntl(sock, F_SETFL, fcntl(sock, F_GETFL) | O_NONBLOCK);
    p->listen_fd = sock;
  });
  sv.set_idle_interval(0, std::chrono::microseconds(kAcceptPoll).count());
  sv.set_keep_alive_max_count(1000);
  sv.set_keep_alive_timeout(2);
  sv.set_read_timeout(2, 0);
  sv.set_write_timeout(config.write_timeout_ms / 1000, (config.write_timeout_ms % 1000) * 1000);
  sv.set_payload_max_length(4096);  // the largest body is POST /api/command's few bytes
  impl->routes();
  errno = 0;
  if (!sv.bind_to_port(config.listen.host, config.listen.port)) {
    const int e = errno;
    *error = config.listen.host + ":" + std::to_string(config.listen.port) + ": cannot listen: " +
             (e == EADDRINUSE ? std::string("address already in use (another program serves this "
                                            "port; choose another)")
              : e != 0        ? std::string(std::strerror(e))
                              : std::string("bind failed"));
    return nullptr;
  }
  if (p->slot != nullptr) p->sampler = Thread(kSamplerStack, [p] { p->sample_loop(); });
  p->refuser = Thread(kRefuserStack, [p] { p->refuse_loop(); });
  p->listener = Thread(kListenerStack, [p] {
    lower_priority(p->config.nice);  // before the pool threads exist: they inherit it
    p->server.listen_after_bind();
  });
  // stop() only stops a server that is running: wait for it, so the destructor cannot miss it.
  for (int i = 0; i < 1000 && !p->server.is_running(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  return std::unique_ptr<ViewServer>(new ViewServer(std::move(impl)));
}

ViewServer::~ViewServer() {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->stopping = true;
  }
  impl_->changed.notify_all();
  // The refuser polls the listening socket: it ends before server.stop() closes it. A listener
  // held by a full pool is let go so that it sees the stop.
  if (impl_->refuser.joinable()) impl_->refuser.join();
  if (SizedPool* pool = impl_->pool.load()) pool->release();
  impl_->server.stop();
  if (impl_->listener.joinable()) impl_->listener.join();
  if (impl_->sampler.joinable()) impl_->sampler.join();
}

ViewServer::Stats ViewServer::stats() const noexcept {
  Stats s;
  s.snapshots = impl_->snapshots.load(std::memory_order_relaxed);
  s.streams_refused = impl_->refused.load(std::memory_order_relaxed);
  s.streams_dropped = impl_->dropped.load(std::memory_order_relaxed);
  s.connections_refused = impl_->connections_refused.load(std::memory_order_relaxed);
  return s;
}

}  // namespace tacse3::viewer
