#include "parts.hpp"

#include <algorithm>
#include <cstddef>

#include "base/batch.hpp"
#include "base/multiversion.hpp"

namespace mppi::bench {

MPPI_MULTIVERSION void cost_map_chunk(const CostMap& map, const float* xs, const float* ys,
                                      int padded, int horizon, int k0, float* acc) noexcept {
  constexpr int W = kChunk;
  const CostMap::View view = map.view();
  float sum[W] = {};
  for (int t = 0; t < horizon; ++t) {
    const float* x = xs + static_cast<std::size_t>(t) * padded + k0;
    const float* y = ys + static_cast<std::size_t>(t) * padded + k0;
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) sum[j] += view.lookup(x[j], y[j]);
  }
  std::copy_n(sum, W, acc + k0);
}

}  // namespace mppi::bench
