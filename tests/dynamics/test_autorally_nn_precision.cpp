// The AutoRally network in reduced precision: its FP32 and bf16 kernels against the
// double-precision network (AutoRallyNetwork::derivatives, std::tanh), over a grid of states
// and controls in the paper's 4-10 m/s range: one-step derivatives and 1-s (50-step) open-loop
// predictions. The hidden test "[.precision_table]" prints the table of docs/BENCHMARKS.md
// ("Reduced precision").
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "base/batch.hpp"
#include "dynamics/autorally_nn.hpp"
#include "test_data.hpp"

namespace {

using mppi::AutoRallyNetwork;
using mppi::NetPrecision;
namespace st = mppi::state;
namespace ct = mppi::control;
constexpr int W = mppi::kChunk;

const AutoRallyNetwork& network() {
  static const AutoRallyNetwork net =
      AutoRallyNetwork::load(mppi::test::data_path("autorally/models/autorally_nnet_09_12_2018.npz"));
  return net;
}

struct GridPoint {
  double x[st::kCommonStates];
  double u[2];
};

// vx 4..10 m/s (7), vy -1..1 m/s (5), yaw rate -2..2 rad/s (5), roll -0.05..0.05 rad (3),
// steer -0.8..0.8 (5), throttle -0.2..0.65 (4): 10500 points, padded to whole chunks by repeats.
std::vector<GridPoint> grid() {
  std::vector<GridPoint> g;
  for (int a = 0; a < 7; ++a)
    for (int b = 0; b < 5; ++b)
      for (int c = 0; c < 5; ++c)
        for (int d = 0; d < 3; ++d)
          for (int e = 0; e < 5; ++e)
            for (const double throttle : {-0.2, 0.15, 0.4, 0.65}) {
              GridPoint p{};
              p.x[st::kVx] = 4.0 + a;
              p.x[st::kVy] = -1.0 + 0.5 * b;
              p.x[st::kYawRate] = -2.0 + 1.0 * c;
              p.x[st::kRoll] = -0.05 + 0.05 * d;
              p.u[ct::kSteer] = -0.8 + 0.4 * e;
              p.u[ct::kThrottle] = throttle;
              g.push_back(p);
            }
  const std::size_t n = g.size();
  for (std::size_t i = 0; g.size() % W != 0; ++i) g.push_back(g[i % n]);
  return g;
}

// Error statistics of one quantity against the double reference.
struct Stat {
  double max_abs = 0, sum_sq = 0, ref_sum_sq = 0;
  long n = 0;
  void add(double v, double ref) {
    max_abs = std::max(max_abs, std::abs(v - ref));
    sum_sq += (v - ref) * (v - ref);
    ref_sum_sq += ref * ref;
    ++n;
  }
  double rms() const { return std::sqrt(sum_sq / std::max(1L, n)); }
  double ref_rms() const { return std::sqrt(ref_sum_sq / std::max(1L, n)); }
};

const int kDerivStates[4] = {st::kRoll, st::kVx, st::kVy, st::kYawRate};
const char* const kDerivNames[4] = {"d roll [rad/s]", "d vx [m/s^2]", "d vy [m/s^2]", "d yaw rate [rad/s^2]"};

// One-step derivatives d/dt (roll, vx, vy, yaw rate) of the network at every grid point.
std::vector<Stat> derivative_errors(NetPrecision precision, bool* supported) {
  AutoRallyNetwork net = network();
  *supported = net.set_precision(precision) || precision == NetPrecision::kFp32;
  const mppi::Mlp& mlp = net.network();
  const std::vector<GridPoint> g = grid();
  std::vector<float> in(AutoRallyNetwork::kNetIn * W), out(AutoRallyNetwork::kNetOut * W),
      scratch(mlp.scratch_floats(W));
  std::vector<Stat> stats(4);
  for (std::size_t k0 = 0; k0 < g.size(); k0 += W) {
    for (int j = 0; j < W; ++j) {
      const GridPoint& p = g[k0 + j];
      const double row[6] = {p.x[st::kRoll], p.x[st::kVx], p.x[st::kVy], p.x[st::kYawRate],
                             p.u[ct::kSteer], p.u[ct::kThrottle]};
      for (int i = 0; i < 6; ++i) in[i * W + j] = static_cast<float>(row[i]);
    }
    mlp.forward<W>(in.data(), out.data(), scratch.data());
    for (int j = 0; j < W; ++j) {
      double dx[st::kCommonStates];
      net.derivatives(g[k0 + j].x, g[k0 + j].u, dx);
      for (int o = 0; o < 4; ++o) stats[o].add(out[o * W + j], dx[kDerivStates[o]]);
    }
  }
  return stats;
}

// 1 s open loop (50 Euler steps of 0.02 s, controls held) from every grid point at the origin:
// position [m], speed vx [m/s] and yaw [rad] against the same Euler steps in double.
std::vector<Stat> open_loop_errors(NetPrecision precision) {
  AutoRallyNetwork net = network();
  net.set_precision(precision);
  const std::vector<GridPoint> g = grid();
  constexpr int kSteps = 50;
  constexpr double kDt = 0.02;
  std::vector<float> x(st::kCommonStates * W), u(2 * W), scratch(net.scratch_floats(W));
  std::vector<Stat> stats(3);
  for (std::size_t k0 = 0; k0 < g.size(); k0 += W) {
    std::vector<std::vector<double>> ref(W);
    for (int j = 0; j < W; ++j) {
      const GridPoint& p = g[k0 + j];
      ref[j].assign(p.x, p.x + st::kCommonStates);
      for (int i = 0; i < st::kCommonStates; ++i) x[i * W + j] = static_cast<float>(p.x[i]);
      for (int c = 0; c < 2; ++c) u[c * W + j] = static_cast<float>(p.u[c]);
    }
    for (int t = 0; t < kSteps; ++t) {
      net.step<W>(mppi::Batch<st::kCommonStates, W>{x.data()}, mppi::ConstBatch<2, W>{u.data()},
                  static_cast<float>(kDt), scratch.data());
      for (int j = 0; j < W; ++j) {
        double dx[st::kCommonStates];
        net.derivatives(ref[j].data(), g[k0 + j].u, dx);
        for (int i = 0; i < st::kCommonStates; ++i) ref[j][i] += kDt * dx[i];
      }
    }
    for (int j = 0; j < W; ++j) {
      const double ex = x[st::kX * W + j] - ref[j][st::kX], ey = x[st::kY * W + j] - ref[j][st::kY];
      stats[0].add(std::hypot(ex, ey), 0.0);
      stats[1].add(x[st::kVx * W + j], ref[j][st::kVx]);
      stats[2].add(x[st::kYaw * W + j], ref[j][st::kYaw]);
    }
  }
  return stats;
}

}  // namespace

