#include "diagnose/synth.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>

#include "base/error.hpp"
#include "dynamics/model_registry.hpp"
#include "dynamics/with_effects.hpp"
#include "sim/closed_loop.hpp"
#include "sim/data_dir.hpp"
#include "sim/plant.hpp"
#include "sim/recording.hpp"
#include "diagnose/candidate_effects.hpp"
#include "diagnose/model_family.hpp"

namespace mppi::diagnose {

std::vector<std::string> parse_effect_assignments(const std::string& text, EffectParams* e) {
  std::vector<std::string> ids;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string::npos) throw Error("effect assignment '" + item + "': expected key=value");
    const std::string key = item.substr(0, eq);
    double v = 0;
    try {
      std::size_t used = 0;
      v = std::stod(item.substr(eq + 1), &used);
      if (used != item.size() - eq - 1) throw std::invalid_argument(item);
    } catch (const std::logic_error&) {
      throw Error("effect assignment '" + item + "': value is not a number");
    }
    bool found = false;
    for (const auto& spec : effect_library())
      for (const auto& p : spec.params)
        if (key == p.name) {
          e->*(p.member) = v;
          if (std::find(ids.begin(), ids.end(), spec.id) == ids.end()) ids.push_back(spec.id);
          found = true;
        }
    if (!found) throw Error("effect assignment '" + item + "': unknown parameter '" + key + "'");
  }
  return ids;
}

const std::vector<SweepCase>& sweep_cases() {
  static const std::vector<SweepCase> cases = {
      {"aero_drag", "aero_drag_kgpm=0.15", "aero_drag_kgpm=0.5"},
      {"rolling_resistance", "rolling_force_N=6", "rolling_force_N=20"},
      {"steer_delay", "steer_delay_s=0.04", "steer_delay_s=0.1"},
      {"throttle_delay", "throttle_delay_s=0.06", "throttle_delay_s=0.15"},
      {"steer_lag", "steer_lag_s=0.04", "steer_lag_s=0.12"},
      {"throttle_lag", "throttle_lag_s=0.1", "throttle_lag_s=0.3"},
      {"steer_offset", "steer_offset=0.03", "steer_offset=0.1"},
      {"steer_gain", "steer_gain=0.85", "steer_gain=0.65"},
      {"throttle_offset", "throttle_offset=-0.05", "throttle_offset=-0.15"},
      {"tire_saturation", "tyre_peak_scale=0.8", "tyre_peak_scale=0.6"},
      {"friction_change", "grip_change_time_s=15,grip_scale=0.8", "grip_change_time_s=15,grip_scale=0.6"},
      {"load_transfer", "cg_height_delta_m=0.05", "cg_height_delta_m=0.1"},
      {"motor_voltage_sag", "voltage_sag=0.15", "voltage_sag=0.35"},
      {"road_grade", "grade_x=0.03", "grade_x=0.08"},
  };
  return cases;
}

