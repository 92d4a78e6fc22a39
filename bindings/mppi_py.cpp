// Python module `mppi`: the MPPI controller with the library's models and costs, the closed-loop
// track simulator, and recording I/O. numpy arrays in and out (float32 for states and controls);
// the GIL is released while C++ computes (Controller.step, run_closed_loop), so Python threads
// can run controllers in parallel. mppi::Error becomes mppi.Error (a RuntimeError).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "costs/autorally_cost.hpp"
#include "costs/cost_config.hpp"
#include "mppi/cost_map.hpp"
#include "costs/goal_obstacle_cost.hpp"
#include "dynamics/autorally_nn.hpp"
#include "dynamics/diff_drive.hpp"
#include "dynamics/kinematic_bicycle.hpp"
#include "dynamics/single_track.hpp"
#include "dynamics/vehicle_params.hpp"
#include "dynamics/model_registry.hpp"
#include "mppi/controller.hpp"
#include "base/error.hpp"
#include "sim/closed_loop.hpp"
#include "sim/data_dir.hpp"
#include "sim/recording.hpp"
#include "sim/summary.hpp"
#ifdef MPPI_HAVE_LAPTIME
#include "laptime/register_collocation.hpp"
#endif

namespace py = pybind11;

#ifdef MPPI_PY_SYSID
void register_sysid(py::module_& m);  // bindings/sysid_py.cpp
#endif
using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

