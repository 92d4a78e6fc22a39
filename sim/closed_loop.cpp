#include "sim/closed_loop.hpp"
#include "sim/surface_plant.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <limits>
#include <numbers>
#include <memory>
#include <optional>
#include <type_traits>
#include <vector>

#include "chassis/sim_adapter.hpp"
#include "costs/autorally_cost.hpp"
#include "costs/cost_config.hpp"
#include "mppi/cost_map.hpp"
#include "dynamics/corrected_model.hpp"
#include "sim/actuator_model.hpp"
#include "dynamics/with_effects.hpp"
#include "dynamics/model_registry.hpp"
#include "dynamics/four_wheel_observe.hpp"
#include "mppi/controller.hpp"
#include "base/error.hpp"
#include "factory/make_controller.hpp"
#include "sim/command_steps.hpp"
#include "sim/corrected_limit_vehicle.hpp"
#include "sim/crash_detector.hpp"
#include "sim/data_dir.hpp"
#include "sim/geometry.hpp"
#include "sim/lap_counter.hpp"
#include "sim/centreline_pose.hpp"
#include "sim/limit_lap.hpp"
#include "sim/limit_lap_methods.hpp"
#include "sim/path_predictor.hpp"
#include "sim/recording.hpp"
#include "sim/track_plot.hpp"

