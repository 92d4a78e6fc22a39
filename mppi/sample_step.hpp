#pragma once
// Sampling of one time step for a chunk of W samples: V = clamp(U_t + std * n) per channel
// with the Philox normals of mppi/noise.hpp, and the control-cost term of each lane, for the CPU
// backend's fused iteration (detail::iterate_chunk) and Controller's sampling pass
// (detail::sample_chunk), so both draw bit for bit the same controls.
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "mppi/fast_math.hpp"
#include "mppi/noise.hpp"

namespace mppi::detail {

// Samples [k0, k0 + W) at step t, channels [c0, c0 + n) (c0 a multiple of 4, n <= 4: one
// Philox block): v[(c - c0) * v_stride + j] = clamp(u_c + on_j * std_c * n), with on_j = 0 for the
// lanes j >= valid_lanes (padding: they get no noise); acc[j] += the control cost
// gamma * u_c / std_c^2 * (v - u_c) summed over those c. nominal_t: the controls of U at step t.
template <int W>
inline void sample_step_block(const NoiseKey& key, std::uint32_t iteration, int k0,
                              float valid_lanes, int t, int c0, int n, const float* nominal_t,
                              const float* noise_std, const float* lo, const float* hi,
                              float gamma, float* v, std::size_t v_stride, float* acc) noexcept {
  alignas(64) float normals[4 * W];
  normal_block<W>(key, iteration, static_cast<std::uint32_t>(k0), static_cast<std::uint32_t>(t),
                  static_cast<std::uint32_t>(c0 / 4), normals, n > 2 ? 2 : 1);
  for (int i = 0; i < n; ++i) {
    const int c = c0 + i;
    const float u = nominal_t[c];
    const float sd = noise_std[c];
    const float inv_var = 1.f / (sd * sd);
    const float* nc = normals + i * W;
    float* vc = v + static_cast<std::size_t>(i) * v_stride;
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j) {
      const float on = static_cast<float>(j) < valid_lanes ? 1.f : 0.f;
      const float vj = clampf(u + on * sd * nc[j], lo[c], hi[c]);
      vc[j] = vj;
      acc[j] += gamma * u * inv_var * (vj - u);
    }
  }
}

}  // namespace mppi::detail
