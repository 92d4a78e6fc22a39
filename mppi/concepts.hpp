#pragma once
// What the controller asks of a dynamics model and of a running cost. Both work on a
// fixed-width SoA batch (base/batch.hpp) and are called inside the per-sample hot loop:
// no allocation, no exceptions, no virtual calls, branch-free lane loops.
#include <concepts>
#include <cstddef>

#include "base/batch.hpp"
#include "mppi/vehicle_state.hpp"

namespace mppi {

// A dynamics model:
//   static constexpr int kNx, kNu;            // state and control sizes
//   std::size_t scratch_floats(int width) const;  // scratch it needs for `width` lanes
//   template <int W> void step(Batch<kNx,W> x, ConstBatch<kNu,W> u, float dt_s,
//                              float* scratch) const noexcept;   // x <- x(t + dt)
// Vehicle models also give `void init_state(const VehicleState&, float* x) const` (their full
// state from the common one), used by the simulator; generic systems need not.
// Controls reaching step() are already clamped to the controller's limits.
template <class D>
concept Dynamics = requires(const D& d, Batch<D::kNx, kChunk> x, ConstBatch<D::kNu, kChunk> u,
                            float dt, float* scratch) {
  { D::kNx } -> std::convertible_to<int>;
  { D::kNu } -> std::convertible_to<int>;
  { d.scratch_floats(kChunk) } -> std::convertible_to<std::size_t>;
  { d.template step<kChunk>(x, u, dt, scratch) } -> std::same_as<void>;
};

template <class D>
concept VehicleDynamics = Dynamics<D> && D::kNx >= state::kCommonStates &&
                          D::kNu >= control::kCommonControls &&
                          requires(const D& d, const VehicleState& s, float* x) {
                            { d.init_state(s, x) } -> std::same_as<void>;
                          };

// A running cost q(x_t, u_t, t), summed over the horizon:
//   template <int Nx, int Nu, int W> void accumulate(ConstBatch<Nx,W> x, ConstBatch<Nu,W> u,
//                                                    int t, float* cost) const noexcept;
// cost[j] += q for lane j. x is the state after the step that used u (x_{t+1}).
template <class C, class D>
concept StageCost = requires(const C& c, ConstBatch<D::kNx, kChunk> x, ConstBatch<D::kNu, kChunk> u,
                             int t, float* cost) {
  { c.template accumulate<D::kNx, D::kNu, kChunk>(x, u, t, cost) } -> std::same_as<void>;
};

}  // namespace mppi
