// AutoRally's basis-function model ("autorally-bf"): one-step predictions against a naive
// double-precision evaluation of the 25 basis functions written here from AutoRally's
// car_bfs.cuh (in AutoRally's own conventions), the shipped weights and bad files, the CPU
// against the Vulkan backend (when one is built: lavapipe in CI), and 3 laps of the Gazebo oval
// without a crash on each.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "base/npz.hpp"
#include "costs/autorally_cost.hpp"
#include "dynamics/models/autorally_bf_model.hpp"
#include "factory/make_controller.hpp"
#include "mppi/cost_map.hpp"
#include "sim/closed_loop.hpp"
#include "test_data.hpp"

namespace {

std::string data(const std::string& rel) { return std::string(MPPI_TEST_DATA_DIR) + "/" + rel; }
const std::string kWeights = "autorally/models/basis_function_09_12_2018.npz";

// phi(s, u) as AutoRally writes it: s = [x, y, yaw, roll, u_x, u_y, yaw_mder], u = [steering
// (right +), throttle]; below u_x = 0.1 the ratios are 0 (and atan(..) - u0 is -u0).
std::array<double, 25> naive_basis(const double* s, const double* u) {
  const bool moving = s[4] > 0.1;
  const double a = moving ? std::atan(s[5] / s[4] + 0.45 * s[6] / s[4]) - u[0] : -u[0];
  const double t = std::tan(a);
  const double q = moving ? s[5] / s[4] - 0.35 * s[6] / s[4] : 0.0;
  return {u[1],
          s[4] / 10.0,
          std::sin(u[0]) * t / 1200.0,
          std::sin(u[0]) * t * std::fabs(t) / 1440000.0,
          std::sin(u[0]) * std::pow(t, 3) / 1728000000.0,
          s[6] * s[5] / 25.0,
          s[6] / 10.0,
          s[5] / 10.0,
          std::sin(u[0]),
          moving ? s[5] / s[4] / 40.0 : 0.0,
          t / 1400.0,
          t * std::fabs(t) / 1960000.0,
          std::pow(t, 3) / 2744000000.0,
          q / 40.0,
          q * std::fabs(q) / 1600.0,
          std::pow(q, 3) / 64000.0,
          s[6] * s[4] / 50.0,
          s[3],
          s[3] * s[6],
          s[3] * s[4] / 3.0,
          s[3] * s[4] * s[6] / 5.0,
          std::pow(s[4], 2) / 100.0,
          std::pow(s[4], 3) / 1000.0,
          std::pow(u[1], 2),
          std::pow(u[1], 3)};
}

// One explicit-Euler step in the library's state [x, y, yaw, vx, vy, yaw_rate, roll] through
// AutoRally's conventions (yaw_mder = -yaw_rate, steering negated), W read here from the file.
std::array<double, 7> naive_step(const std::vector<double>& w, const double* x, double steer, double throttle,
                                 double dt) {
  const double s[7] = {x[0], x[1], x[2], x[6], x[3], x[4], -x[5]};
  const double u[2] = {-steer, throttle};
  const auto phi = naive_basis(s, u);
  double d[4] = {0, 0, 0, 0};
  for (int o = 0; o < 4; ++o)
    for (int b = 0; b < 25; ++b) d[o] += w[static_cast<std::size_t>(o * 25 + b)] * phi[static_cast<std::size_t>(b)];
  // kinematics as AutoRally's CarKinematics: x' = cos(yaw) u_x - sin(yaw) u_y, ..., yaw' = -yaw_mder
  return {x[0] + (std::cos(x[2]) * x[3] - std::sin(x[2]) * x[4]) * dt,
          x[1] + (std::sin(x[2]) * x[3] + std::cos(x[2]) * x[4]) * dt,
          x[2] + x[5] * dt,
          x[3] + d[1] * dt,
          x[4] + d[2] * dt,
          x[5] - d[3] * dt,
          x[6] + d[0] * dt};
}

const mppi::AutoRallyCost& gazebo_cost() {
  static const mppi::AutoRallyCost cost(std::make_shared<const mppi::CostMap>(
      mppi::CostMap::load_npz(data("autorally/maps/gazebo/gazebo_costmap.npz"))));
  return cost;
}

bool lavapipe_installed() {
  for (const char* dir : {"/usr/share/vulkan/icd.d", "/etc/vulkan/icd.d"}) {
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir, ec))
      if (e.path().filename().string().rfind("lvp_icd", 0) == 0) return true;
  }
  return false;
}

// True if a Vulkan device runs the controller; false (with a warning) where none is built or
// installed; a failure where lavapipe is installed and the backend built but it does not run.
bool vulkan_ran(const mppi::BackendReport& report) {
  if (report.backend == "vulkan") return true;
  if (!mppi::backend_factories().empty() && lavapipe_installed())
    FAIL("lavapipe is installed but the Vulkan backend did not run: " << report.reason);
  WARN("Vulkan part not run: " << report.reason);
  return false;
}

}  // namespace

