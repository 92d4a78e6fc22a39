#pragma once
// Jacobians A_t = df/dx, B_t = df/du of a batch model's step x_{t+1} = f(x_t, u_t) along a
// nominal control sequence, by central differences with every perturbation in its own lane:
// one batched step of kChunk lanes gives all columns of A_t and B_t at once.
//
// Lanes of a batch: lane 0 carries the nominal (it rolls the plan out), lanes 1 + 2k and
// 2 + 2k the +h and -h perturbations of variable k (states first, then controls). Central
// differences need 2 (nx + nu) lanes besides the nominal: (kChunk - 2) / 2 = 31 variables per
// batch, enough for every base model here (at most 16 + 2); larger models (a base with the
// actuator-delay chains of with_effects.hpp has 30 + 2) take two batches per step.
// Central rather than forward differences because the step is evaluated in float: the best
// forward difference is only ~sqrt(eps) = 3e-4 accurate, the best central one ~eps^(2/3) = 2e-5.
//
// Step size h = eps^(1/3) max(1, |v|) = 4.9e-3 max(1, |v|) for a variable of value v, so that
// the two errors balance: truncation h^2 |f'''| / 6 (~4e-6 per unit third derivative at unit
// scale) and rounding ~eps |f| / h (~2.4e-5 |f| at unit scale, relative to the variable's
// scale). A column is thus good to a few 1e-5 of the size of the step's result for a smooth,
// well-scaled model. The divisor is the perturbation actually applied, (v + h) - (v - h) taken
// in double from the rounded floats. A model with a kink (a clamp at a control limit) gives the
// mean of the two one-sided slopes there.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "base/batch.hpp"
#include "mppi/concepts.hpp"

namespace mppi {

// Variables (states + controls) perturbed in one batch of kChunk lanes.
inline constexpr int kLinearizeVariablesPerBatch = (kChunk - 1) / 2;

// Floats of scratch linearize_along needs for `model`.
template <Dynamics D>
std::size_t linearize_scratch_floats(const D& model) {
  return static_cast<std::size_t>(D::kNx + D::kNu) * kChunk + model.scratch_floats(kChunk);
}

// Central-difference step for a variable of value v (see the top of the file).
inline float central_difference_step(float v) noexcept {
  const float cbrt_eps = 4.921566e-3f;  // cbrt(FLT_EPSILON) = 2^(-23/3)
  return cbrt_eps * std::max(1.f, std::fabs(v));
}

// Rolls `nominal` (T x nu) out from x0 into states ((T+1) x nx: x0, x1, ..., x_T) and writes
// A ((T x nx x nx): A[(t * nx + i) * nx + j] = dx_{t+1,i} / dx_{t,j}) and B ((T x nx x nu):
// B[(t * nx + i) * nu + c] = dx_{t+1,i} / du_{t,c}), all row-major. scratch:
// linearize_scratch_floats(model) floats. Inputs are not checked (non-finite in, non-finite out).
template <Dynamics D>
void linearize_along(const D& model, const float* x0, const float* nominal, int horizon, float dt_s,
                     float* states, float* A, float* B, float* scratch) noexcept {
  constexpr int W = kChunk;
  constexpr int Nx = D::kNx, Nu = D::kNu, Nv = Nx + Nu;
  constexpr int kBatches = (Nv + kLinearizeVariablesPerBatch - 1) / kLinearizeVariablesPerBatch;
  float* x = scratch;                // Nx x W
  float* u = x + Nx * W;             // Nu x W
  float* model_scratch = u + Nu * W;
  for (int i = 0; i < Nx; ++i) states[i] = x0[i];
  for (int t = 0; t < horizon; ++t) {
    const float* xt = states + static_cast<std::ptrdiff_t>(t) * Nx;
    const float* ut = nominal + static_cast<std::ptrdiff_t>(t) * Nu;
    float* a_t = A + static_cast<std::ptrdiff_t>(t) * Nx * Nx;
    float* b_t = B + static_cast<std::ptrdiff_t>(t) * Nx * Nu;
    for (int batch = 0; batch < kBatches; ++batch) {
      const int v0 = batch * kLinearizeVariablesPerBatch;
      const int count = std::min(kLinearizeVariablesPerBatch, Nv - v0);
      for (int i = 0; i < Nx; ++i) std::fill_n(x + i * W, W, xt[i]);
      for (int c = 0; c < Nu; ++c) std::fill_n(u + c * W, W, ut[c]);
      double divisor[kLinearizeVariablesPerBatch];
      for (int k = 0; k < count; ++k) {
        const int v = v0 + k;
        float* row = v < Nx ? x + v * W : u + (v - Nx) * W;
        const float value = v < Nx ? xt[v] : ut[v - Nx];
        const float h = central_difference_step(value);
        row[1 + 2 * k] = value + h;
        row[2 + 2 * k] = value - h;
        divisor[k] = static_cast<double>(row[1 + 2 * k]) - static_cast<double>(row[2 + 2 * k]);
      }
      model.template step<W>(Batch<Nx, W>{x}, ConstBatch<Nu, W>{u}, dt_s, model_scratch);
      if (batch == 0) {
        float* next = states + static_cast<std::ptrdiff_t>(t + 1) * Nx;
        for (int i = 0; i < Nx; ++i) next[i] = x[i * W];
      }
      for (int k = 0; k < count; ++k) {
        const int v = v0 + k;
        for (int i = 0; i < Nx; ++i) {
          const double d = (static_cast<double>(x[i * W + 1 + 2 * k]) - x[i * W + 2 + 2 * k]) / divisor[k];
          if (v < Nx) a_t[i * Nx + v] = static_cast<float>(d);
          else b_t[i * Nu + (v - Nx)] = static_cast<float>(d);
        }
      }
    }
  }
}

}  // namespace mppi