namespace {

std::vector<float> to_vector(const FloatArray& a) {
  return std::vector<float>(a.data(), a.data() + a.size());
}
FloatArray to_array(std::span<const float> v) {
  FloatArray out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

// A cost of either kind, shared with every controller built from it.
using AnyCost = std::variant<mppi::AutoRallyCost, mppi::GoalObstacleCost>;

// Controller plus what Python needs to feed it: the model name and how to make a model state
// from the common vehicle state (vehicle models only).
struct PyController {
  std::unique_ptr<mppi::Controller> controller;
  std::string model;
  int nx = 0, nu = 0;
  std::function<void(const mppi::VehicleState&, float*)> init_state;  // empty for diff-drive

  std::pair<FloatArray, mppi::StepSummary> step(const FloatArray& state) {
    std::vector<float> x = to_vector(state);
    mppi::StepSummary summary;
    std::vector<float> u;
    {
      py::gil_scoped_release release;
      const std::span<const float> out = controller->step(x, &summary);
      u.assign(out.begin(), out.end());
    }
    return {to_array(u), summary};
  }
};

template <class Model>
void build(PyController& c, Model model, const AnyCost& cost, const mppi::ControllerOptions& o) {
  c.nx = Model::kNx;
  c.nu = Model::kNu;
  std::visit([&](const auto& concrete) {
    using C = std::decay_t<decltype(concrete)>;
    if constexpr (std::is_same_v<C, mppi::AutoRallyCost> && !mppi::VehicleDynamics<Model>)
      throw mppi::Error("AutoRallyCost needs a vehicle model (" + mppi::model_names() +
                        "); use GoalObstacleCost with diff-drive");
    else
      c.controller = std::make_unique<mppi::Controller>(mppi::make_cpu_controller(model, concrete, o));
  }, cost);
  if constexpr (mppi::VehicleDynamics<Model>)
    c.init_state = [model](const mppi::VehicleState& s, float* x) { model.init_state(s, x); };
}

// model: a registered model (mppi::model_names()) or diff-drive; model_file: network npz or
// parameter YAML (empty = the library's default).
std::unique_ptr<PyController> make_controller(const std::string& model, const AnyCost& cost,
                                              const mppi::ControllerOptions& options,
                                              const std::string& model_file) {
  auto c = std::make_unique<PyController>();
  c->model = model;
  if (model == "diff-drive") {
    if (!model_file.empty()) throw mppi::Error("diff-drive takes no model_file (use DiffDriveParams)");
    build(*c, mppi::DiffDrive(), cost, options);
  } else if (mppi::is_registered_model(model)) {
    mppi::with_model(model, [&]<class D>() {
      const std::string default_file = D::kDefaultFile;
      const std::string file =
          !model_file.empty() || default_file.empty() ? model_file : mppi::sim::data_file(default_file);
      build(*c, D::load(file), cost, options);
    });
  } else {
    throw mppi::Error("unknown model '" + model + "' (valid: " + mppi::model_names() + ", diff-drive)");
  }
  return c;
}

py::dict recording_to_dict(const mppi::sim::Recording& r) {
  py::dict columns;
  for (std::size_t c = 0; c < r.columns.size(); ++c) {
    DoubleArray a(static_cast<py::ssize_t>(r.data[c].size()));
    std::copy(r.data[c].begin(), r.data[c].end(), a.mutable_data());
    columns[py::str(r.columns[c])] = a;
  }
  py::dict out;
  out["metadata"] = r.metadata;
  out["columns"] = columns;
  out["column_names"] = r.columns;
  return out;
}

}  // namespace

PYBIND11_MODULE(mppi, m) {
#ifdef MPPI_HAVE_LAPTIME
  mppi::laptime::register_collocation_limit_lap();
#endif
  m.doc() = "MPPI (model predictive path integral) control after AutoRally: controller, models, "
            "costs, closed-loop track simulator and recording I/O";
  py::register_exception<mppi::Error>(m, "Error", PyExc_RuntimeError);

  // ---- options and step summary ----
  py::enum_<mppi::SamplerKind>(m, "SamplerKind", "how the perturbations are drawn along the horizon")
      .value("GAUSSIAN", mppi::SamplerKind::kGaussian)
      .value("LOW_PASS", mppi::SamplerKind::kLowPass)
      .value("SMOOTH", mppi::SamplerKind::kSmooth);
  py::class_<mppi::SamplerOptions>(m, "SamplerOptions", "the sampler (gaussian, low-pass, derivative-space)")
      .def(py::init<>())
      .def_readwrite("kind", &mppi::SamplerOptions::kind)
      .def_readwrite("cutoff_hz", &mppi::SamplerOptions::cutoff_hz)
      .def_readwrite("smooth_time_s", &mppi::SamplerOptions::smooth_time_s);
  py::class_<mppi::TemperatureTarget>(m, "TemperatureTarget",
                                      "adaptive temperature: lambda held at an effective-sample-size share")
      .def(py::init<>())
      .def_readwrite("ess_share", &mppi::TemperatureTarget::ess_share, "target ESS / K; 0 = fixed lambda")
      .def_readwrite("lambda_min", &mppi::TemperatureTarget::lambda_min)
      .def_readwrite("lambda_max", &mppi::TemperatureTarget::lambda_max)
      .def_readwrite("tolerance", &mppi::TemperatureTarget::tolerance);
  py::class_<mppi::LateralForceAdaptation>(m, "LateralForceAdaptation",
                                           "online adaptation of the model's lateral tyre force to the measured motion")
      .def(py::init<>())
      .def_readwrite("enabled", &mppi::LateralForceAdaptation::enabled)
      .def_readwrite("memory_s", &mppi::LateralForceAdaptation::memory_s, "time over which evidence is forgotten [s]")
      .def_readwrite("prior_weight", &mppi::LateralForceAdaptation::prior_weight)
      .def_readwrite("min_scale", &mppi::LateralForceAdaptation::min_scale)
      .def_readwrite("max_scale", &mppi::LateralForceAdaptation::max_scale)
      .def_readwrite("min_speed_mps", &mppi::LateralForceAdaptation::min_speed_mps)
      .def_readwrite("max_accel_mps2", &mppi::LateralForceAdaptation::max_accel_mps2)
      .def_readwrite("speed_param", &mppi::LateralForceAdaptation::speed_param,
                     "cost parameter held at the requested value x sqrt(scale); empty = off")
      .def_readwrite("speed_exponent", &mppi::LateralForceAdaptation::speed_exponent,
                     "the speed parameter is held at the requested value x scale^speed_exponent")
      .def_readwrite("throttle_exponent", &mppi::LateralForceAdaptation::throttle_exponent,
                     "the throttle's upper limit is held at the configured one x scale^throttle_exponent (0: kept)")
      .def_readwrite("scale_model", &mppi::LateralForceAdaptation::scale_model,
                     "plan with the model's lateral force x scale as well");
  py::class_<mppi::ActuatorChannel>(m, "ActuatorChannel",
                                    "one channel's actuator: pure delay, rate limit, first-order lag")
      .def(py::init<>())
      .def(py::init([](float delay_s, float lag_s, float rate_per_s) {
             return mppi::ActuatorChannel{delay_s, lag_s, rate_per_s};
           }),
           py::arg("delay_s") = 0.f, py::arg("lag_s") = 0.f, py::arg("rate_per_s") = 0.f)
      .def_readwrite("delay_s", &mppi::ActuatorChannel::delay_s)
      .def_readwrite("lag_s", &mppi::ActuatorChannel::lag_s)
      .def_readwrite("rate_per_s", &mppi::ActuatorChannel::rate_per_s, "0 = unlimited");
  py::class_<mppi::ControllerOptions>(m, "ControllerOptions",
                                      "MPPI settings (AutoRally defaults: K = 1920, T = 100, 50 Hz)")
      .def(py::init<>())
      .def_readwrite("num_samples", &mppi::ControllerOptions::num_samples)
      .def_readwrite("horizon", &mppi::ControllerOptions::horizon)
      .def_readwrite("dt_s", &mppi::ControllerOptions::dt_s)
      .def_readwrite("iterations", &mppi::ControllerOptions::iterations)
      .def_readwrite("warm_start_iterations", &mppi::ControllerOptions::warm_start_iterations)
      .def_readwrite("lambda_", &mppi::ControllerOptions::lambda, "temperature (lambda)")
      .def_readwrite("gamma", &mppi::ControllerOptions::gamma)
      .def_readwrite("noise_std", &mppi::ControllerOptions::noise_std)
      .def_readwrite("control_min", &mppi::ControllerOptions::control_min)
      .def_readwrite("control_max", &mppi::ControllerOptions::control_max)
      .def_readwrite("safe_control", &mppi::ControllerOptions::safe_control)
      .def_readwrite("smoothing_window", &mppi::ControllerOptions::smoothing_window)
      .def_readwrite("smoothing_order", &mppi::ControllerOptions::smoothing_order)
      .def_readwrite("seed", &mppi::ControllerOptions::seed)
      .def_readwrite("num_threads", &mppi::ControllerOptions::num_threads)
      .def_readwrite("sampler", &mppi::ControllerOptions::sampler)
      .def_readwrite("temperature", &mppi::ControllerOptions::temperature)
      .def_readwrite("force_adaptation", &mppi::ControllerOptions::force_adaptation)
      .def_property("variant",
                    [](const mppi::ControllerOptions& o) { return std::string(mppi::variant_name(o.variant)); },
                    [](mppi::ControllerOptions& o, const std::string& name) {
                      if (!mppi::parse_controller_variant(name, &o.variant))
                        throw mppi::Error("variant must be plain, tube or robust, got '" + name + "'");
                    }, "plain | tube | robust")
      .def_readwrite("tube_reset_distance", &mppi::ControllerOptions::tube_reset_distance)
      .def_readwrite("robust_cost_margin", &mppi::ControllerOptions::robust_cost_margin)
      .def_readwrite("robust_augmented_sampling", &mppi::ControllerOptions::robust_augmented_sampling,
                     "robust: RMPPI's augmented sampling (the real system rolled out in every sample)")
      .def_readwrite("robust_cost_bound", &mppi::ControllerOptions::robust_cost_bound,
                     "robust_augmented_sampling: the most a real-system rollout may cost (inf: unbounded)")
      .def_property("ancillary_q",
                    [](const mppi::ControllerOptions& o) { return o.ancillary.q_diag; },
                    [](mppi::ControllerOptions& o, const std::vector<float>& q) { o.ancillary.q_diag = q; },
                    "tube / robust: the feedback's state weights (empty: 1 each)")
      .def_property("ancillary_r",
                    [](const mppi::ControllerOptions& o) { return o.ancillary.r_diag; },
                    [](mppi::ControllerOptions& o, const std::vector<float>& r) { o.ancillary.r_diag = r; },
                    "tube / robust: the feedback's control weights (empty: 1 each)")
      .def_readwrite("actuators", &mppi::ControllerOptions::actuators,
                     "list of ActuatorChannel, one per control channel (empty: none)")
      .def("is_valid", [](const mppi::ControllerOptions& o, int num_controls) {
        std::string why;
        const bool ok = o.is_valid(num_controls, &why);
        return std::make_pair(ok, why);
      }, py::arg("num_controls"), "(ok, reason) for a model with num_controls controls");

  py::enum_<mppi::StepStatus>(m, "StepStatus")
      .value("OK", mppi::StepStatus::kOk)
      .value("INVALID_STATE", mppi::StepStatus::kInvalidState)
      .value("NO_VALID_ROLLOUT", mppi::StepStatus::kNoValidRollout)
      .value("BACKEND_ERROR", mppi::StepStatus::kBackendError);

  py::class_<mppi::StepSummary>(m, "StepSummary")
      .def_readonly("status", &mppi::StepSummary::status)
      .def_property_readonly("reason", [](const mppi::StepSummary& s) { return std::string(s.reason); })
      .def_readonly("min_cost", &mppi::StepSummary::min_cost)
      .def_readonly("mean_cost", &mppi::StepSummary::mean_cost)
      .def_readonly("effective_sample_size", &mppi::StepSummary::effective_sample_size)
      .def_readonly("valid_samples", &mppi::StepSummary::valid_samples)
      .def_readonly("lateral_force_scale", &mppi::StepSummary::lateral_force_scale)
      .def_readonly("iterations", &mppi::StepSummary::iterations)
      .def_readonly("lambda_", &mppi::StepSummary::lambda, "temperature of the weights")
      .def_readonly("tube_distance", &mppi::StepSummary::tube_distance)
      .def_readonly("nominal_reset", &mppi::StepSummary::nominal_reset)
      .def_readonly("feedback_applied", &mppi::StepSummary::feedback_applied)
      .def_readonly("augmented_sampling", &mppi::StepSummary::augmented_sampling)
      .def_readonly("optimizer_ms", &mppi::StepSummary::optimizer_ms);

  py::class_<mppi::VehicleState>(m, "VehicleState", "common vehicle state (ISO 8855, SI units)")
      .def(py::init([](float x, float y, float yaw, float vx, float vy, float yaw_rate, float roll) {
             return mppi::VehicleState{x, y, yaw, vx, vy, yaw_rate, roll};
           }),
           py::arg("x_m") = 0.f, py::arg("y_m") = 0.f, py::arg("yaw_rad") = 0.f, py::arg("vx_mps") = 0.f,
           py::arg("vy_mps") = 0.f, py::arg("yaw_rate_radps") = 0.f, py::arg("roll_rad") = 0.f)
      .def_readwrite("x_m", &mppi::VehicleState::x_m)
      .def_readwrite("y_m", &mppi::VehicleState::y_m)
      .def_readwrite("yaw_rad", &mppi::VehicleState::yaw_rad)
      .def_readwrite("vx_mps", &mppi::VehicleState::vx_mps)
      .def_readwrite("vy_mps", &mppi::VehicleState::vy_mps)
      .def_readwrite("yaw_rate_radps", &mppi::VehicleState::yaw_rate_radps)
      .def_readwrite("roll_rad", &mppi::VehicleState::roll_rad);

  // ---- cost maps and costs ----
  py::class_<mppi::CostMap, std::shared_ptr<mppi::CostMap>>(m, "CostMap")
      .def(py::init([](float x_min, float x_max, float y_min, float y_max, float ppm, const FloatArray& values) {
             return std::make_shared<mppi::CostMap>(x_min, x_max, y_min, y_max, ppm, to_vector(values));
           }),
           py::arg("x_min_m"), py::arg("x_max_m"), py::arg("y_min_m"), py::arg("y_max_m"),
           py::arg("pixels_per_meter"), py::arg("values"),
           "values: height x width (row 0 at y_min), any shape with that many elements")
      .def_static("load_npz", [](const std::string& p) { return std::make_shared<mppi::CostMap>(mppi::CostMap::load_npz(p)); },
                  py::arg("path"), "AutoRally cost-map npz")
      .def_static("square_obstacles",
                  [](float size_m, float resolution_m, const std::vector<std::tuple<float, float, float>>& obstacles,
                     float value) {
                    std::vector<mppi::SquareObstacle> obs;
                    for (const auto& [x, y, side] : obstacles) obs.push_back({x, y, side});
                    return std::make_shared<mppi::CostMap>(mppi::make_square_obstacle_map(size_m, resolution_m, obs, value));
                  },
                  py::arg("size_m") = 11.f, py::arg("resolution_m") = 0.1f,
                  py::arg("obstacles") = std::vector<std::tuple<float, float, float>>{{8.f, 8.f, 0.4f}, {4.f, 6.f, 0.5f}, {6.f, 5.f, 0.3f}},
                  py::arg("value") = 250.f,
                  "square-obstacle map from (x, y, side) tuples; defaults: the MPPI-Generic benchmark map")
      .def_property_readonly("width", &mppi::CostMap::width)
      .def_property_readonly("height", &mppi::CostMap::height)
      .def_property_readonly("bounds", [](const mppi::CostMap& c) {
        return py::make_tuple(c.x_min_m(), c.x_max_m(), c.y_min_m(), c.y_max_m());
      })
      .def_property_readonly("pixels_per_meter", &mppi::CostMap::pixels_per_meter)
      .def_property_readonly("values", [](const mppi::CostMap& c) {
        FloatArray a({c.height(), c.width()});
        std::copy(c.values().begin(), c.values().end(), a.mutable_data());
        return a;
      })
      .def("lookup", [](const mppi::CostMap& c, const FloatArray& x, const FloatArray& y) {
        if (x.size() != y.size()) throw mppi::Error("CostMap.lookup: x and y differ in size");
        FloatArray out(x.size());
        for (py::ssize_t i = 0; i < x.size(); ++i) out.mutable_data()[i] = c.lookup(x.data()[i], y.data()[i]);
        return out;
      }, py::arg("x_m"), py::arg("y_m"), "nearest-pixel values at (x, y) (1-D arrays), clamped to the edge");

  py::class_<mppi::AutoRallyCostParams>(m, "AutoRallyCostParams")
      .def(py::init<>())
      .def_static("load_yaml", &mppi::load_autorally_cost_params, py::arg("path"))
      .def_readwrite("track_weight", &mppi::AutoRallyCostParams::track_weight)
      .def_readwrite("speed_weight", &mppi::AutoRallyCostParams::speed_weight)
      .def_readwrite("crash_weight", &mppi::AutoRallyCostParams::crash_weight)
      .def_readwrite("slip_weight", &mppi::AutoRallyCostParams::slip_weight)
      .def_readwrite("target_speed_mps", &mppi::AutoRallyCostParams::target_speed_mps)
      .def_readwrite("crash_discount", &mppi::AutoRallyCostParams::crash_discount)
      .def_readwrite("boundary_threshold", &mppi::AutoRallyCostParams::boundary_threshold)
      .def_readwrite("max_roll_rad", &mppi::AutoRallyCostParams::max_roll_rad)
      .def_readwrite("max_yaw_rate_radps", &mppi::AutoRallyCostParams::max_yaw_rate_radps)
      .def_readwrite("slip_min_speed_mps", &mppi::AutoRallyCostParams::slip_min_speed_mps);

  py::class_<mppi::AutoRallyCost>(m, "AutoRallyCost", "the AutoRally paper's running cost on a cost map")
      .def(py::init([](std::shared_ptr<mppi::CostMap> map, const mppi::AutoRallyCostParams& p) {
             return mppi::AutoRallyCost(std::move(map), p);
           }),
           py::arg("map"), py::arg("params") = mppi::AutoRallyCostParams{})
      .def_property_readonly("params", &mppi::AutoRallyCost::params)
      .def("evaluate", [](const mppi::AutoRallyCost& c, const FloatArray& s, int t) {
        if (s.size() < mppi::state::kCommonStates) throw mppi::Error("AutoRallyCost.evaluate: need the 7 common states");
        return c.evaluate(s.data(), t);
      }, py::arg("state"), py::arg("t") = 0, "q(x, t) at one state (common layout, >= 7 floats)");

  py::class_<mppi::GoalObstacleCostParams>(m, "GoalObstacleCostParams")
      .def(py::init<>())
      .def_readwrite("goal_x_m", &mppi::GoalObstacleCostParams::goal_x_m)
      .def_readwrite("goal_y_m", &mppi::GoalObstacleCostParams::goal_y_m)
      .def_readwrite("goal_yaw_rad", &mppi::GoalObstacleCostParams::goal_yaw_rad)
      .def_readwrite("goal_weight", &mppi::GoalObstacleCostParams::goal_weight)
      .def_readwrite("goal_power", &mppi::GoalObstacleCostParams::goal_power)
      .def_readwrite("goal_angle_weight", &mppi::GoalObstacleCostParams::goal_angle_weight)
      .def_readwrite("goal_angle_power", &mppi::GoalObstacleCostParams::goal_angle_power)
      .def_readwrite("goal_distance_threshold_m", &mppi::GoalObstacleCostParams::goal_distance_threshold_m)
      .def_readwrite("critical_weight", &mppi::GoalObstacleCostParams::critical_weight)
      .def_readwrite("repulsion_weight", &mppi::GoalObstacleCostParams::repulsion_weight)
      .def_readwrite("inflation_radius_m", &mppi::GoalObstacleCostParams::inflation_radius_m)
      .def_readwrite("collision_margin_m", &mppi::GoalObstacleCostParams::collision_margin_m)
      .def_readwrite("cost_scaling_factor", &mppi::GoalObstacleCostParams::cost_scaling_factor)
      .def_readwrite("inscribed_radius_m", &mppi::GoalObstacleCostParams::inscribed_radius_m)
      .def_readwrite("near_goal_distance_m", &mppi::GoalObstacleCostParams::near_goal_distance_m)
      .def_readwrite("obstacle_power", &mppi::GoalObstacleCostParams::obstacle_power)
      .def_readwrite("collision_cost", &mppi::GoalObstacleCostParams::collision_cost)
      .def_readwrite("lethal_value", &mppi::GoalObstacleCostParams::lethal_value);

  py::class_<mppi::GoalObstacleCost>(m, "GoalObstacleCost",
                                     "goal + goal-angle + obstacle cost (Nav2 critics, MPPI-Generic benchmark)")
      .def(py::init([](std::shared_ptr<mppi::CostMap> map, const mppi::GoalObstacleCostParams& p) {
             return mppi::GoalObstacleCost(std::move(map), p);
           }),
           py::arg("map"), py::arg("params") = mppi::GoalObstacleCostParams{})
      .def_property_readonly("params", &mppi::GoalObstacleCost::params)
      .def("evaluate", [](const mppi::GoalObstacleCost& c, const FloatArray& s) {
        if (s.size() < 3) throw mppi::Error("GoalObstacleCost.evaluate: need (x, y, yaw)");
        return c.evaluate(s.data());
      }, py::arg("state"));

  // ---- the differential drive (for Python-side plants) ----
  py::class_<mppi::DiffDrive>(m, "DiffDrive", "differential drive: state (x, y, yaw), control (v, omega)")
      .def(py::init([](double r, double l) { return mppi::DiffDrive(mppi::DiffDriveParams{r, l}); }),
           py::arg("wheel_radius_m") = 1.0, py::arg("wheel_base_m") = 1.0)
      .def("step", [](const mppi::DiffDrive& d, const FloatArray& x, const FloatArray& u, float dt_s) {
        if (x.size() != 3 || u.size() != 2) throw mppi::Error("DiffDrive.step: x needs 3 values, u 2");
        float xs[3] = {x.data()[0], x.data()[1], x.data()[2]};
        float us[2] = {u.data()[0], u.data()[1]};
        d.step<1>(mppi::Batch<3, 1>{xs}, mppi::ConstBatch<2, 1>{us}, dt_s, nullptr);
        return to_array(xs);
      }, py::arg("x"), py::arg("u"), py::arg("dt_s"), "one forward-Euler step; returns the new state");

  // ---- the controller ----
  py::class_<PyController>(m, "Controller",
                           "MPPI on the CPU. model: autorally-nn | single-track | kinematic | diff-drive; "
                           "cost: AutoRallyCost (vehicle models) or GoalObstacleCost (any model)")
      .def(py::init([](const std::string& model, py::object cost, const mppi::ControllerOptions& options,
                       const std::string& model_file) {
             AnyCost any = py::isinstance<mppi::AutoRallyCost>(cost)
                               ? AnyCost(cost.cast<mppi::AutoRallyCost>())
                               : AnyCost(cost.cast<mppi::GoalObstacleCost>());
             return make_controller(model, any, options, model_file);
           }),
           py::arg("model"), py::arg("cost"), py::arg("options") = mppi::ControllerOptions{},
           py::arg("model_file") = std::string())
      .def("step", &PyController::step, py::arg("state"),
           "one control step from the model state (float32 array of num_states); returns "
           "(control array of num_controls, StepSummary). Releases the GIL.")
      .def("reset", [](PyController& c) { c.controller->reset(); }, "forget the plan")
      .def("set_cost_param",
           [](PyController& c, const std::string& key, double value) {
             std::string why;
             if (!c.controller->set_cost_param(key, value, &why)) throw mppi::Error(why);
           },
           py::arg("key"), py::arg("value"),
           "change one cost parameter by its YAML key (e.g. 'target_speed_mps') while running; the "
           "plan is kept. Raises for an unknown key or a value out of range (nothing changes)")
      .def("model_state", [](const PyController& c, const mppi::VehicleState& s) {
        if (!c.init_state) throw mppi::Error("model_state: " + c.model + " is not a vehicle model");
        std::vector<float> x(static_cast<std::size_t>(c.nx), 0.f);
        c.init_state(s, x.data());
        return to_array(x);
      }, py::arg("vehicle_state"), "the model's full state for a common vehicle state")
      .def_property_readonly("model", [](const PyController& c) { return c.model; })
      .def_property_readonly("num_states", [](const PyController& c) { return c.nx; })
      .def_property_readonly("num_controls", [](const PyController& c) { return c.nu; })
      .def_property_readonly("step_index", [](const PyController& c) { return c.controller->step_index(); })
      .def_property_readonly("options", [](const PyController& c) { return c.controller->options(); })
      .def_property_readonly("nominal", [](const PyController& c) {
        FloatArray a({c.controller->options().horizon, c.nu});
        const auto n = c.controller->nominal();
        std::copy(n.begin(), n.end(), a.mutable_data());
        return a;
      }, "the plan, T x num_controls")
      .def_property_readonly("sampled_controls", [](const PyController& c) {
        const int t = c.controller->options().horizon, k = c.controller->options().num_samples;
        const auto v = c.controller->sampled_controls();
        FloatArray a({t, c.nu, k});
        if (v.empty()) return a;  // nothing sampled yet
        const auto padded = static_cast<std::size_t>(c.controller->backend().shape().padded_samples);
        float* out = a.mutable_data();
        for (std::size_t r = 0; r < static_cast<std::size_t>(t) * c.nu; ++r)
          std::copy_n(v.begin() + static_cast<std::ptrdiff_t>(r * padded), k, out + r * k);
        return a;
      }, "the last iteration's sampled control sequences, T x num_controls x K")
      .def_property_readonly("feedback_gains", [](const PyController& c) {
        const auto g = c.controller->feedback_gains();
        FloatArray a({static_cast<int>(g.size() / std::max(1, c.nu * c.nx)), c.nu, c.nx});
        std::copy(g.begin(), g.end(), a.mutable_data());
        return a;
      }, "tube / robust: the last step's gains along the plan, T x num_controls x num_states (u = u_nom + K dx)")
      .def_property_readonly("nominal_states", [](const PyController& c) {
        const auto x = c.controller->nominal_states();
        FloatArray a({static_cast<int>(x.size() / std::max(1, c.nx)), c.nx});
        std::copy(x.begin(), x.end(), a.mutable_data());
        return a;
      }, "tube / robust: the last plan's states from the nominal state, (T + 1) x num_states")
      .def_property_readonly("sampled_costs", [](const PyController& c) { return to_array(c.controller->sampled_costs()); })
      .def_property_readonly("weights", [](const PyController& c) { return to_array(c.controller->weights()); });

  // ---- closed-loop simulator ----
  py::class_<mppi::sim::ActuatorLimits>(m, "ActuatorLimits")
      .def(py::init<>())
      .def_readwrite("steer_rate_per_s", &mppi::sim::ActuatorLimits::steer_rate_per_s)
      .def_readwrite("throttle_rate_per_s", &mppi::sim::ActuatorLimits::throttle_rate_per_s)
      .def_readwrite("steer_min", &mppi::sim::ActuatorLimits::steer_min)
      .def_readwrite("steer_max", &mppi::sim::ActuatorLimits::steer_max)
      .def_readwrite("throttle_min", &mppi::sim::ActuatorLimits::throttle_min)
      .def_readwrite("throttle_max", &mppi::sim::ActuatorLimits::throttle_max);

  using Cfg = mppi::sim::ClosedLoopConfig;
  py::class_<Cfg>(m, "ClosedLoopConfig", "settings of sim.run_closed_loop (the mppi-sim flags)")
      .def(py::init<>())
      .def_readwrite("track", &Cfg::track)
      .def_readwrite("clockwise", &Cfg::clockwise)
      .def_readwrite("model", &Cfg::model)
      .def_readwrite("plant", &Cfg::plant)
      .def_readwrite("target_speed_mps", &Cfg::target_speed_mps)
      .def_readwrite("laps", &Cfg::laps)
      .def_readwrite("max_time_s", &Cfg::max_time_s)
      .def_readwrite("stall_timeout_s", &Cfg::stall_timeout_s)
      .def_readwrite("stall_progress_m", &Cfg::stall_progress_m)
      .def_readwrite("controller", &Cfg::controller)
      .def_readwrite("cost_params_yaml", &Cfg::cost_params_yaml)
      .def_readwrite("cost_map_npz", &Cfg::cost_map_npz)
      .def_readwrite("limit_lap_method", &Cfg::limit_lap_method)
      .def_readwrite("plant_params_yaml", &Cfg::plant_params_yaml)
      .def_readwrite("model_params_yaml", &Cfg::model_params_yaml)
      .def_readwrite("network_npz", &Cfg::network_npz)
      .def_readwrite("actuators", &Cfg::actuators)
      .def_readwrite("actuator_model", &Cfg::actuator_model, "none | plant | a corrected-model file")
      .def_readwrite("plant_dt_s", &Cfg::plant_dt_s)
      .def_readwrite("out_dir", &Cfg::out_dir)
      .def_readwrite("progress", &Cfg::progress);

  using Sum = mppi::sim::RunSummary;
  py::class_<Sum>(m, "RunSummary")
      .def_readonly("track", &Sum::track)
      .def_readonly("model", &Sum::model)
      .def_readonly("plant", &Sum::plant)
      .def_readonly("seed", &Sum::seed)
      .def_readonly("samples", &Sum::samples)
      .def_readonly("horizon", &Sum::horizon)
      .def_readonly("target_speed_mps", &Sum::target_speed_mps)
      .def_readonly("sim_time_s", &Sum::sim_time_s)
      .def_readonly("finished", &Sum::finished)
      .def_readonly("laps_completed", &Sum::laps_completed)
      .def_readonly("lap_times_s", &Sum::lap_times_s)
      .def_readonly("limit_lap_s", &Sum::limit_lap_s)
      .def_readonly("standing_limit_lap_s", &Sum::standing_limit_lap_s)
      .def_readonly("limit_lap_method", &Sum::limit_lap_method)
      .def_readonly("lap_time_ratio", &Sum::lap_time_ratio)
      .def_readonly("crashes", &Sum::crashes)
      .def_readonly("crash_reasons", &Sum::crash_reasons)
      .def_readonly("stalls", &Sum::stalls)
      .def_readonly("stall_times_s", &Sum::stall_times_s)
      .def_readonly("mean_speed_mps", &Sum::mean_speed_mps)
      .def_readonly("max_speed_mps", &Sum::max_speed_mps)
      .def_readonly("optimizer_ms_p50", &Sum::optimizer_ms_p50)
      .def_readonly("optimizer_ms_p99", &Sum::optimizer_ms_p99)
      .def_readonly("effective_sample_size_mean", &Sum::effective_sample_size_mean)
      .def_readonly("sampler", &Sum::sampler)
      .def_readonly("ess_target_share", &Sum::ess_target_share)
      .def_readonly("ess_in_band_share", &Sum::ess_in_band_share)
      .def_readonly("lambda_p50", &Sum::lambda_p50)
      .def_readonly("lateral_force_adaptation", &Sum::lateral_force_adaptation)
      .def_readonly("lateral_force_scale_final", &Sum::lateral_force_scale_final)
      .def_readonly("lateral_force_scale_p50", &Sum::lateral_force_scale_p50)
      .def_readonly("actuator_model", &Sum::actuator_model)
      .def_readonly("variant", &Sum::variant)
      .def_readonly("nominal_resets", &Sum::nominal_resets)
      .def_readonly("mean_abs_steer_step", &Sum::mean_abs_steer_step)
      .def_readonly("mean_abs_throttle_step", &Sum::mean_abs_throttle_step)
      .def("to_json", [](const Sum& s) { return mppi::sim::to_json(s); });

  m.def("run_closed_loop", [](const Cfg& config) {
    py::gil_scoped_release release;
    return mppi::sim::run_closed_loop(config);
  }, py::arg("config"), "drive laps of a built-in track (releases the GIL); returns a RunSummary");

  m.def("data_dir", &mppi::sim::data_dir, "the data folder ($MPPI_DATA_DIR or the source tree's data/)");

  // ---- recordings ----
  m.def("read_recording", [](const std::string& path) {
    return recording_to_dict(mppi::sim::RecordingReader::read(path));
  }, py::arg("path"),
        "read a CSV recording (docs/RECORDING_FORMAT.md): {'metadata': dict, 'column_names': list, "
        "'columns': {name: float64 array}} (NaN = missing)");

  m.def("write_recording", [](const std::string& path, py::dict columns, py::dict metadata) {
    // required columns first, in the format's order, then the others in the dict's order
    std::vector<std::string> extra;
    std::vector<DoubleArray> data;
    for (const std::string& name : mppi::sim::kRecordingRequiredColumns) {
      if (!columns.contains(name)) throw mppi::Error("write_recording: missing required column '" + name + "'");
      data.push_back(columns[py::str(name)].cast<DoubleArray>());
    }
    for (auto item : columns) {
      const auto name = item.first.cast<std::string>();
      bool required = false;
      for (const std::string& r : mppi::sim::kRecordingRequiredColumns) required |= r == name;
      if (required) continue;
      extra.push_back(name);
      data.push_back(item.second.cast<DoubleArray>());
    }
    std::vector<std::pair<std::string, std::string>> meta;
    for (auto item : metadata) meta.emplace_back(py::str(item.first), py::str(item.second));
    const auto rows = data[0].size();
    for (std::size_t c = 0; c < data.size(); ++c)
      if (data[c].size() != rows) throw mppi::Error("write_recording: columns differ in length");
    mppi::sim::RecordingWriter writer(path, extra, meta);
    std::vector<double> row(data.size());
    for (py::ssize_t r = 0; r < rows; ++r) {
      for (std::size_t c = 0; c < data.size(); ++c) row[c] = data[c].data()[r];
      writer.write_row(row);
    }
    writer.close();
  }, py::arg("path"), py::arg("columns"), py::arg("metadata") = py::dict(),
        "write a CSV recording from {name: array} (t, x, y, yaw, vx, vy, yaw_rate, steer, "
        "throttle required; other columns are extras; NaN = missing)");

#ifdef MPPI_PY_SYSID
  register_sysid(m);
#endif
}
