#pragma once
// Kernels for the "parts" benchmarks that the library has no public entry point for.
#include "mppi/cost_map.hpp"

namespace mppi::bench {

// acc[k0 + j] = sum over t of map.lookup(xs[t][k0 + j], ys[t][k0 + j]) for the kChunk lanes of
// one chunk; xs, ys: T x padded. The lookup the AutoRally cost does per lane and time step.
void cost_map_chunk(const CostMap& map, const float* xs, const float* ys, int padded, int horizon,
                    int k0, float* acc) noexcept;

}  // namespace mppi::bench
