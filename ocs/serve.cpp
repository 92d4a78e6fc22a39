#include "ocs/serve.hpp"

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "base/error.hpp"
#include "ocs/live_observer.hpp"
#include "ocs/recording_json.hpp"
#include "ocs/server.hpp"
#include "ocs/track_json.hpp"
#include "sim/recording.hpp"

namespace mppi::ocs {
namespace {

std::atomic<bool> g_interrupted{false};
void on_signal(int) { g_interrupted = true; }

ServerSettings server_settings(const ServeOptions& o) {
  ServerSettings s;
  s.bind_address = o.bind_address;
  s.port = o.port;
  s.frame_rate_hz = o.frame_rate_hz;
  s.access = o.access;
  return s;
}

}  // namespace

sim::RunSummary run_closed_loop_with_page(sim::ClosedLoopConfig config, const ServeOptions& options,
                                          PageTiming* timing_out) {
  LiveSettings live_settings;
  live_settings.frame_rate_hz = options.frame_rate_hz;
  live_settings.realtime = options.realtime;
  LiveObserver live(live_settings);
  OcsServer server(server_settings(options), &live, track_json(config.track, config.clockwise), "");
  config.observer = &live;
  server.start();
  // Always printed (also when quiet): the page can change nothing without the token in this URL.
  std::fprintf(stderr, "ocs: operator page on %s (%.0f frames/s%s)\n", server.page_url().c_str(),
               options.frame_rate_hz, options.realtime ? ", real time" : "");
  g_interrupted = false;
  auto previous_int = std::signal(SIGINT, on_signal);
  auto previous_term = std::signal(SIGTERM, on_signal);
  std::atomic<bool> done{false};
  std::thread interrupt_watch([&] {
    while (!done) {
      if (g_interrupted) live.request_stop();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  sim::RunSummary summary;
  try {
    summary = sim::run_closed_loop(config);
  } catch (...) {
    done = true;
    interrupt_watch.join();
    std::signal(SIGINT, previous_int);
    std::signal(SIGTERM, previous_term);
    throw;
  }
  done = true;
  interrupt_watch.join();
  std::signal(SIGINT, previous_int);
  std::signal(SIGTERM, previous_term);
  server.stop();

  const TimingSplit split = live.timing();
  PageTiming t;
  t.steps_without = static_cast<long>(split.without_page_ms.size());
  t.steps_with = static_cast<long>(split.with_page_ms.size());
  t.p50_without_ms = sim::percentile(split.without_page_ms, 50);
  t.p99_without_ms = sim::percentile(split.without_page_ms, 99);
  t.p50_with_ms = sim::percentile(split.with_page_ms, 50);
  t.p99_with_ms = sim::percentile(split.with_page_ms, 99);
  if (!options.quiet)
    std::fprintf(stderr,
                 "ocs: optimizer without a page p50 %.3f p99 %.3f ms (%ld steps), with a page p50 %.3f p99 %.3f ms "
                 "(%ld steps); with/without p50 %.3f p99 %.3f\n",
                 t.p50_without_ms, t.p99_without_ms, t.steps_without, t.p50_with_ms, t.p99_with_ms, t.steps_with,
                 t.p50_with_ms / t.p50_without_ms, t.p99_with_ms / t.p99_without_ms);
  if (!config.out_dir.empty()) {
    auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
    const nlohmann::json j = {{"steps_without_page", t.steps_without}, {"steps_with_page", t.steps_with},
                              {"optimizer_ms_p50_without_page", num(t.p50_without_ms)},
                              {"optimizer_ms_p99_without_page", num(t.p99_without_ms)},
                              {"optimizer_ms_p50_with_page", num(t.p50_with_ms)},
                              {"optimizer_ms_p99_with_page", num(t.p99_with_ms)},
                              {"ratio_p50", num(t.p50_with_ms / t.p50_without_ms)},
                              {"ratio_p99", num(t.p99_with_ms / t.p99_without_ms)}};
    std::ofstream(config.out_dir + "/ocs_timing.json") << j.dump(2) << "\n";
  }
  if (timing_out) *timing_out = t;
  return summary;
}

int serve_recording(const std::string& csv_path, std::string track, const ServeOptions& options) {
  const sim::Recording recording = sim::RecordingReader::read(csv_path);
  if (track.empty()) {
    const auto it = recording.metadata.find("track");
    if (it != recording.metadata.end()) track = it->second;
  }
  OcsServer server(server_settings(options), nullptr, track.empty() ? std::string() : track_json(track, false),
                   recording_json(recording, csv_path));
  server.start();
  std::fprintf(stderr, "ocs: replay of %s (%zu rows%s%s) on %s - Ctrl-C to stop\n", csv_path.c_str(),
               recording.rows(), track.empty() ? "" : ", track ", track.c_str(), server.page_url().c_str());
  g_interrupted = false;
  auto previous_int = std::signal(SIGINT, on_signal);
  auto previous_term = std::signal(SIGTERM, on_signal);
  while (!g_interrupted) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  std::signal(SIGINT, previous_int);
  std::signal(SIGTERM, previous_term);
  server.stop();
  return 0;
}

}  // namespace mppi::ocs
