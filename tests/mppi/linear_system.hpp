#pragma once
// A double integrator with a quadratic cost, as an mppi::Dynamics / mppi::StageCost pair, for
// tests that compare MPPI with closed forms.
#include "base/batch.hpp"

namespace mppi::test {

struct DoubleIntegrator {
  static constexpr int kNx = 2;  // position [m], velocity [m/s]
  static constexpr int kNu = 1;  // acceleration [m/s^2]
  std::size_t scratch_floats(int) const { return 0; }
  template <int W>
  void step(Batch<kNx, W> x, ConstBatch<kNu, W> u, float dt, float*) const noexcept {
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) {
      x[0][j] += dt * x[1][j];
      x[1][j] += dt * u[0][j];
    }
  }
};

// q = qp p^2 + qv v^2 + r u^2 on the state after the step.
struct QuadraticCost {
  float qp = 1.f, qv = 0.1f, r = 0.05f;
  template <int Nx, int Nu, int W>
  void accumulate(ConstBatch<Nx, W> x, ConstBatch<Nu, W> u, int, float* cost) const noexcept {
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j)
      cost[j] += qp * x[0][j] * x[0][j] + qv * x[1][j] * x[1][j] + r * u[0][j] * u[0][j];
  }
};

}  // namespace mppi::test
