#include "ros/controller_setup.hpp"

#include <cmath>
#include <functional>

#include "base/error.hpp"
#include "costs/autorally_cost.hpp"
#include "costs/cost_config.hpp"
#include "dynamics/model_registry.hpp"
#include "factory/make_controller.hpp"
#include "mppi/backend_choice.hpp"
#include "mppi/controller.hpp"
#include "mppi/controller_options.hpp"
#include "mppi/cost_map.hpp"
#include "sim/data_dir.hpp"
#include "sim/path_predictor.hpp"
#include "sim/track.hpp"
#ifdef MPPI_HAVE_OCS
#include "ocs/loop_page.hpp"
#endif

namespace mppi::ros {

bool ControllerNodeSettings::is_valid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (!(hz > 0.0 && hz <= 1000.0)) return fail("hz must be in (0, 1000], got " + std::to_string(hz));
  if (!(desired_speed >= 0.0) || !std::isfinite(desired_speed)) return fail("desired_speed must be >= 0");
  if (!(max_throttle > -0.99 && max_throttle <= 1.0)) return fail("max_throttle must be in (-0.99, 1]");
  if (!(max_steering > 0.0 && max_steering <= 1.0)) return fail("max_steering must be in (0, 1]");
  if (serve_port < -1 || serve_port > 65535) return fail("serve_port must be -1 (none) or a port in [0, 65535]");
  if (backend != "cpu" && backend != "vulkan" && backend != "auto")
    return fail("backend must be cpu, vulkan or auto, got '" + backend + "'");
  ControllerVariant v;
  if (!parse_controller_variant(variant, &v)) return fail("variant must be plain, tube or robust, got '" + variant + "'");
  std::string option_why;
  if (!options().is_valid(control::kCommonControls, &option_why)) return fail(option_why);
  return true;
}

ControllerOptions ControllerNodeSettings::options() const {
  ControllerOptions o;
  o.num_samples = num_rollouts;
  o.horizon = num_timesteps;
  o.dt_s = static_cast<float>(1.0 / hz);
  o.lambda = static_cast<float>(lambda);
  o.gamma = static_cast<float>(gamma);
  o.noise_std = {static_cast<float>(steering_std), static_cast<float>(throttle_std)};
  o.control_min = {-static_cast<float>(max_steering), -0.99f};
  o.control_max = {static_cast<float>(max_steering), static_cast<float>(max_throttle)};
  o.safe_control = {0.f, std::min(0.f, static_cast<float>(max_throttle))};
  o.num_threads = num_threads;
  o.seed = seed;
  parse_controller_variant(variant, &o.variant);
  o.force_adaptation.enabled = adapt_grip;
  o.robust_augmented_sampling = robust_augmented;
  o.robust_cost_bound = static_cast<float>(robust_cost_bound);
  return o;
}

struct NodeController::Impl {
  std::unique_ptr<Controller> controller;
  int model_states = 0;
  std::function<void(const float* common, float* model_x)> observe;
  sim::PathPredictor predict;
  std::string backend;
  std::vector<float> x;
  std::vector<float> gains;
  StepSummary summary;
#ifdef MPPI_HAVE_OCS
  std::unique_ptr<ocs::LoopPage> page;
#endif
};

NodeController::NodeController(const ControllerNodeSettings& s) : impl_(std::make_unique<Impl>()) {
  std::string why;
  if (!s.is_valid(&why)) throw Error("controller node parameters: " + why);
  const sim::Track track = sim::Track::load(s.track);
  AutoRallyCostParams cost_params =
      load_autorally_cost_params(s.cost_params.empty() ? sim::data_file("config/autorally_cost.yaml") : s.cost_params);
  cost_params.target_speed_mps = static_cast<float>(s.desired_speed);
  const AutoRallyCost cost(
      std::make_shared<const CostMap>(CostMap::load_npz(s.map_path.empty() ? track.costmap_path() : s.map_path)),
      cost_params);
  const ControllerOptions options = s.options();
  const BackendChoice choice = parse_backend_choice(s.backend);
  Impl& d = *impl_;
  with_model(s.model, [&]<class D>() {
    std::string file = s.model_params;
    if (file.empty()) {
      const std::string default_file = D::kDefaultFile;
      file = default_file.empty() ? default_file : sim::data_file(default_file);
    }
    const typename D::Model model = D::load(file);
    BackendReport report;
    d.controller = std::make_unique<Controller>(make_controller(model, cost, options, choice, &report));
    // The adaptation governs the target speed the controller was asked for.
    if (options.force_adaptation.enabled && !d.controller->set_cost_param("target_speed_mps", s.desired_speed, &why))
      throw Error("controller node parameters: desired_speed: " + why);
    d.backend = report.backend + (report.device.empty() ? "" : " on " + report.device) + " (" + report.reason + ")";
    d.model_states = D::Model::kNx;
    d.observe = [model](const float* common, float* mx) { D::from_plant(model, common, state::kCommonStates, mx); };
    d.predict = sim::make_path_predictor(model, options.dt_s);
  }, "model");
  d.x.assign(static_cast<std::size_t>(d.model_states), 0.f);
  if (s.serve_port >= 0) {
#ifdef MPPI_HAVE_OCS
    ocs::ServerSettings page;
    page.port = s.serve_port;
    d.page = std::make_unique<ocs::LoopPage>(page, s.map_path.empty() ? s.track : std::string(), d.predict,
                                             s.desired_speed);
#else
    throw Error("serve_port: this build has no operator page (ocs/CMakeLists.txt says why)");
#endif
  }
}

NodeController::~NodeController() = default;

NodeController::Step NodeController::step(const VehicleState& state, double t_s, Control applied,
                                          bool motion_enabled) {
  Impl& d = *impl_;
  const auto common = state.to_array();
  d.observe(common.data(), d.x.data());
#ifdef MPPI_HAVE_OCS
  if (d.page) d.page->apply_requests(*d.controller);
#endif
  const auto u = d.controller->step(d.x, &d.summary);
#ifdef MPPI_HAVE_OCS
  if (d.page)
    d.page->after_step(t_s, state, d.x, Control{u[control::kSteer], u[control::kThrottle]}, applied, d.summary,
                       *d.controller, motion_enabled, false);
#else
  (void)t_s, (void)applied, (void)motion_enabled;
#endif
  Step out;
  out.ok = d.summary.status == StepStatus::kOk;
  out.reason = d.summary.reason;
  out.output = Control{u[control::kSteer], u[control::kThrottle]};
  out.optimizer_ms = d.summary.optimizer_ms;
  const auto g = d.controller->feedback_gains();
  d.gains.assign(g.begin(), g.end());
  return out;
}

void NodeController::planned_path(std::vector<float>* xy) const {
  const Impl& d = *impl_;
  xy->assign(static_cast<std::size_t>(horizon() + 1) * 2, 0.f);
  d.predict(d.x, d.controller->nominal(), 1, *xy);
}

bool NodeController::page_motion_allowed() const {
#ifdef MPPI_HAVE_OCS
  if (impl_->page) return impl_->page->motion_allowed();
#endif
  return true;
}

const std::vector<float>& NodeController::feedback_gains() const { return impl_->gains; }
int NodeController::horizon() const { return impl_->controller->options().horizon; }
int NodeController::controls() const { return control::kCommonControls; }
int NodeController::model_states() const { return impl_->model_states; }
const std::string& NodeController::backend() const { return impl_->backend; }

}  // namespace mppi::ros