namespace {

// The truth's pure command delays are the plant's actuators' (exact), not the model's.
template <VehicleDynamics M>
sim::Recording drive_open_loop(M truth_model, const EffectParams& truth, std::uint64_t seed, double duration_s,
                               const SensorNoise& noise) {
  sim::ActuatorLimits fast;
  fast.steer_rate_per_s = fast.throttle_rate_per_s = 1e4f;
  fast.steer_delay_s = static_cast<float>(truth.steer_delay_s);
  fast.throttle_delay_s = static_cast<float>(truth.throttle_delay_s);
  sim::Plant<M> plant(std::move(truth_model), fast, 0.002f);
  VehicleState s0;
  s0.vx_mps = 4.f;
  plant.reset(s0);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::normal_distribution<double> n01(0.0, noise.scale);
  sim::Recording rec;
  rec.metadata = {{"source", "mppi-fit synth (open loop)"}, {"seed", std::to_string(seed)}};
  rec.columns = {sim::kRecordingRequiredColumns.begin(), sim::kRecordingRequiredColumns.end()};
  rec.columns.push_back("roll");
  // Its own stream and distribution (normal_distribution caches draws): the other draws stay as
  // they were without the roll column.
  std::mt19937_64 roll_rng(seed * 6007 + 29);
  std::normal_distribution<double> roll_n01(0.0, noise.scale);
  rec.data.assign(rec.columns.size(), {});
  Control cmd;
  double hold = 0;
  const int steps = static_cast<int>(std::lround(duration_s / 0.02));
  for (int k = 1; k <= steps; ++k) {
    if ((hold -= 0.02) <= 0) {  // new random command
      hold = 0.1 + 0.4 * uni(rng);
      const double v = plant.vehicle_state().vx_mps;
      cmd.steer = static_cast<float>((uni(rng) < 0.2 ? 0.9 : 0.45) * (2 * uni(rng) - 1));
      const double base = v < 3 ? 0.6 : v > 9 ? -0.2 : 0.35;
      cmd.throttle = static_cast<float>(std::clamp(base + 0.5 * (2 * uni(rng) - 1), -0.8, 0.9));
    }
    plant.advance(cmd, 0.02f);
    const VehicleState s = plant.vehicle_state();
    const double row[] = {0.02 * k,
                          s.x_m + noise.position_m * n01(rng),
                          s.y_m + noise.position_m * n01(rng),
                          s.yaw_rad + noise.yaw_rad * n01(rng),
                          s.vx_mps + noise.vx_mps * n01(rng),
                          s.vy_mps + noise.vy_mps * n01(rng),
                          s.yaw_rate_radps + noise.yaw_rate_radps * n01(rng),
                          cmd.steer,
                          cmd.throttle,
                          s.roll_rad + noise.roll_rad * roll_n01(roll_rng)};
    for (std::size_t c = 0; c < rec.columns.size(); ++c) rec.data[c].push_back(row[c]);
  }
  return rec;
}

}  // namespace

sim::Recording synthesize_open_loop(const EffectParams& truth, std::uint64_t seed, double duration_s,
                                    const SensorNoise& noise, const std::string& nominal_model) {
  std::optional<sim::Recording> rec;
  const CorrectedModelFile defaults;  // the library's default parameters of every nominal model
  visit_by_name(CorrectedNominalModels{}, nominal_model, [&]<class D>() {
    using M = WithEffects<typename D::Model>;
    EffectParams undelayed = truth;
    undelayed.steer_delay_s = undelayed.throttle_delay_s = 0.0;
    rec.emplace(drive_open_loop(M(corrected_nominal<D>(defaults, sim::network_file_or_default("")), undelayed), truth,
                                seed, duration_s, noise));
  });
  if (!rec) throw Error("synthesize_open_loop: unknown nominal model '" + nominal_model + "' (valid: " +
                        kCorrectedNominalModels + ")");
  return std::move(*rec);
}

std::vector<std::pair<double, double>> speed_schedule(std::uint64_t seed, double duration_s, double speed_min_mps,
                                                      double speed_max_mps, double hold_min_s, double hold_max_s) {
  if (!(speed_min_mps > 0 && speed_max_mps >= speed_min_mps && hold_min_s > 0 && hold_max_s >= hold_min_s &&
        std::isfinite(speed_max_mps) && std::isfinite(hold_max_s) && std::isfinite(duration_s)))
    throw Error("speed schedule: need 0 < speed_min_mps <= speed_max_mps and 0 < hold_min_s <= hold_max_s");
  std::mt19937_64 rng(seed * 104729 + 3);
  std::uniform_real_distribution<double> speed(speed_min_mps, speed_max_mps), hold(hold_min_s, hold_max_s);
  std::vector<std::pair<double, double>> out;
  for (double t = 0; t < duration_s; t += hold(rng)) out.emplace_back(t, speed(rng));
  return out;
}

