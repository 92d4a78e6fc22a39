// mppi-bench: what one MPPI control step with the AutoRally network costs on this CPU, how far
// it is from the bare limit of the network's arithmetic, and which part dominates.
//
//   BM_MppiIteration/threads:N/bf16:B  one controller.step(x0): sampling + rollouts + weights +
//                                update (AutoRally network, AutoRallyCost on the Gazebo cost map,
//                                K = 1920, T = 100, 1 iteration); B = 1: the network's hidden
//                                layers in bf16 (AutoRallyNetwork::set_precision), 0: FP32
//   BM_VariantIteration/threads:N/variant:V  the same step for each controller variant, to be
//                                read as a ratio to variant 0 of the same run: 0 plain, 1 low-pass
//                                sampling, 2 derivative-space (smooth) sampling, 3 adaptive
//                                temperature (ESS 10 % of K), 4 actuator-aware (steering delay
//                                0.04 s, lag 0.1 s, 5/s; throttle 10/s), 5 Tube-MPPI, 6 Robust
//                                MPPI (nominal-state choice + feedback), 7 Robust MPPI with
//                                augmented sampling (the real system rolled out in every sample)
//   BM_MppiContention/threads:N/busy:B/schedule:S  the same step while B busy processes (started
//                                and stopped by the benchmark) share the CPU; S: 0 work stealing
//                                (oneTBB, the default), 1 OpenMP dynamic, 2 OpenMP static
//   BM_StepLatency/threads:N/steps:M/schedule:S  p50, p99 and max of M step() wall times
//   BM_BareLimit/threads:N/bf16:B  the network alone over the same K x T, hand-tuned
//                                (bare_limit.hpp; B = 1: bare_limit_bf16.cpp)
//   BM_NetworkForward/kernel:M   Mlp::forward<64> alone, one chunk x T steps; M: 0 portable,
//                                1 AVX-512 FP32, 2 AVX-512 bf16 (dynamics/mlp.hpp)
//   BM_NoiseSampling/threads:N   drawing the K x T x 2 clamped perturbed controls
//   BM_NetworkRollout/threads:N/bf16:B  backend rollout, network + kinematics, cost = 0
//   BM_Rollout/threads:N/bf16:B  backend rollout, network + AutoRallyCost (what step() runs)
//   BM_CostMapLookup/threads:N   K x T cost-map lookups (nearest pixel, clamped, as the cost does)
// N is the OpenMP thread count. Times are wall-clock (UseRealTime). items = K*T rollout steps.
// Standard Google Benchmark flags: --benchmark_format=json, --benchmark_out=FILE,
// --benchmark_repetitions=N, --benchmark_filter=REGEX. The JSON context has the CPU (Google
// Benchmark's own fields plus cpu_model, dispatch_isa, compiler, flags, omp_max_threads).
// Before the benchmarks, a one-off check prints (stderr) that the bare kernel matches a naive
// double-precision reference, and exits 1 if it does not.
#include <benchmark/benchmark.h>
#include <omp.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bare_limit.hpp"
#include "parts.hpp"
#include "costs/autorally_cost.hpp"
#include "dynamics/autorally_nn.hpp"
#include "mppi/controller.hpp"
#include "mppi/cost_map.hpp"
#include "mppi/cpu_backend.hpp"
#include "mppi/noise.hpp"

