#include "cli/sim_command_line.hpp"

#include <algorithm>
#include <string>
#include <vector>

#include "cli/app.hpp"
#include "cli/options.hpp"

namespace mppi::cli {
namespace {

// A float setting read as a double and rounded once to float (as the options hold it), so that
// the value given and a run file's round trip agree to the last bit.
CLI::Option* add_float_option(CLI::App& app, const std::string& name, float& target, const std::string& description) {
  return app.add_option_function<double>(name, [&target](double v) { target = static_cast<float>(v); }, description)
      ->default_str(CLI::detail::to_string(target));
}

// A comma-separated list of numbers ("" = empty), so that an empty default round-trips
// through a run file.
CLI::Option* add_float_list_option(CLI::App& app, const std::string& name, std::vector<float>& target,
                                   const std::string& description) {
  auto join = [](const std::vector<float>& v) {
    std::string text;
    for (std::size_t i = 0; i < v.size(); ++i) text += (i ? "," : "") + CLI::detail::to_string(v[i]);
    return text;
  };
  return app
      .add_option_function<std::string>(
          name,
          [&target, name](const std::string& text) {
            std::vector<float> values;
            std::size_t start = 0;
            while (start < text.size()) {
              const std::size_t end = std::min(text.find(',', start), text.size());
              const std::string item = text.substr(start, end - start);
              std::size_t used = 0;
              double v = 0.0;
              try {
                v = std::stod(item, &used);
              } catch (const std::exception&) {
                used = 0;
              }
              if (used == 0 || used != item.size())
                throw CLI::ValidationError(name, "'" + item + "' is not a number (give numbers separated by commas)");
              values.push_back(static_cast<float>(v));
              start = end + 1;
            }
            target = std::move(values);
          },
          description)
      ->default_str(join(target));
}

}  // namespace

sim::ClosedLoopConfig SimCommandLine::defaults() {
  sim::ClosedLoopConfig c;
  c.out_dir = "out/sim";
  c.backend = BackendChoice::kAuto;
  // Upstream AutoRally ends every control step with a 5-point quadratic Savitzky-Golay filter over
  // the plan (MPPIController::computeControl); on the oval it adds about 0.2 m/s of mean speed at
  // 8 m/s without a crash (docs/CALIBRATION.md). The library's own default stays off.
  c.controller.smoothing_window = 5;
  c.controller.smoothing_order = 2;
  return c;
}

void add_sim_options(CLI::App& app, SimCommandLine& cl) {
  configure(app);
  sim::ClosedLoopConfig& c = cl.config;
  ControllerOptions& mppi = c.controller;
  add_track_option(app, c.track);
  app.add_flag("--clockwise", c.clockwise, "drive clockwise (default counter-clockwise)");
  add_model_option(app, "--model", c.model,
                   "controller model: a registered model, or corrected (a nominal model + effects from mppi-fit "
                   "diagnose, in --model-params)",
                   {}, {"corrected"});
  add_model_option(app, "--plant", c.plant, "simulated car: a registered model, or corrected", {}, {"corrected"});
  app.add_flag("--list-models", cl.list_models, "every model with its data file, states and parameters, and exit")
      ->configurable(false);
  app.add_flag("--limit-lap", cl.limit_lap,
               "print the plant's limit lap on the track (minimum-time lap on a racing line, docs/LIMIT_LAP.md), "
               "write DIR/limit_lap.csv and DIR/limit_lap.png (--out), and exit");
  app.add_option("--speed", c.target_speed_mps, "target speed [m/s]")->type_name("MPS");
  app.add_option("--laps", c.laps, "laps to drive")->type_name("N");
  app.add_option("--max-time", c.max_time_s, "stop after S simulated seconds (0: from the laps)")->type_name("S");
  app.add_option("--stall-timeout", c.stall_timeout_s,
                 "a car with less than 2 m of progress along the track in S seconds is stalled: counted and put "
                 "back on the track (0: off)")
      ->type_name("S")
      ->check(CLI::NonNegativeNumber);
  add_float_option(app, "--steer-rate-limit", c.actuators.steer_rate_per_s,
                   "the simulated car's steering servo: max |d steer / dt| in commands per second (2 / R s lock to lock)")
      ->type_name("R")
      ->check(CLI::PositiveNumber);
  add_float_option(app, "--throttle-rate-limit", c.actuators.throttle_rate_per_s,
                   "the simulated car's throttle channel: max |d throttle / dt| [1/s]")
      ->type_name("R")
      ->check(CLI::PositiveNumber);
  app.add_option("--samples", mppi.num_samples, "MPPI samples per step")->type_name("K");
  app.add_option("--horizon", mppi.horizon, "MPPI time steps")->type_name("T");
  app.add_option("--iterations", mppi.iterations, "MPPI iterations per step")->type_name("N");
  app.add_option("--warm-start-iterations", mppi.warm_start_iterations,
                 "extra MPPI iterations at the first step and after each respawn, when the plan is cold")
      ->type_name("N")
      ->check(CLI::Range(0, 1000));
  add_float_option(app, "--lambda", mppi.lambda, "MPPI temperature")->type_name("L");
  add_float_list_option(app, "--noise-std", mppi.noise_std,
                        "standard deviation of the sampled perturbations per control channel (steering, "
                        "throttle), comma-separated")
      ->type_name("S,...");
  app.add_option("--smoothing", mppi.smoothing_window, "Savitzky-Golay window over the plan (odd, <= the horizon; upstream AutoRally: 5), 0 = off")
      ->type_name("W");
  app.add_option_function<std::string>(
         "--sampler", [&mppi](const std::string& name) { parse_sampler_kind(name, &mppi.sampler.kind); },
         "how the perturbations are drawn along the horizon: gaussian (white, the paper's) | lowpass (a "
         "first-order low-pass, --sampler-cutoff) | smooth (drawn on the controls' rate and integrated, as "
         "SMPPI, --smooth-time)")
      ->type_name("NAME")
      ->check(CLI::IsMember({"gaussian", "lowpass", "smooth"}).name("SAMPLER").description(""))
      ->default_str(sampler_name(mppi.sampler.kind));
  add_float_option(app, "--sampler-cutoff", mppi.sampler.cutoff_hz, "lowpass sampler: corner frequency [Hz]")
      ->type_name("HZ")
      ->check(CLI::PositiveNumber);
  add_float_option(app, "--smooth-time", mppi.sampler.smooth_time_s,
                   "smooth sampler: time at which the integrated noise reaches the noise's standard deviation [s]")
      ->type_name("S")
      ->check(CLI::PositiveNumber);
  add_float_option(app, "--ess-target", mppi.temperature.ess_share,
                   "adaptive temperature: lambda set at every step so that the effective sample size is this "
                   "share of the samples (0 = fixed --lambda)")
      ->type_name("SHARE")
      ->check(CLI::Range(0.0, 1.0));
  add_float_option(app, "--lambda-min", mppi.temperature.lambda_min, "adaptive temperature: lowest lambda")
      ->type_name("L")
      ->check(CLI::PositiveNumber);
  add_float_option(app, "--lambda-max", mppi.temperature.lambda_max, "adaptive temperature: highest lambda")
      ->type_name("L")
      ->check(CLI::PositiveNumber);
  app.add_option_function<std::string>(
         "--variant", [&mppi](const std::string& name) { parse_controller_variant(name, &mppi.variant); },
         "plain (plans from the measured state) | tube (Tube-MPPI: plans from a nominal state, LQR feedback "
         "on the error) | robust (Robust MPPI's choice of the nominal state, the same feedback)")
      ->type_name("NAME")
      ->check(CLI::IsMember({"plain", "tube", "robust"}).name("VARIANT").description(""))
      ->default_str(variant_name(mppi.variant));
  add_float_option(app, "--tube-reset", mppi.tube_reset_distance,
                   "tube / robust: the Q-weighted distance of the measured state from the nominal one that puts "
                   "the nominal state back on it")
      ->type_name("D")
      ->check(CLI::PositiveNumber);
  add_float_option(app, "--robust-margin", mppi.robust_cost_margin,
                   "robust: how much more the plan may cost from the measured state than from the nominal one "
                   "for the measured state to be taken [cost units]")
      ->type_name("C")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--robust-augmented", mppi.robust_augmented_sampling,
               "robust: RMPPI's augmented sampling: every sample also rolls out the real system from the measured "
               "state under the feedback, and is scored by both rollouts (CPU backend)");
  add_float_option(app, "--robust-cost-bound", mppi.robust_cost_bound,
                   "robust with --robust-augmented: the most a sample's real-system rollout may cost (RMPPI's "
                   "bound; default inf: unbounded) [cost units]")
      ->type_name("C")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {  // > 0, inf included (what --dump-config writes)
            try {
              return std::stod(text) > 0 ? "" : "must be > 0 (inf: unbounded), got " + text;
            } catch (const std::exception&) {
              return "must be a number > 0 or inf, got " + text;
            }
          },
          "POSITIVE or inf"));
  add_float_list_option(app, "--ancillary-q", mppi.ancillary.q_diag,
                        "tube / robust: the feedback's state weights, comma-separated, one per model state "
                        "(empty: 1 each)")
      ->type_name("Q,...");
  add_float_list_option(app, "--ancillary-r", mppi.ancillary.r_diag,
                        "tube / robust: the feedback's control weights, comma-separated, one per control "
                        "(empty: 1 each)")
      ->type_name("R,...");
  app.add_flag("--adapt-grip", mppi.force_adaptation.enabled,
               "online grip adaptation: fit a scale of the model's lateral tyre force to the measured motion at "
               "every step and hold the target speed at --speed x scale^--adapt-speed-exponent (CPU backend; "
               "mppi/lateral_force_adaptation.hpp)");
  app.add_flag("--adapt-model", mppi.force_adaptation.scale_model,
               "online grip adaptation: plan with the model's lateral force x the scale as well (the AutoRally "
               "network)");
  add_float_option(app, "--adapt-speed-exponent", mppi.force_adaptation.speed_exponent,
                   "online grip adaptation: the target speed is --speed x scale^this (0.5: steady cornering's "
                   "sqrt(mu); 1: with a margin)")
      ->type_name("E")
      ->check(CLI::Range(0.0, 2.0));
  add_float_option(app, "--adapt-throttle-exponent", mppi.force_adaptation.throttle_exponent,
                   "online grip adaptation: the throttle's upper limit is the configured one x scale^this (0: kept)")
      ->type_name("E")
      ->check(CLI::Range(0.0, 2.0));
  add_float_option(app, "--adapt-memory", mppi.force_adaptation.memory_s,
                   "online adaptation: time over which the evidence is forgotten [s]")
      ->type_name("S")
      ->check(CLI::PositiveNumber);
  app.add_option("--actuator-model", c.actuator_model,
                 "the actuators the controller plans through (delay, rate limit, lag per channel): none | plant "
                 "(the simulated car's own) | a corrected-model FILE (mppi-fit diagnose)")
      ->type_name("SOURCE");
  add_seed_option(app, mppi.seed);
  add_threads_option(app, mppi.num_threads);
  add_backend_option(app, c.backend);
  app.add_option("--cost-config", c.cost_params_yaml, "AutoRally cost weights (YAML; default data/config)")
      ->type_name("FILE");
  app.add_option("--cost-map", c.cost_map_npz,
                 "the controller's cost map (AutoRally .npz; default: the track's own; --limit-lap writes one "
                 "around the racing line)")
      ->type_name("FILE");
  app.add_option("--limit-lap-method", c.limit_lap_method,
                 "how the limit lap is computed: qss (quasi-steady-state on a racing line) | collocation (the "
                 "minimum-time lap of the single-track equations, IPOPT; docs/LIMIT_LAP.md)")
      ->type_name("M");
  app.add_option("--plant-params", c.plant_params_yaml,
                 "the plant's data file (YAML parameters, or a corrected-model file; keys: --list-models)")
      ->type_name("FILE");
  app.add_option("--model-params", c.model_params_yaml, "the controller model's data file (the same kinds)")
      ->type_name("FILE");
  app.add_option("--network", c.network_npz, "weights (.npz) of a learned model, when no --*-params file is given")
      ->type_name("FILE");
  app.add_option("--nn-precision", c.nn_precision,
                 "CPU backend: arithmetic of the controller network's hidden layers, fp32 | bf16 (bf16 on "
                 "CPUs with AVX512-BF16, else fp32; docs/BENCHMARKS.md section 5)")
      ->type_name("P")
      ->check(CLI::IsMember({"fp32", "bf16"}).name("P").description(""));
  app.add_option("--inject-device-loss-at-step", c.inject_device_loss_at_step,
                 "fault drill: the backend fails like a lost GPU after N control steps; the run goes on on the "
                 "CPU backend (summary.json: backend_switches)")
      ->type_name("N");
  app.add_option("--surface", c.surface_yaml, "grip and elevation by place (YAML, docs/SURFACES.md; single-track plant)")
      ->type_name("FILE");
  add_out_option(app, c.out_dir, "write DIR/log.csv, DIR/track.png, DIR/summary.json");
  app.add_flag("--json", cl.print_json, "print summary.json to stdout");
  app.add_flag("--quiet", cl.quiet, "no progress lines");
  add_data_dir_option(app, cl.data_dir);
  cl.run_file.add_options(app);
}

void finish_sim_options(CLI::App& app, SimCommandLine& cl) {
  cl.run_file.apply(app);
  const ControllerOptions& mppi = cl.config.controller;
  if (mppi.smoothing_window > mppi.horizon)
    throw usage_error("--smoothing", "a window of " + std::to_string(mppi.smoothing_window) +
                                         " steps (mppi-sim's default: 5) needs --horizon >= " +
                                         std::to_string(mppi.smoothing_window) + "; --smoothing 0 turns it off");
  cl.config.progress = !cl.quiet;
}

}  // namespace mppi::cli
