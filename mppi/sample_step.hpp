#pragma once
// Sampling of two time steps for a chunk of W samples: V = clamp(U_t + std * n) per channel
// with the Philox normals of mppi/noise.hpp (one Philox call per lane and channel pair serves
// both steps), and the control-cost term of each lane, for the CPU backend's fused iteration
// (detail::iterate_chunk) and Controller's sampling pass (detail::sample_chunk), so both draw
// bit for bit the same controls and sum the control cost in the same order.
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "base/fast_math.hpp"
#include "mppi/noise.hpp"
#include "mppi/sampler.hpp"

namespace mppi::detail {

// The most control channels a sampler filters (the size of its per-lane state).
inline constexpr int kMaxNoiseChannels = 8;

// Samples [k0, k0 + W) at steps t + s, s in [0, steps) (t even, steps 1 or 2), channels
// [0, nu): v[s * v_step_stride + c * v_stride + j] = clamp(u_{t+s,c} + on_j * std_c * eps), with
// on_j = 0 for the lanes j >= valid_lanes (padding: they get no noise); acc[j] += the control
// cost gamma * u / std_c^2 * (v - u), summed per channel pair, then step, then channel.
// eps is the white normal n, or the filter's recursion over n (mppi/sampler.hpp) whose state
// per lane is eps_state[c * W + j], carried from one call to the next (read only for t > 0).
// nominal_t: the controls of U from step t on (nu per step).
template <int W>
inline void sample_step_pair(const NoiseKey& key, std::uint32_t iteration, int k0,
                             float valid_lanes, int t, int steps, int nu, const float* nominal_t,
                             const float* noise_std, const float* lo, const float* hi,
                             float gamma, const NoiseFilter& filter, float* eps_state, float* v,
                             std::size_t v_stride, std::size_t v_step_stride, float* acc) noexcept {
  const bool white = filter.white();
  alignas(64) float normals[4 * W];
  for (int c0 = 0; c0 < nu; c0 += 2) {
    normal_block<W>(key, iteration, static_cast<std::uint32_t>(k0), static_cast<std::uint32_t>(t / 2),
                    static_cast<std::uint32_t>(c0 / 2), normals, steps);
    const int n = std::min(2, nu - c0);
    for (int s = 0; s < steps; ++s)
      for (int i = 0; i < n; ++i) {
        const int c = c0 + i;
        const float u = nominal_t[s * nu + c];
        const float sd = noise_std[c];
        const float inv_var = 1.f / (sd * sd);
        const float lo_c = lo[c], hi_c = hi[c];
        const float* nc = normals + (2 * s + i) * W;
        if (!white) {  // nc <- the filtered noise, kept as the lane's state
          float* ec = eps_state + c * W;
          float* filtered = normals + (2 * s + i) * W;
          if (t + s == 0) {
            const float g0 = filter.first_gain;
            MPPI_SIMD_LOOP
            for (int j = 0; j < W; ++j) filtered[j] = ec[j] = g0 * nc[j];
          } else {
            const float a = filter.carry, g = filter.gain;
            MPPI_SIMD_LOOP
            for (int j = 0; j < W; ++j) filtered[j] = ec[j] = a * ec[j] + g * nc[j];
          }
        }
        float* vc = v + static_cast<std::size_t>(s) * v_step_stride + static_cast<std::size_t>(c) * v_stride;
        MPPI_SIMD_LOOP
        for (int j = 0; j < W; ++j) {
          const float on = static_cast<float>(j) < valid_lanes ? 1.f : 0.f;
          const float vj = clampf(u + on * sd * nc[j], lo_c, hi_c);
          vc[j] = vj;
          acc[j] += gamma * u * inv_var * (vj - u);
        }
      }
  }
}

}  // namespace mppi::detail