namespace mppi::sim {
namespace {

constexpr const char* kDefaultCostYaml = "config/autorally_cost.yaml";
// Not a registered model: a model written by mppi-fit diagnose (a nominal + effects file).
constexpr const char* kCorrectedModel = "corrected";

// The data file of a registered model: the given file; for a model whose data are weights
// (npz), the --network file; else the model's default data file; "" = built-in defaults.
template <class D>
std::string model_file(const std::string& params_file, const std::string& weights_file) {
  if (!params_file.empty()) return params_file;
  const std::string default_file = D::kDefaultFile;
  const bool weights = default_file.size() > 4 && default_file.substr(default_file.size() - 4) == ".npz";
  if (weights && !weights_file.empty()) return weights_file;
  return default_file.empty() ? std::string() : data_file(default_file);
}

// The model of a corrected-model file (nominal + effects, WithEffects<Model>), handed to f as
// its concrete type, with how it reads a plant's state: a plant of the same corrected model is
// copied whole; any other as the nominal model reads it, with time 0 and the actuator chains at
// rest.
// With pure_delays_outside, the model is built without the file's pure command delays (a plant
// realises them exactly, by its actuators; a controller's model keeps its chain of delay stages).
template <class F>
auto visit_corrected(const std::string& path, const char* flag, F&& f, bool pure_delays_outside = false) {
  if (path.empty()) throw Error(std::string("--") + flag + " corrected needs --" + flag + "-params FILE");
  CorrectedModelFile file = load_corrected_model(path);
  if (pure_delays_outside) file.effects.steer_delay_s = file.effects.throttle_delay_s = 0.0;
  using Result = decltype(f(std::declval<const CorrectedSingleTrack&>(),
                            std::function<void(const float*, int, float*)>()));
  std::optional<Result> result;
  visit_by_name(CorrectedNominalModels{}, file.nominal_model, [&]<class D>() {
    using M = WithEffects<typename D::Model>;
    const M model(corrected_nominal<D>(file, network_file_or_default(file.network_npz)), file.effects);
    std::function<void(const float*, int, float*)> observe = [base = model.nominal()](const float* px,
                                                                                      int plant_states, float* mx) {
      if (plant_states == M::kNx) {
        std::copy(px, px + M::kNx, mx);
        return;
      }
      std::fill(mx, mx + M::kNx, 0.f);
      D::from_plant(base, px, plant_states, mx);
    };
    result.emplace(f(model, std::move(observe)));
  });
  return std::move(*result);
}

// The controller and how it reads the plant: full plant state -> controller model state.
struct ControllerSetup {
  std::unique_ptr<Controller> controller;
  std::string backend;  // the backend it starts on
  int model_states = 0;
  std::function<void(const float* plant_x, int plant_states, float* model_x)> observe;
  PathPredictor predict;  // the controller model's paths, for an observer
};

// The controller on the backend the config asks for (factory/make_controller.hpp).
struct BuiltController {
  std::unique_ptr<Controller> controller;
  std::string backend;
};

template <class D>
BuiltController build_controller(const ClosedLoopConfig& config, const D& model,
                                             const AutoRallyCost& cost) {
  BackendReport report;
  auto controller = std::make_unique<Controller>(
      mppi::make_controller(model, cost, config.controller, config.backend, &report));
  if (config.inject_device_loss_at_step >= 0)
    controller->inject_device_loss(static_cast<std::uint64_t>(config.inject_device_loss_at_step));
  if (config.progress)
    std::fprintf(stderr, "backend: %s%s%s (%s)\n", report.backend.c_str(),
                 report.device.empty() ? "" : " on ", report.device.c_str(), report.reason.c_str());
  if (config.backend_report) *config.backend_report = report;
  return {std::move(controller), report.backend};
}

// The controller model's network precision (ClosedLoopConfig::nn_precision).
template <class M>
void apply_nn_precision(const ClosedLoopConfig& config, M& model) {
  if (config.nn_precision != "fp32" && config.nn_precision != "bf16")
    throw Error("nn-precision must be fp32 or bf16, got '" + config.nn_precision + "'");
  if constexpr (requires { model.set_precision(NetPrecision::kBf16); }) {
    if (config.nn_precision == "bf16" && !model.set_precision(NetPrecision::kBf16) && config.progress)
      std::fprintf(stderr, "nn-precision: this CPU has no AVX512-BF16, the network runs in fp32\n");
  }
}

template <class M, class Observe>
ControllerSetup controller_setup(const ClosedLoopConfig& config, const M& model, const AutoRallyCost& cost,
                                 Observe observe) {
  ControllerSetup setup;
  BuiltController built = build_controller(config, model, cost);
  setup.controller = std::move(built.controller);
  setup.backend = std::move(built.backend);
  setup.model_states = M::kNx;
  setup.observe = std::move(observe);
  if (config.observer) setup.predict = make_path_predictor(model, config.controller.dt_s);
  return setup;
}

ControllerSetup make_controller(const ClosedLoopConfig& config, const AutoRallyCost& cost) {
  if (config.model == kCorrectedModel)
    return visit_corrected(config.model_params_yaml, "model", [&](const auto& model, auto observe) {
      return controller_setup(config, model, cost, std::move(observe));
    });
  return with_model(config.model, [&]<class D>() {
    typename D::Model model = D::load(model_file<D>(config.model_params_yaml, config.network_npz));
    apply_nn_precision(config, model);
    return controller_setup(config, model, cost, [model](const float* px, int plant_states, float* mx) {
      D::from_plant(model, px, plant_states, mx);
    });
  }, "controller model");
}

// The vehicle whose limit lap a plant is measured against (plant_vehicle_params).
template <class P>
std::optional<SingleTrackParams> limit_lap_vehicle(const P& plant) {
  if constexpr (requires { plant.params().rigid_limit(); }) return plant.params().rigid_limit().base;
  else if constexpr (HasSingleTrackCore<P>) return SingleTrackParams(single_track_core(plant.params()));
  else return std::nullopt;
}

// The limit laps a run's laps are measured against: the first lap starts from rest at the start
// line (the car is spawned there standing), the others are flying.
struct LimitLapTimes {
  double flying_s = std::numeric_limits<double>::quiet_NaN();
  double standing_s = std::numeric_limits<double>::quiet_NaN();
  // The reference of lap `lap` (1-based).
  double for_lap(int lap) const { return lap == 1 ? standing_s : flying_s; }
  bool any() const { return std::isfinite(flying_s) || std::isfinite(standing_s); }
};

// The limit lap's time of a vehicle on the track from the given start; NaN where it cannot be
// computed (said on stderr with progress on). Computed once per track, direction, vehicle and
// start in a process (a test suite runs many loops).
double vehicle_limit_lap_s(const ClosedLoopConfig& config, const SingleTrackParams& vehicle, const Track& track,
                           LapStart start) {
  static std::mutex mutex;
  static std::map<std::string, LimitLap> cache;
  const bool standing = start == LapStart::kStanding;
  const char* what = standing ? "standing-start limit lap" : "limit lap";
  const std::string key = config.limit_lap_method + (standing ? " standing " : " flying ") + track.name() +
                          (track.direction() == Direction::kClockwise ? " cw\n" : " ccw\n") + to_yaml(vehicle);
  try {
    std::unique_lock lock(mutex);
    auto it = cache.find(key);
    if (it == cache.end())
      it = cache.emplace(key, limit_lap_by_method(config.limit_lap_method, track, vehicle, start)).first;
    const LimitLap& lap = it->second;
    if (config.progress)
      std::fprintf(stderr, "%s of the plant's vehicle (%s): %.2f s (mean %.2f m/s, max %.2f m/s; docs/LIMIT_LAP.md)\n",
                   what, config.limit_lap_method.c_str(), lap.lap_time_s, lap.mean_speed_mps, lap.max_speed_mps);
    return lap.lap_time_s;
  } catch (const Error& e) {
    if (config.progress) std::fprintf(stderr, "no %s: %s\n", what, e.what());
    return std::numeric_limits<double>::quiet_NaN();
  }
}

// The same for the plant's vehicle (limit_lap_vehicle; a corrected-model plant's from its file,
// corrected_limit_lap_vehicle), flying and standing; NaN where the plant has none.
template <class P>
LimitLapTimes plant_limit_laps(const ClosedLoopConfig& config, const P& plant, const Track& track) {
  const std::optional<SingleTrackParams> vehicle =
      config.plant == kCorrectedModel
          ? corrected_limit_lap_vehicle(load_corrected_model(config.plant_params_yaml))
          : limit_lap_vehicle(plant);
  LimitLapTimes times;
  if (!vehicle) return times;
  times.flying_s = vehicle_limit_lap_s(config, *vehicle, track, LapStart::kFlying);
  times.standing_s = vehicle_limit_lap_s(config, *vehicle, track, LapStart::kStanding);
  return times;
}

std::string format_times(const std::vector<double>& times) {
  std::string s;
  char buf[32];
  for (double t : times) {
    std::snprintf(buf, sizeof buf, "%s%.2f", s.empty() ? "" : ", ", t);
    s += buf;
  }
  return s;
}

template <VehicleDynamics P>
RunSummary run_with_plant(const ClosedLoopConfig& config, P plant_model, const Track& track,
                          const AutoRallyCost& cost) {
  ControllerSetup setup = make_controller(config, cost);
  Controller* controller = setup.controller.get();
  const LimitLapTimes limit_laps = plant_limit_laps(config, plant_model, track);
  Plant<P> plant(std::move(plant_model), config.actuators, static_cast<float>(config.plant_dt_s));
  const Pose2 start = track.start_pose();
  VehicleState s0;
  s0.x_m = static_cast<float>(start.x_m);
  s0.y_m = static_cast<float>(start.y_m);
  s0.yaw_rad = static_cast<float>(start.yaw_rad);
  plant.reset(s0);

  LapCounter laps(track);
  laps.reset({start.x_m, start.y_m}, 0.0);
  const CrashDetector crash_detector(track);

  if (!(config.stall_timeout_s >= 0.0) || !(config.stall_progress_m >= 0.0))
    throw Error("stall_timeout_s and stall_progress_m must be >= 0 (0 = no stall check)");
  const double control_dt = config.controller.dt_s;
  const int substeps = std::max(1, static_cast<int>(std::lround(control_dt / config.plant_dt_s)));
  const double max_time = config.max_time_s > 0
                              ? config.max_time_s
                              : 30.0 + config.laps * track.length_m() /
                                           std::max(1.0, 0.3 * config.target_speed_mps);

  std::unique_ptr<RecordingWriter> log;
  if (!config.out_dir.empty()) {
    std::filesystem::create_directories(config.out_dir);
    log = std::make_unique<RecordingWriter>(
        config.out_dir + "/log.csv",
        std::vector<std::string>{"roll", "applied_steer", "applied_throttle", "progress_m",
                                 "lap", "optimizer_ms", "effective_sample_size", "min_cost",
                                 "slip_angle_rad", "lateral_accel_mps2", "step_status", "backend_switches",
                                 "lateral_force_scale"},
        std::vector<std::pair<std::string, std::string>>{
            {"source", "mppi-sim"}, {"track", track.name()}, {"model", config.model},
            {"plant", config.plant}, {"seed", std::to_string(config.controller.seed)},
            {"target_speed_mps", std::to_string(config.target_speed_mps)},
            {"surface", config.surface_yaml.empty() ? "flat" : config.surface_yaml}});
  }

  RunSummary summary;
  summary.track = track.name();
  summary.model = config.model;
  summary.plant = config.plant;
  summary.seed = config.controller.seed;
  summary.samples = config.controller.num_samples;
  summary.horizon = config.controller.horizon;
  summary.target_speed_mps = config.target_speed_mps;
  summary.backend = setup.backend;
  summary.limit_lap_s = limit_laps.flying_s;
  summary.standing_limit_lap_s = limit_laps.standing_s;
  if (limit_laps.any()) summary.limit_lap_method = config.limit_lap_method;
  long control_step = 0;

  std::vector<float> model_x(static_cast<std::size_t>(setup.model_states));
  std::vector<double> optimizer_ms, ess, lambdas, force_scales;
  std::vector<PathSample> path;
  std::vector<PathSample> slip_path;  // the same trail, value = |body slip| [deg]
  std::vector<double> abs_slip;
  double prev_vy = 0.0, prev_t = -1.0;
  std::vector<std::pair<float, float>> crash_points;
  double speed_sum = 0.0;
  long speed_samples = 0;
  CommandSteps command_steps;
  bool in_contact = false;
  double t = 0.0;
  int reported_laps = 0;
  StepSummary step_summary;
  std::optional<chassis::SimChassis> chassis;
  if (config.through_chassis) chassis.emplace();
  std::size_t next_target = 0;  // next entry of target_speed_schedule
  double target_speed_mps = config.target_speed_mps;
  // The adaptation holds the cost's target speed at the requested one x sqrt(grip scale): it
  // learns the request here.
  if (std::string why; config.controller.force_adaptation.enabled &&
                       !controller->set_cost_param("target_speed_mps", target_speed_mps, &why))
    throw Error("the controller refused the target speed: " + why);
  bool motion_enabled = true;
  // A marshal puts the car back on the centreline nearest to it, at rest, facing along the track.
  auto marshal_puts_back = [&](const VehicleState& s) {
    const Pose2 p = centreline_pose_nearest(track, {s.x_m, s.y_m});
    VehicleState respawn;
    respawn.x_m = static_cast<float>(p.x_m);
    respawn.y_m = static_cast<float>(p.y_m);
    respawn.yaw_rad = static_cast<float>(p.yaw_rad);
    plant.reset(respawn);
    controller->reset();
  };
  // Stall watch: the progress last reached and when (reset while the car is not asked to drive).
  double stall_ref_progress_m = laps.progress_m(), stall_ref_t = 0.0;
  if (config.observer) config.observer->on_start(setup.predict);
  while (t < max_time && laps.laps_completed() < config.laps) {
    if (config.observer) {
      const OperatorRequests r = config.observer->poll_requests(t);
      if (r.stop) break;
      std::string why;
      if (r.target_speed_mps && controller->set_cost_param("target_speed_mps", *r.target_speed_mps, &why))
        target_speed_mps = *r.target_speed_mps;
      if (r.motion_enabled && chassis) {
        chassis->set_motion_enabled(*r.motion_enabled);
        motion_enabled = *r.motion_enabled;
      }
    }
    const auto& schedule = config.target_speed_schedule;
    if (next_target < schedule.size() && t + 1e-9 >= schedule[next_target].first) {
      while (next_target + 1 < schedule.size() && t + 1e-9 >= schedule[next_target + 1].first) ++next_target;
      // The controller keeps its warm-started plan; only the cost's target changes.
      std::string why;
      if (!controller->set_cost_param("target_speed_mps", schedule[next_target].second, &why))
        throw Error("target_speed_schedule entry " + std::to_string(next_target) + ": " + why);
      target_speed_mps = schedule[next_target].second;
      ++next_target;
    }
    setup.observe(plant.state(), P::kNx, model_x.data());
    const auto u = controller->step(model_x, &step_summary);
    if (step_summary.status != StepStatus::kOk) ++summary.failed_steps;
    if (step_summary.backend_switched) {
      const Controller::BackendSwitch& b = controller->backend_switches().back();
      summary.backend_switches.push_back({control_step, t, b.from, b.to, b.reason});
      if (config.progress)
        std::fprintf(stderr, "  control step %ld (t = %.2f s): switched from the %s to the %s backend: %s\n",
                     control_step, t, b.from.c_str(), b.to.c_str(), b.reason.c_str());
    }
    ++control_step;
    // As on the real car, the controller's output reaches the plant through the chassis
    // interface (command validation, priorities, runstop, watchdog, calibration to pulse
    // widths and back through the simulated servos); through_chassis = false bypasses it.
    const Control output{u[control::kSteer], u[control::kThrottle]};
    const Control command = chassis ? chassis->drive(output, t) : output;
    command_steps.add(command);
    optimizer_ms.push_back(step_summary.optimizer_ms);
    ess.push_back(step_summary.effective_sample_size);
    lambdas.push_back(step_summary.lambda);
    force_scales.push_back(step_summary.lateral_force_scale);
    summary.nominal_resets += step_summary.nominal_reset ? 1 : 0;
    for (int i = 0; i < substeps; ++i) {
      plant.advance(command, static_cast<float>(config.plant_dt_s));
      t += config.plant_dt_s;
      const VehicleState s = plant.vehicle_state();
      laps.update({s.x_m, s.y_m}, t);
      const CrashResult crash = crash_detector.check(s.x_m, s.y_m, s.yaw_rad);
      if (crash.crashed && !in_contact) {
        ++summary.crashes;
        summary.crash_reasons.push_back(crash.reason);
        crash_points.emplace_back(static_cast<float>(crash.x_m), static_cast<float>(crash.y_m));
        if (config.progress)
          std::fprintf(stderr, "  crash at t = %.2f s: %s\n", t, crash.reason.c_str());
        marshal_puts_back(s);
        stall_ref_progress_m = laps.progress_m();
        stall_ref_t = t;
        in_contact = false;
        break;  // new control step from the respawned state
      }
      in_contact = crash.crashed;
    }
    const bool asked_to_drive = motion_enabled && target_speed_mps >= 1.0;
    if (!asked_to_drive || laps.progress_m() >= stall_ref_progress_m + config.stall_progress_m) {
      stall_ref_progress_m = laps.progress_m();
      stall_ref_t = t;
    } else if (config.stall_timeout_s > 0.0 && t - stall_ref_t >= config.stall_timeout_s) {
      ++summary.stalls;
      summary.stall_times_s.push_back(t);
      if (config.progress)
        std::fprintf(stderr, "  stalled at t = %.2f s: less than %.1f m of progress in %.1f s; put back on the track\n",
                     t, config.stall_progress_m, config.stall_timeout_s);
      marshal_puts_back(plant.vehicle_state());
      stall_ref_progress_m = laps.progress_m();
      stall_ref_t = t;
    }
    const VehicleState s = plant.vehicle_state();
    const double speed = std::hypot(s.vx_mps, s.vy_mps);
    speed_sum += speed;
    ++speed_samples;
    summary.max_speed_mps = std::max(summary.max_speed_mps, speed);
    path.push_back({s.x_m, s.y_m, static_cast<float>(speed)});
    const double slip = std::atan2(static_cast<double>(s.vy_mps), static_cast<double>(s.vx_mps));
    const double lat_accel = (prev_t >= 0.0 && t > prev_t ? (s.vy_mps - prev_vy) / (t - prev_t) : 0.0) +
                             static_cast<double>(s.vx_mps) * s.yaw_rate_radps;
    prev_vy = s.vy_mps;
    prev_t = t;
    if (s.vx_mps > 1.0f) {
      abs_slip.push_back(std::abs(slip));
      summary.peak_slip_angle_rad = std::max(summary.peak_slip_angle_rad, std::abs(slip));
      summary.peak_lateral_accel_mps2 = std::max(summary.peak_lateral_accel_mps2, std::abs(lat_accel));
    }
    slip_path.push_back({s.x_m, s.y_m, static_cast<float>(s.vx_mps > 1.0f ? std::abs(slip) * 180.0 / std::numbers::pi : 0.0)});
    if (log) {
      const double extras[] = {s.roll_rad, plant.applied().steer, plant.applied().throttle,
                               laps.progress_m(), static_cast<double>(laps.laps_completed()),
                               step_summary.optimizer_ms, step_summary.effective_sample_size,
                               step_summary.min_cost, slip, lat_accel, static_cast<double>(step_summary.status),
                               static_cast<double>(summary.backend_switches.size()),
                               step_summary.lateral_force_scale};
      log->write(t, s, command, extras);
    }
    if (config.observer)
      config.observer->after_step({.t_s = t, .state = s, .model_state = model_x, .output = output,
                                   .applied = plant.applied(), .summary = &step_summary, .controller = controller,
                                   .chassis = chassis ? &*chassis : nullptr, .laps_completed = laps.laps_completed(),
                                   .crashes = summary.crashes, .progress_m = laps.progress_m(),
                                   .target_speed_mps = target_speed_mps});
    if (!std::isfinite(s.x_m) || !std::isfinite(s.vx_mps))
      throw Error("the plant state became non-finite at t = " + std::to_string(t) + " s");
    if (laps.laps_completed() > reported_laps && config.progress) {
      reported_laps = laps.laps_completed();
      const double lap_time = laps.lap_times_s().back();
      char ratio[96] = "";
      const double limit_s = limit_laps.for_lap(reported_laps);
      if (std::isfinite(limit_s))
        std::snprintf(ratio, sizeof ratio, "%.2f x the %slimit lap %.2f s; ", lap_time / limit_s,
                      reported_laps == 1 ? "standing-start " : "", limit_s);
      std::fprintf(stderr, "lap %d/%d: %.2f s (%smean %.2f m/s), crashes so far %d, t = %.1f s\n",
                   reported_laps, config.laps, lap_time, ratio, track.length_m() / lap_time,
                   summary.crashes, t);
    }
  }
  if (config.observer) config.observer->on_finish();
  summary.sim_time_s = t;
  summary.laps_completed = laps.laps_completed();
  summary.lap_times_s = laps.lap_times_s();
  // Lap 1 against the standing-start limit lap (the car starts it from rest), the others the flying one.
  if (limit_laps.any())
    for (std::size_t i = 0; i < summary.lap_times_s.size(); ++i)
      summary.lap_time_ratio.push_back(summary.lap_times_s[i] / limit_laps.for_lap(static_cast<int>(i) + 1));
  summary.finished = summary.laps_completed >= config.laps;
  summary.mean_speed_mps = speed_samples ? speed_sum / speed_samples : 0.0;
  summary.mean_abs_steer_step = command_steps.mean_abs_steer_step();
  summary.mean_abs_throttle_step = command_steps.mean_abs_throttle_step();
  summary.optimizer_ms_p50 = percentile(optimizer_ms, 50);
  summary.p95_slip_angle_rad = abs_slip.empty() ? 0.0 : percentile(abs_slip, 95);
  summary.optimizer_ms_p99 = percentile(optimizer_ms, 99);
  double ess_sum = 0;
  for (double e : ess) ess_sum += e;
  summary.effective_sample_size_mean = ess.empty() ? 0.0 : ess_sum / ess.size();
  summary.sampler = sampler_name(config.controller.sampler.kind);
  summary.ess_target_share = config.controller.temperature.ess_share;
  summary.lambda_p50 = percentile(lambdas, 50);
  summary.actuator_model = config.actuator_model.empty() ? "none" : config.actuator_model;
  if (summary.actuator_model == "none" && !config.controller.actuators.empty()) summary.actuator_model = "custom";
  summary.variant = variant_name(config.controller.variant);
  summary.lateral_force_adaptation = config.controller.force_adaptation.enabled;
  if (!force_scales.empty()) {
    summary.lateral_force_scale_final = force_scales.back();
    summary.lateral_force_scale_p50 = percentile(force_scales, 50);
  }
  if (summary.ess_target_share > 0 && !ess.empty()) {
    const double want = summary.ess_target_share * config.controller.num_samples;
    std::size_t in_band = 0;
    for (double e : ess) in_band += std::abs(e / want - 1) <= 0.25;
    summary.ess_in_band_share = static_cast<double>(in_band) / static_cast<double>(ess.size());
  }
  if (log) {
    log->close();
    char title[256];
    std::snprintf(title, sizeof title, "%s | model %s, plant %s | %d laps [%s] s | crashes %d",
                  track.name().c_str(), config.model.c_str(), config.plant.c_str(),
                  summary.laps_completed, format_times(summary.lap_times_s).c_str(),
                  summary.crashes);
    plot_track_run(config.out_dir + "/track.png", track, path, crash_points, title);
    PlotOptions slip_plot;
    slip_plot.quantity = "body slip";
    slip_plot.unit = "deg";
    plot_track_run(config.out_dir + "/track_slip.png", track, slip_path, crash_points, title, slip_plot);
    write_summary(config.out_dir + "/summary.json", summary);
  }
  return summary;
}

}  // namespace

std::optional<SingleTrackParams> plant_vehicle_params(const ClosedLoopConfig& config) {
  if (!config.surface_yaml.empty())  // the single-track plant on a surface map: its own car file
    return load_single_track_params(model_file<models::SingleTrackModel>(config.plant_params_yaml, config.network_npz));
  if (config.plant == kCorrectedModel)
    return config.plant_params_yaml.empty()
               ? std::nullopt
               : corrected_limit_lap_vehicle(load_corrected_model(config.plant_params_yaml));
  return with_model(config.plant, [&]<class D>() -> std::optional<SingleTrackParams> {
    if constexpr (HasSingleTrackCore<typename D::Model>)
      return limit_lap_vehicle(D::load(model_file<D>(config.plant_params_yaml, config.network_npz)));
    else
      return std::nullopt;
  }, "plant");
}

RunSummary run_closed_loop(const ClosedLoopConfig& given) {
  ClosedLoopConfig config = given;
  require_limit_lap_method(config.limit_lap_method);
  if (!config.actuator_model.empty() && config.actuator_model != "none")
    config.controller.actuators =
        resolve_actuator_model(config.actuator_model, config.plant, config.plant_params_yaml, config.actuators);
  TrackOptions track_options;
  track_options.direction = config.clockwise ? Direction::kClockwise : Direction::kCounterClockwise;
  const Track track = Track::load(config.track, track_options);
  AutoRallyCostParams cost_params = load_autorally_cost_params(
      config.cost_params_yaml.empty() ? data_file(kDefaultCostYaml) : config.cost_params_yaml);
  cost_params.target_speed_mps = static_cast<float>(config.target_speed_mps);
  const AutoRallyCost cost(std::make_shared<const CostMap>(CostMap::load_npz(
                               config.cost_map_npz.empty() ? track.costmap_path() : config.cost_map_npz)),
                           cost_params);
  if (config.laps < 1) throw Error("laps must be >= 1");
  for (std::size_t i = 0; i < config.target_speed_schedule.size(); ++i) {
    const auto& [from_s, speed] = config.target_speed_schedule[i];
    if (!std::isfinite(from_s) || !std::isfinite(speed) ||
        (i > 0 && from_s < config.target_speed_schedule[i - 1].first))
      throw Error("target_speed_schedule entry " + std::to_string(i) +
                  ": times must be finite and ascending, speeds finite");
  }
  if (!config.surface_yaml.empty()) {
    // The surface plant is the single-track car on the map: a plant whose parameters are
    // SingleTrackParams themselves.
    const bool single_track_params = is_registered_model(config.plant) && with_model(config.plant, [&]<class D>() {
      if constexpr (HasParamTable<D>) return std::is_same_v<typename D::Params, SingleTrackParams>;
      else return false;
    }, "plant");
    if (!single_track_params)
      throw Error("a surface map (" + config.surface_yaml + ") needs the single-track plant, not '" + config.plant + "'");
    auto surface = std::make_shared<const SurfaceMap>(SurfaceMap::load(config.surface_yaml));
    const SingleTrackParams params =
        load_single_track_params(model_file<models::SingleTrackModel>(config.plant_params_yaml, config.network_npz));
    return run_with_plant(config, SingleTrackOnSurface(params, std::move(surface)), track, cost);
  }
  if (config.plant == kCorrectedModel) {
    // The plant's actuators delay the commands exactly, by the file's pure delays.
    ClosedLoopConfig plant_config = config;
    if (!config.plant_params_yaml.empty()) {
      const EffectParams e = load_corrected_model(config.plant_params_yaml).effects;
      plant_config.actuators.steer_delay_s = static_cast<float>(e.steer_delay_s);
      plant_config.actuators.throttle_delay_s = static_cast<float>(e.throttle_delay_s);
    }
    return visit_corrected(
        config.plant_params_yaml, "plant",
        [&](const auto& model, auto) { return run_with_plant(plant_config, model, track, cost); },
        /*pure_delays_outside=*/true);
  }
  return with_model(config.plant, [&]<class D>() {
    return run_with_plant(config, D::load(model_file<D>(config.plant_params_yaml, config.network_npz)), track, cost);
  }, "plant");
}

}  // namespace mppi::sim
