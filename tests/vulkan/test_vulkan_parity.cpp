// Parity of the Vulkan backend with the CPU backend, on whatever Vulkan device exists (in CI:
// lavapipe). The oracle is the CPU backend (itself tested against closed forms and double
// references): for every model with a GPU twin, under the AutoRally cost on the Gazebo map,
// 99% of the per-sample total costs must agree within 1e-3 relative and the first control
// within 1e-4, for K not a multiple of the workgroup size (64) and T = 100 and T = 500 (lavapipe
// silently stops a shader's loops after 65,535 iterations: a truncated rollout would miss
// hundreds of steps of cost and fail here).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "costs/autorally_cost.hpp"
#include "mppi/cost_map.hpp"
#include "dynamics/autorally_nn.hpp"
#include "dynamics/kinematic_bicycle.hpp"
#include "dynamics/single_track.hpp"
#include "factory/make_controller.hpp"
#include "vulkan/vulkan_backend.hpp"
#include "mppi/controller.hpp"
#include "vulkan/vulkan_test_util.hpp"

namespace {

std::string data(const std::string& rel) { return std::string(MPPI_TEST_DATA_DIR) + "/" + rel; }

const mppi::AutoRallyCost& gazebo_cost() {
  static const mppi::AutoRallyCost cost(std::make_shared<const mppi::CostMap>(
      mppi::CostMap::load_npz(data("autorally/maps/gazebo/gazebo_costmap.npz"))));
  return cost;
}

mppi::ControllerOptions parity_options(int k, int t, mppi::SamplerKind sampler,
                                       std::vector<mppi::ActuatorChannel> actuators = {}) {
  mppi::ControllerOptions o;
  o.actuators = std::move(actuators);
  o.sampler.kind = sampler;
  o.num_samples = k;
  o.horizon = t;
  o.gamma = 0.1f;  // exercise the control cost too
  o.seed = 12345;
  return o;
}

// On the Gazebo centreline heading along the straight at 5 m/s, slightly yawing.
std::vector<float> start_state(int nx) {
  std::vector<float> x(static_cast<std::size_t>(nx), 0.f);
  x[mppi::state::kX] = -8.5f;
  x[mppi::state::kY] = -8.9f;
  x[mppi::state::kYaw] = 2.3561945f;
  x[mppi::state::kVx] = 5.f;
  x[mppi::state::kYawRate] = 0.1f;
  if (nx == mppi::SingleTrack::kNx)
    x[mppi::SingleTrack::kOmegaFront] = x[mppi::SingleTrack::kOmegaRear] =
        5.f / static_cast<float>(mppi::SingleTrackParams{}.wheel_radius_m);
  return x;
}

struct Worst {
  double cost_rel = 0, control = 0, sampled = 0;
  double sampled_first = 0;  // the first step's sampled controls (same nominal plan on both)
  double cost_rel_p99 = 0;   // the 99th percentile of the per-sample cost differences
};

// Two control steps on the CPU and on Vulkan from the same state: compare the sampled
// controls (the device's Philox), the per-sample costs and the returned first control.
// The second step samples around each backend's own updated plan, which differ by the first
// update's rounding (bounded by the first-control check), so the noise itself is compared on
// the first step. A sample whose state comes within float rounding of the AutoRally cost's
// crash threshold can flip the crash indicator on one device only (a jump of
// crash_weight * crash_discount^t in its cost), so the per-sample costs are checked by their
// 99th percentile: at most 1% of the samples may differ by more than 1e-3.
template <class D>
Worst compare(const D& model, int device, int k, int t,
              mppi::SamplerKind sampler = mppi::SamplerKind::kGaussian,
              std::vector<mppi::ActuatorChannel> actuators = {}, int steps = 2) {
  const mppi::ControllerOptions o = parity_options(k, t, sampler, std::move(actuators));
  mppi::Controller cpu = mppi::make_cpu_controller(model, gazebo_cost(), o);
  std::string why;
  const auto twin = mppi::vulkan::twin_of(model, &why);
  REQUIRE(twin);
  mppi::Controller gpu(std::make_unique<mppi::vulkan::VulkanBackend>(*twin, gazebo_cost(), k, t,
                                                                     o.dt_s, device),
                       o);
  Worst w;
  const std::vector<float> x0 = start_state(D::kNx);
  for (int step = 0; step < steps; ++step) {
    mppi::StepSummary sc, sg;
    const auto uc = cpu.step(x0, &sc);
    const std::vector<float> u_cpu(uc.begin(), uc.end());
    const auto ug = gpu.step(x0, &sg);
    REQUIRE(sc.status == mppi::StepStatus::kOk);
    REQUIRE(sg.status == mppi::StepStatus::kOk);
    CHECK(sg.valid_samples == sc.valid_samples);
    const auto vc = cpu.sampled_controls();
    const auto vg = gpu.sampled_controls();
    REQUIRE(vg.size() == vc.size());
    for (int r = 0; r < t * D::kNu; ++r)
      for (int j = 0; j < k; ++j) {
        const std::size_t i = static_cast<std::size_t>(r) * cpu.backend().shape().padded_samples + j;
        w.sampled = std::max(w.sampled, static_cast<double>(std::abs(vc[i] - vg[i])));
        if (step == 0) w.sampled_first = std::max(w.sampled_first, static_cast<double>(std::abs(vc[i] - vg[i])));
      }
    const auto cc = cpu.sampled_costs();
    const auto cg = gpu.sampled_costs();
    REQUIRE(cg.size() == static_cast<std::size_t>(k));
    std::vector<double> rels(static_cast<std::size_t>(k));
    for (int j = 0; j < k; ++j) {
      const double rel = std::abs(static_cast<double>(cc[j]) - cg[j]) / std::max(1.0, std::abs(static_cast<double>(cc[j])));
      w.cost_rel = std::max(w.cost_rel, rel);
      rels[static_cast<std::size_t>(j)] = rel;
    }
    std::sort(rels.begin(), rels.end());
    w.cost_rel_p99 = std::max(w.cost_rel_p99, rels[static_cast<std::size_t>(k) * 99 / 100]);
    for (int c = 0; c < D::kNu; ++c)
      w.control = std::max(w.control, static_cast<double>(std::abs(u_cpu[c] - ug[c])));
    CHECK(sg.effective_sample_size == Approx(sc.effective_sample_size).epsilon(1e-2));
  }
  return w;
}

template <class D>
void check_parity(const D& model, const char* name) {
  const int device = mppi::test::vulkan_test_device();
  if (device < 0) return;
  for (const int t : {100, 500}) {
    const int k = t == 100 ? 1000 : 333;  // neither is a multiple of the workgroup size (64)
    const Worst w = compare(model, device, k, t);
    INFO(name << ": K = " << k << ", T = " << t << ": worst cost rel. diff " << w.cost_rel
              << " (99th percentile " << w.cost_rel_p99 << "), first-control diff " << w.control
              << ", sampled-control diff " << w.sampled << " (first step " << w.sampled_first << ")");
    CHECK(w.sampled_first <= 1e-6);  // same Philox numbers (last-bit differences from FMA only)
    CHECK(w.sampled <= 1e-4);        // + the plans' difference after one update
    CHECK(w.cost_rel_p99 <= 1e-3);   // (the worst sample may have flipped a crash indicator)
    CHECK(w.control <= 1e-4);
  }
}

}  // namespace