TEST_CASE("autorally-bf: one step equals a naive double evaluation of the 25 basis functions", "[autorally_bf]") {
  const mppi::NpzFile file = mppi::NpzFile::load(data(kWeights));
  const std::vector<double>& w = file.at("W").values;
  const auto model = mppi::AutoRallyBasisFunctionModel::load(data(kWeights));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> vx(-1.0, 12.0), vy(-2.0, 2.0), r(-3.0, 3.0), roll(-0.2, 0.2),
      yaw(-10.0, 10.0), steer(-1.0, 1.0), throttle(-1.0, 1.0);
  double worst = 0;
  int checked = 0;
  for (int i = 0; i < 20000; ++i) {
    double x[7] = {vx(rng), vy(rng), yaw(rng), vx(rng), vy(rng), r(rng), roll(rng)};
    const double u[2] = {steer(rng), throttle(rng)};
    if (i % 10 == 0) x[3] = 0.05;  // the standstill branch
    // tan(beta - u0) is singular at +-pi/2: keep away from it, where float and double part.
    const double beta = x[3] > 0.1 ? std::atan((x[4] - 0.45 * x[5]) / x[3]) : 0.0;
    if (std::cos(beta + u[0]) < 0.3) continue;
    float xf[7], uf[2] = {static_cast<float>(u[0]), static_cast<float>(u[1])};
    for (int k = 0; k < 7; ++k) {
      xf[k] = static_cast<float>(x[k]);
      x[k] = xf[k];  // the same start in both
    }
    const auto expected = naive_step(w, x, uf[0], uf[1], 0.02);
    model.step<1>(mppi::Batch<7, 1>{xf}, mppi::ConstBatch<2, 1>{uf}, 0.02f, nullptr);
    for (int k = 0; k < 7; ++k) {
      const double err = std::abs(xf[k] - expected[static_cast<std::size_t>(k)]) /
                         std::max(1.0, std::abs(expected[static_cast<std::size_t>(k)]));
      worst = std::max(worst, err);
    }
    ++checked;
  }
  INFO("states checked " << checked << ", worst relative error " << worst);
  CHECK(checked > 10000);
  CHECK(worst < 2e-6);  // float rounding of a 0.02 s step (measured 2.8e-7)
}

TEST_CASE("autorally-bf: the shipped weights load, bad files are refused with the reason", "[autorally_bf]") {
  const auto model = mppi::AutoRallyBasisFunctionModel::load(data(kWeights));
  CHECK(model.weights()[0] == Approx(-0.006).margin(1e-3));  // W[0][0], roll row, throttle
  CHECK_THROWS_WITH(mppi::AutoRallyBasisFunctionModel::load(data("autorally/models/autorally_nnet_09_12_2018.npz")),
                    Catch::Contains("missing array 'W'"));
  CHECK_THROWS_WITH(mppi::AutoRallyBasisFunctionModel::load("/nonexistent/bf.npz"), Catch::Contains("/nonexistent/bf.npz"));
  mppi::AutoRallyBasisFunctionModel::Weights bad{};
  bad[7] = NAN;
  CHECK_THROWS_WITH(mppi::AutoRallyBasisFunctionModel(bad), Catch::Contains("NaN"));
}

TEST_CASE("autorally-bf: the Vulkan backend's costs equal the CPU backend's", "[autorally_bf][vulkan]") {
  const auto model = mppi::AutoRallyBasisFunctionModel::load(data(kWeights));
  for (const int t : {100, 500}) {
    const int k = t == 100 ? 1000 : 333;  // not multiples of the workgroup size
    mppi::ControllerOptions o;
    o.num_samples = k;
    o.horizon = t;
    o.gamma = 0.1f;
    o.seed = 12345;
    mppi::BackendReport report;
    mppi::Controller cpu = mppi::make_controller(model, gazebo_cost(), o, mppi::BackendChoice::kCpu);
    mppi::Controller gpu = mppi::make_controller(model, gazebo_cost(), o, mppi::BackendChoice::kVulkan, &report);
    if (!vulkan_ran(report)) return;
    const std::vector<float> x0 = {-8.5f, -8.9f, 2.3561945f, 5.f, 0.f, 0.1f, 0.f};
    double worst_cost = 0, worst_control = 0;
    for (int step = 0; step < 2; ++step) {
      const auto uc = cpu.step(x0);
      const std::vector<float> u_cpu(uc.begin(), uc.end());
      const auto ug = gpu.step(x0);
      const auto cc = cpu.sampled_costs(), cg = gpu.sampled_costs();
      for (int j = 0; j < k; ++j)
        worst_cost = std::max(worst_cost, std::abs(double(cc[j]) - cg[j]) / std::max(1.0, std::abs(double(cc[j]))));
      for (int c = 0; c < 2; ++c) worst_control = std::max(worst_control, double(std::abs(u_cpu[c] - ug[c])));
    }
    INFO("K = " << k << ", T = " << t << ": worst cost rel. diff " << worst_cost << ", control diff " << worst_control);
    CHECK(worst_cost <= 1e-3);
    CHECK(worst_control <= 1e-4);
  }
}

TEST_CASE("autorally-bf drives 3 laps of the Gazebo oval without a crash, on the CPU and on Vulkan",
          "[autorally_bf][closed_loop][slow]") {
  for (const auto backend : {mppi::BackendChoice::kCpu, mppi::BackendChoice::kVulkan}) {
    mppi::sim::ClosedLoopConfig c;
    c.model = mppi::models::AutoRallyBasisFunctions::kName;
    c.laps = 3;
    c.backend = backend;
    mppi::BackendReport report;
    c.backend_report = &report;
    c.progress = false;
    const mppi::sim::RunSummary s = mppi::sim::run_closed_loop(c);
    if (backend == mppi::BackendChoice::kVulkan && !vulkan_ran(report)) return;
    INFO(report.backend << ": laps " << s.laps_completed << ", crashes " << s.crashes << ", mean speed "
                        << s.mean_speed_mps);
    CHECK(s.laps_completed == 3);
    CHECK(s.crashes == 0);
    CHECK(s.mean_speed_mps > 4.0);
  }
}