namespace {

constexpr int kSamples = 1920;  // K (AutoRally's)
constexpr int kHorizon = 100;   // T
constexpr float kDt = 0.02f;

std::string data_path(const std::string& relative) {
  return std::string(MPPI_BENCH_DATA_DIR) + "/" + relative;
}
const char* const kNetworkFile = "autorally/models/autorally_nnet_09_12_2018.npz";
const char* const kCostMapFile = "autorally/maps/gazebo/gazebo_costmap.npz";

// On the Gazebo track centreline (channel0 = 0 for 7 m ahead), heading along the straight
// (north-west, 135 deg) at 5 m/s.
mppi::VehicleState start_state() {
  mppi::VehicleState s;
  s.x_m = -8.5f;
  s.y_m = -8.9f;
  s.yaw_rad = 2.3561945f;
  s.vx_mps = 5.f;
  return s;
}

const mppi::AutoRallyNetwork& network() {
  static const mppi::AutoRallyNetwork net = mppi::AutoRallyNetwork::load(data_path(kNetworkFile));
  return net;
}
// The network in FP32 or with bf16 hidden layers; false if this CPU cannot run bf16.
bool network_with_precision(bool bf16, mppi::AutoRallyNetwork* net) {
  *net = network();
  return net->set_precision(bf16 ? mppi::NetPrecision::kBf16 : mppi::NetPrecision::kFp32);
}
const std::shared_ptr<const mppi::CostMap>& cost_map() {
  static const std::shared_ptr<const mppi::CostMap> map =
      std::make_shared<const mppi::CostMap>(mppi::CostMap::load_npz(data_path(kCostMapFile)));
  return map;
}
mppi::AutoRallyCost make_cost() { return mppi::AutoRallyCost(cost_map()); }

mppi::ControllerOptions options(int threads) {
  mppi::ControllerOptions o;  // AutoRally's defaults: K = 1920, T = 100, dt = 0.02, 1 iteration
  o.num_samples = kSamples;
  o.horizon = kHorizon;
  o.dt_s = kDt;
  o.iterations = 1;
  o.num_threads = threads;
  return o;
}

std::vector<float> model_state(const mppi::AutoRallyNetwork& net, const mppi::VehicleState& s) {
  std::vector<float> x(mppi::AutoRallyNetwork::kNx, 0.f);
  net.init_state(s, x.data());
  return x;
}

void set_rate_counters(benchmark::State& state, int threads) {
  const double steps = static_cast<double>(kSamples) * kHorizon;
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * kSamples * kHorizon);
  state.counters["threads"] = threads;
  state.counters["K"] = kSamples;
  state.counters["T"] = kHorizon;
  // wall time per rollout step (one sample, one time step), all threads together
  state.counters["time_per_step"] =
      benchmark::Counter(steps, benchmark::Counter::kIsIterationInvariantRate |
                                    benchmark::Counter::kInvert);
}

// A running cost of zero: the rollout is then the network and kinematics only.
struct ZeroCost {
  template <int Nx, int Nu, int W>
  void accumulate(mppi::ConstBatch<Nx, W>, mppi::ConstBatch<Nu, W>, int, float*) const noexcept {}
};

// Sampled controls as the controller draws them (T x nu x padded), for the rollout benchmarks.
std::vector<float> sampled_controls(int padded) {
  const mppi::ControllerOptions o = options(1);
  const int nu = mppi::AutoRallyNetwork::kNu;
  std::vector<float> nominal(static_cast<std::size_t>(kHorizon) * nu, 0.f);
  for (int t = 0; t < kHorizon; ++t) nominal[t * nu + 1] = 0.3f;  // some throttle
  std::vector<float> controls(nominal.size() * padded), control_cost(padded);
  for (int k0 = 0; k0 < padded; k0 += mppi::kChunk)
    mppi::detail::sample_chunk(mppi::NoiseKey{o.seed}, 0, k0, kSamples, padded, kHorizon, nu,
                               nominal.data(), o.noise_std.data(), o.control_min.data(),
                               o.control_max.data(), o.gamma, controls.data(), control_cost.data());
  return controls;
}

// ---- 1. the full control step ------------------------------------------------------------
// Times controller.step() from the start state (after 3 warm-up steps); the last summary.
mppi::StepSummary time_steps(benchmark::State& state, mppi::Controller& controller, int threads) {
  const std::vector<float> x0 = model_state(network(), start_state());
  mppi::StepSummary summary;
  for (int i = 0; i < 3; ++i) controller.step(x0, &summary);  // warm caches and thread pool
  for (auto _ : state) {
    auto u = controller.step(x0, &summary);
    benchmark::DoNotOptimize(u.data());
    benchmark::ClobberMemory();
  }
  set_rate_counters(state, threads);
  return summary;
}