TEST_CASE("Vulkan parity: the low-pass and smooth samplers draw the CPU's numbers", "[vulkan][parity][sampler]") {
  const int device = mppi::test::vulkan_test_device();
  if (device < 0) return;
  for (auto kind : {mppi::SamplerKind::kLowPass, mppi::SamplerKind::kSmooth}) {
    const Worst w = compare(mppi::KinematicBicycle{}, device, 1000, 500, kind);
    INFO(mppi::sampler_name(kind) << ": worst cost rel. diff " << w.cost_rel << " (99th percentile "
                                  << w.cost_rel_p99 << "), first-control diff " << w.control
                                  << ", sampled-control diff " << w.sampled << " (first step " << w.sampled_first << ")");
    // The recursion carries last-bit differences (FMA) along 500 steps: a few ulp of eps.
    CHECK(w.sampled_first <= 1e-5);
    CHECK(w.sampled <= 1e-4);
    CHECK(w.cost_rel_p99 <= 1e-3);
    CHECK(w.control <= 1e-4);
  }
}

TEST_CASE("Vulkan parity: rollouts through the actuators' delay, rate limit and lag", "[vulkan][parity][actuators]") {
  const int device = mppi::test::vulkan_test_device();
  if (device < 0) return;
  // Steering: 3 steps of delay, a slew of 4 / s and a 50-ms lag; throttle: 2 steps of delay
  // alone. Over 4 steps the commands in flight are the controller's own earlier commands.
  const std::vector<mppi::ActuatorChannel> chain = {{0.06f, 0.05f, 4.f}, {0.04f, 0.f, 0.f}};
  const int k = 1000, t = 500;
  const Worst w = compare(mppi::SingleTrack{}, device, k, t, mppi::SamplerKind::kGaussian, chain, 4);
  INFO("worst cost rel. diff " << w.cost_rel << " (99th percentile " << w.cost_rel_p99
                               << "), first-control diff " << w.control << ", sampled-control diff " << w.sampled);
  CHECK(w.sampled_first <= 1e-6);
  CHECK(w.sampled <= 1e-4);
  CHECK(w.cost_rel_p99 <= 1e-3);
  CHECK(w.control <= 1e-4);

  // The chain changes the costs (so the comparison above would see a shader that ignored it):
  // the same first step without it differs in most samples.
  const mppi::ControllerOptions with = parity_options(k, t, mppi::SamplerKind::kGaussian, chain);
  const mppi::ControllerOptions without = parity_options(k, t, mppi::SamplerKind::kGaussian);
  mppi::Controller a = mppi::make_cpu_controller(mppi::SingleTrack{}, gazebo_cost(), with);
  mppi::Controller b = mppi::make_cpu_controller(mppi::SingleTrack{}, gazebo_cost(), without);
  const std::vector<float> x0 = start_state(mppi::SingleTrack::kNx);
  a.step(x0);
  b.step(x0);
  int differ = 0;
  for (int j = 0; j < k; ++j)
    differ += std::abs(a.sampled_costs()[j] - b.sampled_costs()[j]) > 1e-2f * std::max(1.f, std::abs(b.sampled_costs()[j]));
  CHECK(differ > k / 2);
}

