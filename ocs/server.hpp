#pragma once
// The operator page's web server (cpp-httplib): the page and its scripts, the track, and
// either a live simulation (frames as server-sent events at a bounded rate, controls) or a
// recording to replay. It runs on its own threads; the simulation only ever meets it through
// LiveObserver's non-blocking mailbox. Endpoints are listed in docs/OCS.md; who may use them
// (page_access.hpp) in docs/SECURITY.md.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "ocs/live_observer.hpp"
#include "ocs/page_access.hpp"

namespace httplib {
class Server;
}

namespace mppi::ocs {

struct ServerSettings {
  std::string bind_address = "127.0.0.1";  // loopback only by default
  int port = 8080;                         // 0 = any free port
  double frame_rate_hz = 20.0;             // frames sent to a page per second, at most
  int max_streams = 4;                     // pages streaming at once; more get 503
  PageAccess access;                       // TLS, remote use, the token
};

class OcsServer {
 public:
  // live: the simulation to show (null in replay mode); track_json: ocs::track_json() or empty;
  // recording_json: ocs::recording_json() for replay mode, else empty.
  OcsServer(ServerSettings settings, LiveObserver* live, std::string track_json, std::string recording_json);
  ~OcsServer();
  OcsServer(const OcsServer&) = delete;
  OcsServer& operator=(const OcsServer&) = delete;

  // Binds and starts serving; throws mppi::Error if the address or port cannot be bound, or if
  // it is off loopback with neither TLS nor access.insecure_remote.
  void start();
  void stop();
  int port() const { return port_; }
  // The page's address with its token (after start()): the one URL whose page can change state.
  std::string page_url() const;
  long refused_requests() const { return refused_.load(); }

 private:
  void add_routes();
  void publish_loop();
  void log_refusal(const std::string& request, const std::string& why);

  ServerSettings settings_;
  LiveObserver* live_;
  std::string track_json_, recording_json_;
  std::unique_ptr<httplib::Server> http_;
  std::thread listener_, publisher_;
  int port_ = 0;
  AccessRules rules_;  // set in start(), before the first request
  std::atomic<long> refused_{0};
  std::atomic<int> streams_{0};

  std::mutex latest_mutex_;
  std::condition_variable latest_changed_;
  std::shared_ptr<const std::string> latest_json_;
  std::uint64_t latest_sequence_ = 0;
  bool stopping_ = false;
};

}  // namespace mppi::ocs