void BM_MppiIteration(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  mppi::AutoRallyNetwork net = network();
  if (!network_with_precision(state.range(1) != 0, &net)) return state.SkipWithError("no AVX512-BF16");
  mppi::Controller controller = mppi::make_cpu_controller(net, make_cost(), options(threads));
  const mppi::StepSummary summary = time_steps(state, controller, threads);
  state.counters["min_cost"] = summary.min_cost;
  state.counters["ess"] = summary.effective_sample_size;
  state.counters["valid"] = summary.valid_samples;
  if (summary.status != mppi::StepStatus::kOk) state.SkipWithError(summary.reason);
}

// One controller.step(x0) of a controller variant (see the list at the top).
void BM_VariantIteration(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  mppi::ControllerOptions o = options(threads);
  switch (state.range(1)) {
    case 1: o.sampler.kind = mppi::SamplerKind::kLowPass; break;
    case 2: o.sampler.kind = mppi::SamplerKind::kSmooth; break;
    case 3: o.temperature.ess_share = 0.1f; break;
    case 4: o.actuators = {{0.04f, 0.1f, 5.f}, {0.f, 0.f, 10.f}}; break;
    case 5: o.variant = mppi::ControllerVariant::kTube; break;
    case 6: o.variant = mppi::ControllerVariant::kRobust; break;
    case 7:
      o.variant = mppi::ControllerVariant::kRobust;
      o.robust_augmented_sampling = true;
      break;
    default: break;
  }
  mppi::Controller controller = mppi::make_cpu_controller(network(), make_cost(), o);
  const mppi::StepSummary summary = time_steps(state, controller, threads);
  state.counters["ess"] = summary.effective_sample_size;
  state.counters["lambda"] = summary.lambda;
  if (summary.status != mppi::StepStatus::kOk) state.SkipWithError(summary.reason);
}

// ---- 1b. the step under a shared CPU, and its latency distribution ------------------------
// Busy processes that compete for the cores while a benchmark runs: started by the benchmark,
// killed when it ends.
class BusyProcesses {
 public:
  explicit BusyProcesses(int count) {
    for (int i = 0; i < count; ++i) {
      const pid_t pid = fork();
      if (pid == 0) {
        volatile std::uint64_t spin = 0;
        for (;;) spin = spin + 1;  // until killed
      }
      if (pid > 0) pids_.push_back(pid);
    }
    if (count > 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));  // let them start
  }
  ~BusyProcesses() {
    for (pid_t pid : pids_) kill(pid, SIGKILL);
    for (pid_t pid : pids_) waitpid(pid, nullptr, 0);
  }
  BusyProcesses(const BusyProcesses&) = delete;
  BusyProcesses& operator=(const BusyProcesses&) = delete;

 private:
  std::vector<pid_t> pids_;
};

// 0 work stealing (oneTBB, the default), 1 OpenMP dynamic, 2 OpenMP static
mppi::ThreadSchedule schedule_arg(std::int64_t arg) {
  return arg == 0 ? mppi::ThreadSchedule::kWorkStealing
                  : arg == 1 ? mppi::ThreadSchedule::kDynamic : mppi::ThreadSchedule::kStatic;
}

// One controller.step(x0) while `busy` other processes spin on the machine.
void BM_MppiContention(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  mppi::ControllerOptions o = options(threads);
  o.schedule = schedule_arg(state.range(2));
  mppi::Controller controller = mppi::make_cpu_controller(network(), make_cost(), o);
  const std::vector<float> x0 = model_state(network(), start_state());
  mppi::StepSummary summary;
  for (int i = 0; i < 3; ++i) controller.step(x0, &summary);
  const BusyProcesses busy(static_cast<int>(state.range(1)));
  for (auto _ : state) {
    auto u = controller.step(x0, &summary);
    benchmark::DoNotOptimize(u.data());
    benchmark::ClobberMemory();
  }
  set_rate_counters(state, threads);
}