TEST_CASE("Vulkan parity: Tube-MPPI and Robust MPPI sample on the GPU, linearise on the CPU", "[vulkan][parity][tube]") {
  const int device = mppi::test::vulkan_test_device();
  if (device < 0) return;
  const int k = 1000, t = 100;
  for (auto variant : {mppi::ControllerVariant::kTube, mppi::ControllerVariant::kRobust}) {
    mppi::ControllerOptions o = parity_options(k, t, mppi::SamplerKind::kGaussian);
    o.variant = variant;
    o.tube_reset_distance = 5.f;
    mppi::Controller cpu = mppi::make_cpu_controller(mppi::SingleTrack{}, gazebo_cost(), o);
    std::string why;
    const auto twin = mppi::vulkan::twin_of(mppi::SingleTrack{}, &why);
    REQUIRE(twin);
    // Without a feedback backend the GPU backend cannot serve a tube variant.
    CHECK_THROWS_WITH(mppi::Controller(std::make_unique<mppi::vulkan::VulkanBackend>(*twin, gazebo_cost(), k, t, o.dt_s, device), o),
                      Catch::Contains("linearises its model"));
    mppi::Controller gpu(std::make_unique<mppi::vulkan::VulkanBackend>(*twin, gazebo_cost(), k, t, o.dt_s, device), o,
                         std::make_unique<mppi::CpuBackend<mppi::SingleTrack, mppi::AutoRallyCost>>(
                             mppi::SingleTrack{}, gazebo_cost(), 64, t, o.dt_s, 1));
    // The measured state drifts from the nominal one (a lateral push), so the feedback acts.
    std::vector<float> x = start_state(mppi::SingleTrack::kNx);
    double worst_control = 0, worst_gain = 0, worst_state = 0;
    int applied = 0;
    for (int step = 0; step < 4; ++step) {
      x[mppi::state::kY] += 0.05f;
      mppi::StepSummary sc, sg;
      const auto uc = cpu.step(x, &sc);
      const std::vector<float> u_cpu(uc.begin(), uc.end());
      const auto ug = gpu.step(x, &sg);
      REQUIRE(sg.status == mppi::StepStatus::kOk);
      CHECK(sg.nominal_reset == sc.nominal_reset);
      CHECK(sg.tube_distance == Approx(sc.tube_distance).margin(1e-4));
      applied += sg.feedback_applied && sc.feedback_applied;
      for (int c = 0; c < 2; ++c) worst_control = std::max(worst_control, static_cast<double>(std::abs(u_cpu[c] - ug[c])));
      const auto gc = cpu.feedback_gains();
      const auto gg = gpu.feedback_gains();
      REQUIRE(gc.size() == gg.size());
      for (std::size_t i = 0; i < gc.size(); ++i)
        worst_gain = std::max(worst_gain, std::abs(static_cast<double>(gc[i]) - gg[i]) / std::max(1.0, std::abs(static_cast<double>(gc[i]))));
      const auto nc = cpu.nominal_states();
      const auto ng = gpu.nominal_states();
      for (std::size_t i = 0; i < nc.size(); ++i)
        worst_state = std::max(worst_state, std::abs(static_cast<double>(nc[i]) - ng[i]) / std::max(1.0, std::abs(static_cast<double>(nc[i]))));
    }
    INFO(mppi::variant_name(variant) << ": control diff " << worst_control << ", gain rel. diff " << worst_gain
                                      << ", nominal-state rel. diff " << worst_state);
    CHECK(applied == 4);
    CHECK(worst_control <= 1e-3);
    CHECK(worst_gain <= 1e-2);
    CHECK(worst_state <= 1e-3);

    // make_controller() gives a tube variant on Vulkan its CPU feedback backend.
    mppi::BackendReport report;
    mppi::Controller made = mppi::make_controller(mppi::SingleTrack{}, gazebo_cost(), o, mppi::BackendChoice::kVulkan, &report);
    CHECK(report.backend == "vulkan");
    mppi::StepSummary sm;
    made.step(start_state(mppi::SingleTrack::kNx), &sm);
    CHECK(sm.status == mppi::StepStatus::kOk);
  }
}

