#include "sim/summary.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

#include <nlohmann/json.hpp>

#include "base/error.hpp"

namespace mppi::sim {

namespace {
nlohmann::ordered_json number(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}
}  // namespace

std::string to_json(const RunSummary& s) {
  nlohmann::ordered_json j;
  j["track"] = s.track;
  j["model"] = s.model;
  j["plant"] = s.plant;
  j["seed"] = s.seed;
  j["samples"] = s.samples;
  j["horizon"] = s.horizon;
  j["target_speed_mps"] = number(s.target_speed_mps);
  j["sim_time_s"] = number(s.sim_time_s);
  j["finished"] = s.finished;
  j["laps_completed"] = s.laps_completed;
  j["lap_times_s"] = nlohmann::ordered_json::array();
  for (double t : s.lap_times_s) j["lap_times_s"].push_back(number(t));
  j["limit_lap_s"] = number(s.limit_lap_s);
  j["standing_limit_lap_s"] = number(s.standing_limit_lap_s);
  j["limit_lap_method"] = s.limit_lap_method.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(s.limit_lap_method);
  j["lap_time_ratio"] = nlohmann::ordered_json::array();
  for (double r : s.lap_time_ratio) j["lap_time_ratio"].push_back(number(r));
  j["crashes"] = s.crashes;
  j["crash_reasons"] = s.crash_reasons;
  j["stalls"] = s.stalls;
  j["stall_times_s"] = nlohmann::ordered_json::array();
  for (double t : s.stall_times_s) j["stall_times_s"].push_back(number(t));
  j["mean_speed_mps"] = number(s.mean_speed_mps);
  j["max_speed_mps"] = number(s.max_speed_mps);
  j["peak_slip_angle_rad"] = number(s.peak_slip_angle_rad);
  j["p95_slip_angle_rad"] = number(s.p95_slip_angle_rad);
  j["peak_lateral_accel_mps2"] = number(s.peak_lateral_accel_mps2);
  j["mean_abs_steer_step"] = number(s.mean_abs_steer_step);
  j["mean_abs_throttle_step"] = number(s.mean_abs_throttle_step);
  j["optimizer_ms_p50"] = number(s.optimizer_ms_p50);
  j["optimizer_ms_p99"] = number(s.optimizer_ms_p99);
  j["effective_sample_size_mean"] = number(s.effective_sample_size_mean);
  j["sampler"] = s.sampler;
  j["ess_target_share"] = number(s.ess_target_share);
  j["ess_in_band_share"] = number(s.ess_in_band_share);
  j["lambda_p50"] = number(s.lambda_p50);
  j["actuator_model"] = s.actuator_model;
  j["variant"] = s.variant;
  j["nominal_resets"] = s.nominal_resets;
  j["lateral_force_adaptation"] = s.lateral_force_adaptation;
  j["lateral_force_scale_final"] = number(s.lateral_force_scale_final);
  j["lateral_force_scale_p50"] = number(s.lateral_force_scale_p50);
  j["backend"] = s.backend;
  j["failed_steps"] = s.failed_steps;
  j["backend_switches"] = nlohmann::ordered_json::array();
  for (const BackendSwitchRecord& b : s.backend_switches)
    j["backend_switches"].push_back({{"control_step", b.control_step}, {"time_s", number(b.time_s)},
                                     {"from", b.from}, {"to", b.to}, {"reason", b.reason}});
  return j.dump(2) + "\n";
}

void write_summary(const std::string& path, const RunSummary& summary) {
  std::ofstream out(path, std::ios::out | std::ios::trunc);
  if (!out) throw Error(path + ": cannot open for writing");
  out << to_json(summary);
  out.close();
  if (!out) throw Error(path + ": write failed");
}

double percentile(std::vector<double> values, double p) {
  if (!(p >= 0.0 && p <= 100.0)) throw Error("percentile: p must be in [0, 100]");
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const double rank = p / 100.0 * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(rank));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  const double frac = rank - static_cast<double>(lo);
  return values[lo] + frac * (values[hi] - values[lo]);
}

}  // namespace mppi::sim