// The distribution of step() wall times over many steps (quiet machine): p50, p99, max [ms].
void BM_StepLatency(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const int steps = static_cast<int>(state.range(1));
  mppi::ControllerOptions o = options(threads);
  o.schedule = schedule_arg(state.range(2));
  mppi::Controller controller = mppi::make_cpu_controller(network(), make_cost(), o);
  const std::vector<float> x0 = model_state(network(), start_state());
  mppi::StepSummary summary;
  for (int i = 0; i < 3; ++i) controller.step(x0, &summary);
  std::vector<double> ms(static_cast<std::size_t>(steps));
  for (auto _ : state) {
    for (int i = 0; i < steps; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      auto u = controller.step(x0, &summary);
      benchmark::DoNotOptimize(u.data());
      ms[static_cast<std::size_t>(i)] =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    }
  }
  std::sort(ms.begin(), ms.end());
  auto at = [&](double q) { return ms[static_cast<std::size_t>(q * (ms.size() - 1))]; };
  state.counters["p50_ms"] = at(0.5);
  state.counters["p99_ms"] = at(0.99);
  state.counters["max_ms"] = ms.back();
  state.counters["p99_over_p50"] = at(0.99) / at(0.5);
}

// ---- 2. the bare limit ---------------------------------------------------------------------
const mppi::bench::MlpWeights& mlp_weights() {
  static const mppi::bench::MlpWeights w = mppi::bench::load_mlp_weights(data_path(kNetworkFile));
  return w;
}

void BM_BareLimit(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const bool bf16 = state.range(1) != 0;
  if (bf16 && !mppi::bench::BareLimit::bf16_supported()) return state.SkipWithError("no AVX512-BF16");
  mppi::bench::BareLimit bare(mlp_weights(), kSamples, kHorizon, kDt, threads, bf16);
  bare.run();
  for (auto _ : state) {
    bare.run();
    benchmark::ClobberMemory();
  }
  set_rate_counters(state, threads);
  // 6x32 + 32x32 + 32x4 multiply-adds and 64 tanh per rollout step
  state.counters["GFMA"] = benchmark::Counter(
      1344.0 * kSamples * kHorizon * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["checksum"] = bare.checksum();
}

// ---- 3. the parts --------------------------------------------------------------------------
void BM_NoiseSampling(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const mppi::ControllerOptions o = options(threads);
  const int nu = mppi::AutoRallyNetwork::kNu;
  const int padded = mppi::padded_sample_count(kSamples);
  std::vector<float> nominal(static_cast<std::size_t>(kHorizon) * nu, 0.1f);
  std::vector<float> controls(nominal.size() * padded), control_cost(padded);
  std::uint32_t iteration = 0;
  for (auto _ : state) {
    // exactly what Controller::sample does
    const int chunks = padded / mppi::kChunk;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int c = 0; c < chunks; ++c)
      mppi::detail::sample_chunk(mppi::NoiseKey{o.seed}, iteration, c * mppi::kChunk, kSamples,
                                 padded, kHorizon, nu, nominal.data(), o.noise_std.data(),
                                 o.control_min.data(), o.control_max.data(), o.gamma,
                                 controls.data(), control_cost.data());
    ++iteration;
    benchmark::ClobberMemory();
  }
  set_rate_counters(state, threads);
}

template <class Cost>
void run_rollout(benchmark::State& state, Cost cost) {
  const int threads = static_cast<int>(state.range(0));
  mppi::AutoRallyNetwork net = network();
  if (!network_with_precision(state.range(1) != 0, &net)) return state.SkipWithError("no AVX512-BF16");
  mppi::CpuBackend<mppi::AutoRallyNetwork, Cost> backend(net, std::move(cost), kSamples, kHorizon,
                                                         kDt, threads);
  const int padded = backend.shape().padded_samples;
  const std::vector<float> controls = sampled_controls(padded);
  const std::vector<float> x0 = model_state(network(), start_state());
  std::vector<float> costs(padded);
  backend.rollout(x0, controls, costs);
  for (auto _ : state) {
    backend.rollout(x0, controls, costs);
    benchmark::DoNotOptimize(costs.data());
    benchmark::ClobberMemory();
  }
  set_rate_counters(state, threads);
}
void BM_NetworkRollout(benchmark::State& state) { run_rollout(state, ZeroCost{}); }
void BM_Rollout(benchmark::State& state) { run_rollout(state, make_cost()); }