TEST_CASE("Vulkan parity: kinematic bicycle, AutoRally cost", "[vulkan][parity]") {
  check_parity(mppi::KinematicBicycle{}, "kinematic");
}

TEST_CASE("Vulkan parity: AutoRally network, AutoRally cost", "[vulkan][parity]") {
  check_parity(mppi::AutoRallyNetwork::load(data("autorally/models/autorally_nnet_09_12_2018.npz")),
               "network");
}

// A GPU reads the network's weights from workgroup memory (copied there once per workgroup);
// a CPU driver from the uniform buffer. Each path is checked against the CPU backend wherever
// the tests run: MPPI_VULKAN_WEIGHTS_IN_SHARED selects the other one.
TEST_CASE("Vulkan parity: AutoRally network with its weights in workgroup memory and in the uniform buffer",
          "[vulkan][parity]") {
  const char* before = std::getenv("MPPI_VULKAN_WEIGHTS_IN_SHARED");
  const std::string restore = before ? before : "";
  const auto net = mppi::AutoRallyNetwork::load(data("autorally/models/autorally_nnet_09_12_2018.npz"));
  for (const char* shared : {"1", "0"}) {
    INFO("MPPI_VULKAN_WEIGHTS_IN_SHARED=" << shared);
    setenv("MPPI_VULKAN_WEIGHTS_IN_SHARED", shared, 1);
    check_parity(net, shared[0] == '1' ? "network, weights in workgroup memory" : "network, weights in the uniform buffer");
  }
  if (before) setenv("MPPI_VULKAN_WEIGHTS_IN_SHARED", restore.c_str(), 1);
  else unsetenv("MPPI_VULKAN_WEIGHTS_IN_SHARED");
}

TEST_CASE("Vulkan parity: single-track Pacejka model, AutoRally cost", "[vulkan][parity]") {
  check_parity(mppi::SingleTrack{}, "single-track");
}

TEST_CASE("Vulkan parity: single-track with per-axle tyres, AutoRally cost", "[vulkan][parity]") {
  mppi::SingleTrackParams p;  // the rear tyre differs in all three of B, C, D
  p.rear_tyre_B_scale = 1.3;
  p.rear_tyre_C_scale = 0.8;
  p.rear_tyre_D_scale = 0.9;
  check_parity(mppi::SingleTrack{p}, "single-track, per-axle tyres");
}

TEST_CASE("Vulkan parity: single-track with four-wheel drive, AutoRally cost", "[vulkan][parity]") {
  mppi::SingleTrackParams p;  // 40 % of the motor torque on the front axle
  p.front_drive_share = 0.4;
  check_parity(mppi::SingleTrack{p}, "single-track, four-wheel drive");
}

TEST_CASE("Vulkan rollout() of given controls equals the CPU backend's", "[vulkan][parity]") {
  const int device = mppi::test::vulkan_test_device();
  if (device < 0) return;
  const auto net = mppi::AutoRallyNetwork::load(data("autorally/models/autorally_nnet_09_12_2018.npz"));
  const int k = 200, t = 500;
  mppi::CpuBackend<mppi::AutoRallyNetwork, mppi::AutoRallyCost> cpu(net, gazebo_cost(), k, t, 0.02f, 0);
  mppi::vulkan::VulkanBackend gpu(*mppi::vulkan::twin_of(net, nullptr), gazebo_cost(), k, t, 0.02f, device);
  const int padded = cpu.shape().padded_samples;
  REQUIRE(gpu.shape().padded_samples == padded);
  // Smooth, distinct control sequences: a slow steering sine per sample, constant throttle.
  std::vector<float> v(static_cast<std::size_t>(t) * 2 * padded, 0.f);
  for (int s = 0; s < t; ++s)
    for (int j = 0; j < padded; ++j) {
      v[(static_cast<std::size_t>(s) * 2 + 0) * padded + j] = 0.4f * std::sin(0.01f * s * (1 + j % 7) + j);
      v[(static_cast<std::size_t>(s) * 2 + 1) * padded + j] = 0.2f + 0.002f * (j % 50);
    }
  const std::vector<float> x0 = start_state(7);
  std::vector<float> cc(padded), cg(padded);
  cpu.rollout(x0, v, cc);
  gpu.rollout(x0, v, cg);
  for (int j = 0; j < k; ++j) {
    INFO("sample " << j);
    REQUIRE(std::isfinite(cg[j]));
    CHECK(cg[j] == Approx(cc[j]).epsilon(1e-3));
  }
}
