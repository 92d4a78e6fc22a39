#pragma once
// The operator page for the programs: a closed-loop simulation shown live, or a recording
// replayed with a time slider. Both serve until the run ends (live) or until SIGINT/SIGTERM
// (replay); Ctrl-C ends a live run cleanly (its logs are written).
#include <string>

#include "ocs/page_access.hpp"
#include "sim/closed_loop.hpp"
#include "sim/summary.hpp"

namespace mppi::ocs {

struct ServeOptions {
  std::string bind_address = "127.0.0.1";
  int port = 8080;
  double frame_rate_hz = 20.0;
  bool realtime = true;  // live: hold the simulation to wall-clock time
  bool quiet = false;
  PageAccess access;      // TLS, remote use, the token (docs/SECURITY.md)
};

// Optimizer time percentiles of a live run, split by whether a page was connected.
struct PageTiming {
  long steps_without = 0, steps_with = 0;
  double p50_without_ms = 0, p99_without_ms = 0, p50_with_ms = 0, p99_with_ms = 0;
};

// Runs sim::run_closed_loop with the page served; *timing (if given) gets the split optimizer
// times, which are also printed and, with an out_dir, written to out_dir/ocs_timing.json.
// Throws mppi::Error as run_closed_loop does, or if the port cannot be bound.
sim::RunSummary run_closed_loop_with_page(sim::ClosedLoopConfig config, const ServeOptions& options,
                                          PageTiming* timing = nullptr);

// Serves the recording at `csv_path` for replay until SIGINT/SIGTERM. `track` names the built-in
// track to draw ("" = the recording's "track" metadata, if any). Returns the exit status.
int serve_recording(const std::string& csv_path, std::string track, const ServeOptions& options);

}  // namespace mppi::ocs