// One chunk of 64 lanes through the network T times (the inputs stay: only the kernel is timed).
void BM_NetworkForward(benchmark::State& state) {
  mppi::Mlp net = network().network();
  const auto kernel = static_cast<mppi::MlpKernel>(state.range(0));
  if (!net.set_kernel(kernel)) return state.SkipWithError("this CPU cannot run the kernel");
  constexpr int W = mppi::kChunk;
  std::vector<float> in(static_cast<std::size_t>(net.num_inputs()) * W), out(4 * W),
      scratch(net.scratch_floats(W));
  for (int j = 0; j < W; ++j) {
    const float a = static_cast<float>(j) / W;
    const float row[6] = {0.02f * (a - 0.5f), 4.f + 6.f * a, 0.4f * (a - 0.5f), 1.f - 2.f * a, 0.8f - 1.6f * a, 0.5f * a};
    for (int i = 0; i < 6; ++i) in[static_cast<std::size_t>(i) * W + j] = row[i];
  }
  for (auto _ : state) {
    for (int t = 0; t < kHorizon; ++t) net.forward<W>(in.data(), out.data(), scratch.data());
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * W * kHorizon);
  state.counters["ns_per_sample"] = benchmark::Counter(
      static_cast<double>(W) * kHorizon, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_CostMapLookup(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  // K x T positions: a fan of trajectories from the start state, like the sampled rollouts'.
  const int padded = mppi::padded_sample_count(kSamples);
  std::vector<float> xs(static_cast<std::size_t>(kHorizon) * padded),
      ys(static_cast<std::size_t>(kHorizon) * padded);
  const mppi::VehicleState s0 = start_state();
  for (int k = 0; k < padded; ++k) {
    const float curvature = -0.4f + 0.8f * static_cast<float>(k % 193) / 192.f;
    for (int t = 0; t < kHorizon; ++t) {
      const float dist = s0.vx_mps * kDt * static_cast<float>(t + 1);
      const float yaw = s0.yaw_rad + curvature * dist;
      xs[static_cast<std::size_t>(t) * padded + k] = s0.x_m + dist * std::cos(yaw);
      ys[static_cast<std::size_t>(t) * padded + k] = s0.y_m + dist * std::sin(yaw);
    }
  }
  const mppi::CostMap& map = *cost_map();
  std::vector<float> acc(padded);
  for (auto _ : state) {
    const int chunks = padded / mppi::kChunk;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int c = 0; c < chunks; ++c)
      mppi::bench::cost_map_chunk(map, xs.data(), ys.data(), padded, kHorizon, c * mppi::kChunk,
                                  acc.data());
    benchmark::DoNotOptimize(acc.data());
    benchmark::ClobberMemory();
  }
  set_rate_counters(state, threads);
}

void thread_args(benchmark::internal::Benchmark* b) {
  b->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);
}
// threads x network precision (0 FP32, 1 bf16)
void thread_precision_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"threads", "bf16"})->ArgsProduct({{1, 2}, {0, 1}})->UseRealTime()->Unit(benchmark::kMillisecond);
}
BENCHMARK(BM_MppiIteration)->Apply(thread_precision_args);
BENCHMARK(BM_VariantIteration)
    ->ArgNames({"threads", "variant"})
    ->ArgsProduct({{1, 2}, {0, 1, 2, 3, 4, 5, 6, 7}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
// threads x busy processes x schedule (0 work stealing, 1 OpenMP dynamic, 2 OpenMP static)
BENCHMARK(BM_MppiContention)
    ->ArgNames({"threads", "busy", "schedule"})
    ->ArgsProduct({{1, 2}, {0, 1, 2}, {0, 1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StepLatency)
    ->ArgNames({"threads", "steps", "schedule"})
    ->ArgsProduct({{1, 2}, {10000}, {0, 1, 2}})
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BareLimit)->Apply(thread_precision_args);
BENCHMARK(BM_NetworkForward)->ArgName("kernel")->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_NoiseSampling)->Apply(thread_args);
BENCHMARK(BM_NetworkRollout)->Apply(thread_precision_args);
BENCHMARK(BM_Rollout)->Apply(thread_precision_args);
BENCHMARK(BM_CostMapLookup)->Apply(thread_args);

// A field of the first processor in /proc/cpuinfo ("model name", "cpu family", ...).
std::string cpuinfo(const std::string& key) {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind(key, 0) == 0 && line.find(':') != std::string::npos) {
      const auto colon = line.find(':');
      const auto start = line.find_first_not_of(" \t", colon + 1);
      return start == std::string::npos ? std::string() : line.substr(start);
    }
  return "unknown";
}

// The bare kernel must do the real network arithmetic: compare lanes against a naive
// double-precision reference after 1 step and after T steps. Returns false on a mismatch.
// bf16: the bf16 kernel, against the same FP64 reference with the tolerance `tol`.
bool check_bare_limit(bool bf16, double tol, std::string* report) {
  mppi::bench::BareLimit bare(mlp_weights(), kSamples, kHorizon, kDt, 1, bf16);
  double worst = 0.0;
  char buf[256];
  std::string text;
  for (const int steps : {1, kHorizon}) {
    bare.run_steps(steps);
    for (const int k : {0, 1, 17, 63, 64, 777, kSamples - 1}) {
      const std::vector<double> ref = bare.reference(k, steps);
      for (int s = 0; s < 4; ++s) {
        const double err = std::abs(bare.final_state(s, k) - ref[s]) / (1.0 + std::abs(ref[s]));
        worst = std::max(worst, err);
      }
    }
    std::snprintf(buf, sizeof buf,
                  "  after %3d steps, lane 777: fast (%.6f, %.6f, %.6f, %.6f) ref (%.6f, %.6f, "
                  "%.6f, %.6f)\n",
                  steps, bare.final_state(0, 777), bare.final_state(1, 777),
                  bare.final_state(2, 777), bare.final_state(3, 777), bare.reference(777, steps)[0],
                  bare.reference(777, steps)[1], bare.reference(777, steps)[2],
                  bare.reference(777, steps)[3]);
    text += buf;
  }
  const bool ok = worst < tol;
  std::snprintf(buf, sizeof buf, "bare-limit%s check vs naive double reference (7 lanes, 1 and %d steps): "
                "max rel. error %.2e (limit %.0e) -> %s\n", bf16 ? " bf16" : "", kHorizon, worst, tol,
                ok ? "PASS" : "FAIL");
  *report = std::string(buf) + text;
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  std::string check;
  bool ok = false;
  try {
    // bf16: 2^-9 rounding of the hidden activations and weights; measured 1.7e-2 after 100 steps
    // (2 s open loop: the states drift apart), while a packing error gives O(1)
    std::string check_bf16;
    ok = check_bare_limit(false, 1e-4, &check) &&
         (!mppi::bench::BareLimit::bf16_supported() || check_bare_limit(true, 5e-2, &check_bf16));
    check += check_bf16;
    network();
    cost_map();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mppi-bench: %s\n", e.what());
    return 1;
  }
  std::fputs(check.c_str(), stderr);
  if (!ok) return 1;
  benchmark::AddCustomContext("cpu_model", cpuinfo("model name"));
  benchmark::AddCustomContext("cpu_family_model_stepping", cpuinfo("cpu family") + " / " +
                                                               cpuinfo("model\t") + " / " +
                                                               cpuinfo("stepping"));
  benchmark::AddCustomContext("dispatch_isa", mppi::bench::BareLimit::dispatched_isa());
#if defined(__clang__)
  benchmark::AddCustomContext("compiler", "Clang " __clang_version__);
#else
  benchmark::AddCustomContext("compiler", "GCC " __VERSION__);
#endif
  benchmark::AddCustomContext("cxx_flags", MPPI_BENCH_CXX_FLAGS);
  benchmark::AddCustomContext("cmake_build_type", MPPI_BENCH_BUILD_TYPE);
  benchmark::AddCustomContext("omp_max_threads", std::to_string(omp_get_max_threads()));
  benchmark::AddCustomContext("network", kNetworkFile);
  benchmark::AddCustomContext("cost_map", kCostMapFile);
  benchmark::AddCustomContext("K", std::to_string(kSamples));
  benchmark::AddCustomContext("T", std::to_string(kHorizon));
  benchmark::AddCustomContext("bare_check", check.substr(0, check.find('\n')));
  benchmark::AddCustomContext(
      "library_build_type_note",
      "library_build_type is how Google Benchmark itself was built (Debian's package says "
      "debug); the measured code is built as cmake_build_type with cxx_flags");
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