TEST_CASE("autorally_nn: bf16 derivatives and 1-s predictions stay close to the double network",
          "[nn][precision]") {
  bool supported = false;
  const std::vector<Stat> fp32 = derivative_errors(NetPrecision::kFp32, &supported);
  for (int o = 0; o < 4; ++o) {
    INFO(kDerivNames[o] << ": fp32 max " << fp32[o].max_abs);
    CHECK(fp32[o].max_abs < 3e-5);  // FP32 sums and fast_tanh; observed <= 6.7e-6
  }
  const std::vector<Stat> bf16 = derivative_errors(NetPrecision::kBf16, &supported);
  if (!supported) {
    WARN("no AVX512-BF16 on this CPU: bf16 not tested");
    return;
  }
  // Bounds: about 2x the errors measured on the grid (docs/BENCHMARKS.md, "Reduced precision":
  // max 4.6e-3, 4.3e-2, 6.8e-2, 5.4e-2; rms 1.4e-3, 9.4e-3, 1.7e-2, 1.3e-2).
  const double max_bound[4] = {0.01, 0.09, 0.14, 0.11};
  const double rms_bound[4] = {0.003, 0.02, 0.035, 0.026};
  for (int o = 0; o < 4; ++o) {
    INFO(kDerivNames[o] << ": bf16 max " << bf16[o].max_abs << ", rms " << bf16[o].rms()
                        << " (spread of the value: rms " << bf16[o].ref_rms() << ")");
    CHECK(bf16[o].max_abs < max_bound[o]);
    CHECK(bf16[o].rms() < rms_bound[o]);
    CHECK(bf16[o].max_abs > fp32[o].max_abs);  // it did run in reduced precision
  }
  const std::vector<Stat> loop = open_loop_errors(NetPrecision::kBf16);
  INFO("1 s open loop, bf16: position max " << loop[0].max_abs << " m, rms " << loop[0].rms()
                                             << "; vx max " << loop[1].max_abs << "; yaw max " << loop[2].max_abs);
  CHECK(loop[0].max_abs < 0.05);   // measured 2.6e-2 m
  CHECK(loop[1].max_abs < 0.09);   // 4.2e-2 m/s
  CHECK(loop[2].max_abs < 0.025);  // 1.3e-2 rad
}

TEST_CASE("autorally_nn: the reduced-precision table of docs/BENCHMARKS.md", "[.precision_table]") {
  bool supported = false;
  const std::vector<Stat> fp32 = derivative_errors(NetPrecision::kFp32, &supported);
  const std::vector<Stat> bf16 = derivative_errors(NetPrecision::kBf16, &supported);
  REQUIRE(supported);
  const std::vector<Stat> loop32 = open_loop_errors(NetPrecision::kFp32);
  const std::vector<Stat> loop16 = open_loop_errors(NetPrecision::kBf16);
  std::printf("| quantity | spread (rms) | fp32 - double: max | rms | bf16 - double: max | rms |\n");
  std::printf("|---|---:|---:|---:|---:|---:|\n");
  for (int o = 0; o < 4; ++o)
    std::printf("| %s | %.3g | %.2e | %.2e | %.2e | %.2e |\n", kDerivNames[o], fp32[o].ref_rms(),
                fp32[o].max_abs, fp32[o].rms(), bf16[o].max_abs, bf16[o].rms());
  const char* const names[3] = {"1 s: position [m]", "1 s: vx [m/s]", "1 s: yaw [rad]"};
  for (int i = 0; i < 3; ++i)
    std::printf("| %s | %s | %.2e | %.2e | %.2e | %.2e |\n", names[i], i == 1 ? "" : "", loop32[i].max_abs,
                loop32[i].rms(), loop16[i].max_abs, loop16[i].rms());
}
