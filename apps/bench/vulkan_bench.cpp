// Vulkan backend benchmarks (registered into mppi-bench), K sweep 128 ... 16384 at T = 100,
// AutoRally network + AutoRallyCost on the Gazebo map, start state as BM_MppiIteration:
//   BM_VulkanIteration/K:k      one controller.step(x0) on Vulkan: device Philox noise,
//                               rollouts, weights and weighted sum, plus the host's share
//                               (uniform/plan upload, submit, wait, read-back of K costs)
//   BM_VulkanIterationKinematic/K:k   the same with the kinematic bicycle (closest to the
//                               published MPPI-Generic benchmark problem: simple kinematics
//                               and a cost-map cost, T = 100)
//   BM_VulkanRollout/K:k        backend rollout() of host-given controls (upload included)
//   BM_CpuIterationSweep/K:k    the network step on the CPU backend (all OpenMP threads), for
//                               the comparison at equal K (and ...Kinematic)
// Counters: steps_per_s = K*T rollout steps per second of wall time. The device is the one
// --backend vulkan would take (MPPI_VULKAN_DEVICE picks another; lavapipe counts); its name is
// the label and in the JSON context. Without a Vulkan device the Vulkan benchmarks are not
// registered, and a line on stderr says why.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "costs/autorally_cost.hpp"
#include "mppi/cost_map.hpp"
#include "dynamics/autorally_nn.hpp"
#include "dynamics/kinematic_bicycle.hpp"
#include "factory/make_controller.hpp"
#include "vulkan/vulkan_backend.hpp"
#include "mppi/controller.hpp"

namespace {

constexpr int kT = 100;

std::string path(const char* rel) { return std::string(MPPI_BENCH_DATA_DIR) + "/" + rel; }

const mppi::AutoRallyNetwork& net() {
  static const auto n = mppi::AutoRallyNetwork::load(path("autorally/models/autorally_nnet_09_12_2018.npz"));
  return n;
}
const mppi::AutoRallyCost& cost() {
  static const mppi::AutoRallyCost c(std::make_shared<const mppi::CostMap>(
      mppi::CostMap::load_npz(path("autorally/maps/gazebo/gazebo_costmap.npz"))));
  return c;
}
mppi::ControllerOptions opts(int k) {
  mppi::ControllerOptions o;
  o.num_samples = k;
  o.horizon = kT;
  return o;
}
std::vector<float> x0() {  // Gazebo straight, 5 m/s (as mppi_bench.cpp's start_state)
  return {-8.5f, -8.9f, 2.3561945f, 5.f, 0.f, 0.f, 0.f};
}

struct Device {
  int index = -1;
  std::string name, why;
};
const Device& device() {
  static const Device d = [] {
    Device r;
    const mppi::vulkan::Probe p = mppi::vulkan::probe();
    r.index = mppi::vulkan::pick_device(p, /*allow_cpu=*/true, &r.why);
    if (r.index >= 0) r.name = p.devices[r.index].name + " (" + p.devices[r.index].type + ")";
    return r;
  }();
  return d;
}

void counters(benchmark::State& state, int k) {
  state.counters["K"] = k;
  state.counters["T"] = kT;
  state.counters["steps_per_s"] = benchmark::Counter(static_cast<double>(k) * kT,
                                                     benchmark::Counter::kIsIterationInvariantRate);
}

template <class D>
void vulkan_iteration(benchmark::State& state, const D& model) {
  const int k = static_cast<int>(state.range(0));
  mppi::Controller c(std::make_unique<mppi::vulkan::VulkanBackend>(
                         *mppi::vulkan::twin_of(model, nullptr), cost(), k, kT, 0.02f, device().index),
                     opts(k));
  const auto x = x0();
  mppi::StepSummary s;
  c.step(x, &s);
  for (auto _ : state) {
    auto u = c.step(x, &s);
    benchmark::DoNotOptimize(u.data());
  }
  counters(state, k);
  state.counters["ess"] = s.effective_sample_size;
  state.SetLabel(device().name);
  if (s.status != mppi::StepStatus::kOk) state.SkipWithError(s.reason);
}
void BM_VulkanIteration(benchmark::State& state) { vulkan_iteration(state, net()); }
void BM_VulkanIterationKinematic(benchmark::State& state) {
  vulkan_iteration(state, mppi::KinematicBicycle{});
}

void BM_VulkanRollout(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0));
  mppi::vulkan::VulkanBackend b(*mppi::vulkan::twin_of(net(), nullptr), cost(), k, kT, 0.02f,
                                device().index);
  const int padded = b.shape().padded_samples;
  std::vector<float> v(static_cast<std::size_t>(kT) * 2 * padded);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = 0.3f * static_cast<float>((i * 2654435761u) % 1000) / 1000.f;
  std::vector<float> costs(padded);
  const auto x = x0();
  b.rollout(x, v, costs);
  for (auto _ : state) {
    b.rollout(x, v, costs);
    benchmark::DoNotOptimize(costs.data());
  }
  counters(state, k);
  state.SetLabel(device().name);
}

template <class D>
void cpu_iteration(benchmark::State& state, const D& model) {
  const int k = static_cast<int>(state.range(0));
  mppi::Controller c = mppi::make_cpu_controller(model, cost(), opts(k));
  const auto x = x0();
  mppi::StepSummary s;
  c.step(x, &s);
  for (auto _ : state) {
    auto u = c.step(x, &s);
    benchmark::DoNotOptimize(u.data());
  }
  counters(state, k);
}
void BM_CpuIterationSweep(benchmark::State& state) { cpu_iteration(state, net()); }
void BM_CpuIterationSweepKinematic(benchmark::State& state) {
  cpu_iteration(state, mppi::KinematicBicycle{});
}

void sweep(benchmark::internal::Benchmark* b) {
  b->ArgName("K")->RangeMultiplier(2)->Range(128, 16384)->UseRealTime()->Unit(benchmark::kMillisecond);
}

[[maybe_unused]] const bool registered = [] {
  benchmark::RegisterBenchmark("BM_CpuIterationSweep", BM_CpuIterationSweep)->Apply(sweep);
  benchmark::RegisterBenchmark("BM_CpuIterationSweepKinematic", BM_CpuIterationSweepKinematic)->Apply(sweep);
  if (device().index < 0) {
    std::fprintf(stderr, "mppi-bench: Vulkan benchmarks skipped: %s\n", device().why.c_str());
    return false;
  }
  benchmark::AddCustomContext("vulkan_device", device().name);
  benchmark::RegisterBenchmark("BM_VulkanIteration", BM_VulkanIteration)->Apply(sweep);
  benchmark::RegisterBenchmark("BM_VulkanIterationKinematic", BM_VulkanIterationKinematic)->Apply(sweep);
  benchmark::RegisterBenchmark("BM_VulkanRollout", BM_VulkanRollout)->Apply(sweep);
  return true;
}();

}  // namespace
