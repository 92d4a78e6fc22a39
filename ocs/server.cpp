#include "ocs/server.hpp"

#include <httplib.h>
#include <pthread.h>
#include <sched.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "base/error.hpp"
#include "ocs/assets.hpp"
#include "ocs/frame_json.hpp"

namespace mppi::ocs {
namespace {

constexpr double kMaxTargetSpeedMps = 30.0;

void reply_error(httplib::Response& res, int status, const std::string& message) {
  res.status = status;
  res.set_content(nlohmann::json{{"error", message}}.dump(), "application/json");
}

// "0" / "1" (also false/true); anything else is an error naming the parameter.
bool parse_flag(const std::string& name, const std::string& text, bool* value, std::string* why) {
  if (text == "1" || text == "true") return *value = true, true;
  if (text == "0" || text == "false") return *value = false, true;
  *why = name + ": expects 0 or 1, got '" + text + "'";
  return false;
}

std::optional<std::string> header(const httplib::Request& req, const char* name) {
  if (!req.has_header(name)) return std::nullopt;
  return req.get_header_value(name);
}

std::unique_ptr<httplib::Server> make_http_server(const ServerSettings& s) {
  const PageAccess& a = s.access;
  if (a.tls_cert_file.empty() != a.tls_key_file.empty())
    throw Error("ocs server: TLS needs both a certificate and a key file (--serve-cert and --serve-key)");
  if (a.tls_cert_file.empty()) {
    if (!is_loopback_bind(s.bind_address) && !a.insecure_remote)
      throw Error("ocs server: refusing to serve the operator page on " + s.bind_address +
                  " (off loopback) over plain HTTP: anyone on the network path could read the token and drive "
                  "the car. Give --serve-cert FILE --serve-key FILE for HTTPS, or --serve-insecure-remote to "
                  "accept that risk (docs/SECURITY.md)");
    return std::make_unique<httplib::Server>();
  }
#ifdef CPPHTTPLIB_OPENSSL_SUPPORT
  auto tls = std::make_unique<httplib::SSLServer>(a.tls_cert_file.c_str(), a.tls_key_file.c_str());
  if (!tls->is_valid())
    throw Error("ocs server: cannot use the TLS certificate " + a.tls_cert_file + " with the key " +
                a.tls_key_file + " (missing, unreadable, not PEM, or not a pair)");
  return tls;
#else
  throw Error("ocs server: this build's cpp-httplib has no OpenSSL support, so no HTTPS (Debian's libcpp-httplib-dev has)");
#endif
}

// The page comes after the controller: every thread of the server runs under SCHED_IDLE, so it
// only gets a core the controller's threads leave idle (Linux; elsewhere nothing changes).
void yield_to_controller() {
#ifdef SCHED_IDLE
  thread_local bool lowered = false;
  if (lowered) return;
  sched_param param{};
  param.sched_priority = 0;
  pthread_setschedparam(pthread_self(), SCHED_IDLE, &param);
  lowered = true;
#endif
}

}  // namespace

OcsServer::OcsServer(ServerSettings settings, LiveObserver* live, std::string track_json, std::string recording_json)
    : settings_(std::move(settings)), live_(live), track_json_(std::move(track_json)),
      recording_json_(std::move(recording_json)) {
  if (!(settings_.frame_rate_hz > 0.0 && settings_.frame_rate_hz <= 60.0))
    throw Error("ocs server: frame rate must be in (0, 60] Hz");
  http_ = make_http_server(settings_);
  add_routes();
}

OcsServer::~OcsServer() { stop(); }

void OcsServer::start() {
  http_->set_read_timeout(5, 0);
  http_->set_write_timeout(5, 0);
  http_->set_payload_max_length(64 * 1024);
  port_ = settings_.port == 0 ? http_->bind_to_any_port(settings_.bind_address)
                              : (http_->bind_to_port(settings_.bind_address, settings_.port) ? settings_.port : -1);
  if (port_ <= 0)
    throw Error("ocs server: cannot listen on " + settings_.bind_address + ":" + std::to_string(settings_.port) +
                " (in use, or not an address of this machine)");
  const bool tls = !settings_.access.tls_cert_file.empty();
  rules_.token = settings_.access.token.empty() ? make_token() : settings_.access.token;
  rules_.hosts = page_hosts(settings_.bind_address, port_, tls, settings_.access.extra_hosts);
  rules_.tls = tls;
  listener_ = std::thread([this] {
    yield_to_controller();
    http_->listen_after_bind();
  });
  // Until the listener runs, httplib's stop() does nothing: a stop() right after start() would
  // leave the listener running and the join in stop() waiting forever.
  for (int i = 0; i < 5000 && !http_->is_running(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  if (live_) publisher_ = std::thread([this] { publish_loop(); });
}

std::string OcsServer::page_url() const {
  std::string host = rules_.hosts.empty() ? "127.0.0.1:" + std::to_string(port_) : rules_.hosts.front();
  return (rules_.tls ? "https://" : "http://") + host + "/?token=" + rules_.token;
}

// Every refusal is logged until there were 20, then one in 100 (a page retrying in a loop, or a
// flood, does not fill the log).
void OcsServer::log_refusal(const std::string& request, const std::string& why) {
  const long n = ++refused_;
  if (n <= 20 || n % 100 == 0)
    std::fprintf(stderr, "ocs: refused %s (403, %ld refused so far): %s\n", request.c_str(), n, why.c_str());
}

void OcsServer::stop() {
  {
    const std::lock_guard<std::mutex> lock(latest_mutex_);
    if (stopping_) return;
    stopping_ = true;
  }
  latest_changed_.notify_all();
  if (publisher_.joinable()) publisher_.join();
  http_->stop();
  if (listener_.joinable()) listener_.join();
}

// Takes the newest frame at most frame_rate_hz times a second while a page streams, predicts its
// paths and turns it into JSON once for every page.
void OcsServer::publish_loop() {
  const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(1.0 / settings_.frame_rate_hz));
  yield_to_controller();
  LiveFrame frame;
  std::uint64_t seen = 0;
  auto next = std::chrono::steady_clock::now();
  for (;;) {
    next += period;
    {
      std::unique_lock<std::mutex> lock(latest_mutex_);
      if (latest_changed_.wait_until(lock, next, [this] { return stopping_; })) return;
    }
    if (live_->clients() == 0 || !live_->take_frame(&frame, &seen)) continue;
    auto json = std::make_shared<const std::string>(
        frame_json(frame, live_->predictor(), live_->priorities(), live_->paused()));
    {
      const std::lock_guard<std::mutex> lock(latest_mutex_);
      latest_json_ = std::move(json);
      ++latest_sequence_;
    }
    latest_changed_.notify_all();
  }
}

void OcsServer::add_routes() {
  httplib::Server& s = *http_;
  // The token is in the page's address: no Referer carries it away, no other site frames the page.
  s.set_default_headers({{"Referrer-Policy", "no-referrer"},
                         {"X-Frame-Options", "DENY"},
                         {"X-Content-Type-Options", "nosniff"}});
  // Before any route: the request must come through this page's own host and origin, and carry
  // the token if it would change anything (page_access.hpp).
  s.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    yield_to_controller();  // the worker thread that handles this request
    const std::string why = refusal(rules_, req.get_header_value("Host"), header(req, "Origin"),
                                    header(req, kTokenHeader), req.method != "GET" && req.method != "HEAD");
    if (why.empty()) return httplib::Server::HandlerResponse::Unhandled;
    log_refusal(req.method + " " + req.path + " from " + req.remote_addr, why);
    reply_error(res, 403, why);
    return httplib::Server::HandlerResponse::Handled;
  });
  s.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
    std::string what = "internal error";
    try {
      if (ep) std::rethrow_exception(ep);
    } catch (const std::exception& e) {
      what = e.what();
    } catch (...) {
    }
    reply_error(res, 500, what);
  });
  for (const Asset& a : assets()) {
    const std::string path = a.path == "/index.html" ? "/" : std::string(a.path);
    s.Get(path, [a](const httplib::Request&, httplib::Response& res) {
      res.set_content(a.body.data(), a.body.size(), (std::string(a.content_type) + "; charset=utf-8").c_str());
    });
  }
  s.Get("/api/info", [this](const httplib::Request&, httplib::Response& res) {
    nlohmann::json priorities = nlohmann::json::array();
    if (live_)
      for (const chassis::PriorityEntry& e : live_->priorities())
        priorities.push_back({{"sender", e.sender}, {"priority", e.priority}});
    const nlohmann::json info = {{"mode", live_ ? "live" : "replay"},
                                 {"frame_rate_hz", settings_.frame_rate_hz},
                                 {"has_track", !track_json_.empty()},
                                 {"priorities", std::move(priorities)},
                                 {"paused", live_ && live_->paused()},
                                 {"can_pause", live_ && live_->pause_allowed()},
                                 {"finished", live_ && live_->finished()},
                                 {"clients", live_ ? live_->clients() : 0},
                                 {"motion_enabled", !live_ || live_->motion_enabled_request()},
                                 {"target_speed_mps", live_ && live_->target_speed_request()
                                                          ? nlohmann::json(*live_->target_speed_request())
                                                          : nlohmann::json(nullptr)},
                                 {"refused_requests", refused_.load()}};
    res.set_content(info.dump(), "application/json");
  });
  s.Get("/api/track", [this](const httplib::Request&, httplib::Response& res) {
    if (track_json_.empty()) return reply_error(res, 404, "no track: the recording names none (use --track)");
    res.set_content(track_json_, "application/json");
  });
  s.Get("/api/recording", [this](const httplib::Request&, httplib::Response& res) {
    if (recording_json_.empty()) return reply_error(res, 404, "no recording: this server shows a live simulation");
    res.set_content(recording_json_, "application/json");
  });
  s.Get("/api/frame", [this](const httplib::Request&, httplib::Response& res) {
    if (!live_) return reply_error(res, 404, "no live simulation: this server replays a recording");
    std::shared_ptr<const std::string> json;
    {
      const std::lock_guard<std::mutex> lock(latest_mutex_);
      json = latest_json_;
    }
    if (!json) return reply_error(res, 503, "no frame yet: frames are made while a page streams /api/stream");
    res.set_content(*json, "application/json");
  });
  s.Get("/api/stream", [this](const httplib::Request&, httplib::Response& res) {
    if (!live_) return reply_error(res, 404, "no live simulation: this server replays a recording");
    if (streams_.fetch_add(1) >= settings_.max_streams) {
      streams_.fetch_sub(1);
      return reply_error(res, 503, "too many pages streaming (at most " + std::to_string(settings_.max_streams) + ")");
    }
    live_->add_client();
    res.set_header("Cache-Control", "no-cache");
    auto seen = std::make_shared<std::uint64_t>(0);
    {  // a new page starts with the next frame, not one made for an earlier page
      const std::lock_guard<std::mutex> lock(latest_mutex_);
      *seen = latest_sequence_;
    }
    res.set_chunked_content_provider(
        "text/event-stream",
        [this, seen](std::size_t, httplib::DataSink& sink) {
          std::shared_ptr<const std::string> json;
          {
            std::unique_lock<std::mutex> lock(latest_mutex_);
            latest_changed_.wait_for(lock, std::chrono::seconds(1),
                                     [&] { return stopping_ || latest_sequence_ != *seen; });
            if (stopping_) return false;
            if (latest_sequence_ != *seen) json = latest_json_, *seen = latest_sequence_;
          }
          // A comment line when there is nothing new: a page that has gone is noticed here.
          const std::string event = json ? "data: " + *json + "\n\n" : std::string(": idle\n\n");
          return sink.write(event.data(), event.size());
        },
        [this](bool) {
          live_->remove_client();
          streams_.fetch_sub(1);
        });
  });
  s.Post("/api/control", [this](const httplib::Request& req, httplib::Response& res) {
    if (!live_) return reply_error(res, 404, "no live simulation: a replay has no controls");
    if (req.params.empty()) return reply_error(res, 400, "no parameter: expected pause, target_speed, runstop or stop");
    // Check every parameter first, then apply: a bad request changes nothing.
    std::optional<bool> pause, runstop, stop;
    std::optional<double> target;
    for (const auto& [name, text] : req.params) {
      std::string why;
      bool flag = false;
      if (name == "pause" || name == "runstop" || name == "stop") {
        if (!parse_flag(name, text, &flag, &why)) return reply_error(res, 400, why);
        (name == "pause" ? pause : name == "runstop" ? runstop : stop) = flag;
      } else if (name == "target_speed") {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0' || !std::isfinite(v) || v < 0.0 || v > kMaxTargetSpeedMps)
          return reply_error(res, 400, "target_speed: expects a number of m/s in [0, " +
                                           std::to_string(static_cast<int>(kMaxTargetSpeedMps)) + "], got '" + text + "'");
        target = v;
      } else {
        return reply_error(res, 400, "unknown parameter '" + name + "' (expected pause, target_speed, runstop or stop)");
      }
    }
    if (pause && !live_->pause_allowed())
      return reply_error(res, 400, "pause: a vehicle cannot be paused (use runstop)");
    if (pause) live_->request_pause(*pause);
    if (target) live_->request_target_speed(*target);
    if (runstop) live_->request_motion_enabled(!*runstop);
    if (stop && *stop) live_->request_stop();
    res.set_content(nlohmann::json{{"ok", true}, {"paused", live_->paused()},
                                   {"motion_enabled", live_->motion_enabled_request()}}.dump(),
                    "application/json");
  });
}

}  // namespace mppi::ocs