namespace {

// The closed-loop run that drives the hidden truth (the plant) with the nominal model's controller;
// *schedule_text: its target speeds, as the recording's metadata gives them.
sim::ClosedLoopConfig closed_loop_config(const SynthOptions& o, const std::string& truth_path,
                                         std::string* schedule_text) {
  sim::ClosedLoopConfig c;
  c.track = o.track;
  c.model = o.nominal_model;
  c.plant = "corrected";
  c.plant_params_yaml = truth_path;
  c.target_speed_mps = o.target_speed_mps;
  *schedule_text = "constant " + std::to_string(o.target_speed_mps);
  if (o.vary_speed && o.speed_max_mps > o.speed_min_mps) {
    c.target_speed_schedule =
        speed_schedule(o.seed, o.duration_s, o.speed_min_mps, o.speed_max_mps, o.hold_min_s, o.hold_max_s);
    c.target_speed_mps = c.target_speed_schedule.front().second;
    schedule_text->clear();
    char b[48];
    for (const auto& [from_s, v] : c.target_speed_schedule) {
      std::snprintf(b, sizeof b, "%s%.2f:%.2f", schedule_text->empty() ? "" : " ", from_s, v);
      *schedule_text += b;
    }
  }
  c.laps = 1000;
  c.max_time_s = o.duration_s;
  c.controller.num_samples = o.samples;
  c.controller.horizon = o.horizon;
  c.controller.seed = o.seed;
  c.controller.num_threads = o.threads;
  // Actuators without slew limits: the nominal model has none, so only the hidden effects differ.
  c.actuators.steer_rate_per_s = 1e4f;
  c.actuators.throttle_rate_per_s = 1e4f;
  c.out_dir = o.work_dir + "/run";
  c.progress = false;
  return c;
}

// The run's log with sensor noise on the measured states, written to csv_path.
void write_noisy_recording(const SynthOptions& o, const sim::Recording& raw, const std::string& csv_path,
                           const std::string& truth_path, const std::string& schedule_text, int crashes) {
  std::mt19937_64 rng(o.seed * 7919 + 17);
  std::normal_distribution<double> n01(0.0, o.noise.scale);
  std::string ids;
  for (const auto& id : o.truth_ids) ids += (ids.empty() ? "" : " ") + id;
  // Roll (an optional column) gets noise from its own stream, so the other columns' noise is
  // the same as without it.
  std::mt19937_64 roll_rng(o.seed * 6007 + 29);
  std::normal_distribution<double> roll_n01(0.0, o.noise.scale);
  sim::RecordingWriter w(csv_path, {"applied_steer", "applied_throttle", "roll"},
                         {{"source", "mppi-fit synth"}, {"track", o.track}, {"seed", std::to_string(o.seed)},
                          {"truth_effects", ids.empty() ? "none" : ids},
                          {"truth_model", truth_path},
                          {"target_speed_schedule_s_mps", schedule_text},
                          {"crashes", std::to_string(crashes)}});
  const auto& t = raw.column("t");
  const auto& x = raw.column("x");
  const auto& y = raw.column("y");
  const auto& yaw = raw.column("yaw");
  const auto& vx = raw.column("vx");
  const auto& vy = raw.column("vy");
  const auto& r = raw.column("yaw_rate");
  const auto& st = raw.column("steer");
  const auto& th = raw.column("throttle");
  const auto& ast = raw.column("applied_steer");
  const auto& ath = raw.column("applied_throttle");
  const auto& roll = raw.column("roll");
  for (std::size_t k = 0; k < raw.rows(); ++k) {
    const double row[] = {t[k],
                          x[k] + o.noise.position_m * n01(rng),
                          y[k] + o.noise.position_m * n01(rng),
                          yaw[k] + o.noise.yaw_rad * n01(rng),
                          vx[k] + o.noise.vx_mps * n01(rng),
                          vy[k] + o.noise.vy_mps * n01(rng),
                          r[k] + o.noise.yaw_rate_radps * n01(rng),
                          st[k], th[k], ast[k], ath[k], roll[k] + o.noise.roll_rad * roll_n01(roll_rng)};
    w.write_row(row);
  }
  w.close();
}

}  // namespace

int synthesize(const SynthOptions& o, const std::string& csv_path) {
  if (o.work_dir.empty()) throw Error("synthesize: work_dir is required");
  std::filesystem::create_directories(o.work_dir);
  model_family_of([&] {  // throws for a model without an effects version
    CorrectedModelFile f;
    f.nominal_model = o.nominal_model;
    return f;
  }());
  CorrectedModelFile truth;
  truth.nominal_model = o.nominal_model;
  truth.effects = o.truth;
  truth.selected = o.truth_ids;
  const std::string truth_path = o.work_dir + "/truth_model.yaml";
  std::ofstream(truth_path) << corrected_model_to_yaml(truth, "hidden truth of a synthetic recording");

  std::string schedule_text;
  const sim::ClosedLoopConfig c = closed_loop_config(o, truth_path, &schedule_text);
  const sim::RunSummary summary = sim::run_closed_loop(c);

  const sim::Recording raw = sim::RecordingReader::read(c.out_dir + "/log.csv");
  write_noisy_recording(o, raw, csv_path, truth_path, schedule_text, summary.crashes);
  return summary.crashes;
}

}  // namespace mppi::diagnose
