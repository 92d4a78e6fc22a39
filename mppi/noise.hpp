#pragma once
// Counter-based Gaussian noise: Philox4x32-10 (Salmon et al., SC'11, the generator of
// Random123) keyed by the seed, with counter (sample, time step, iteration, channel block),
// so every draw depends only on its own indices: the same numbers whatever the thread count,
// and the same on the GPU. Each Philox call gives 4 words -> 2 Box-Muller pairs -> the normals
// of 4 consecutive channels. Written lane-wise so a batch of samples vectorises; tests check it
// against Random123's own philox4x32 and the normal distribution.
#include <cmath>
#include <cstdint>

#include "mppi/batch.hpp"
#include "mppi/fast_math.hpp"

namespace mppi {

struct NoiseKey {
  std::uint64_t seed = 0;
};

namespace detail {
inline constexpr std::uint32_t kPhiloxM0 = 0xD2511F53u;
inline constexpr std::uint32_t kPhiloxM1 = 0xCD9E8D57u;
inline constexpr std::uint32_t kPhiloxW0 = 0x9E3779B9u;  // golden ratio
inline constexpr std::uint32_t kPhiloxW1 = 0xBB67AE85u;  // sqrt(3) - 1

}  // namespace detail

// Philox4x32 with 10 rounds on four scalars (no array, so that a lane loop vectorises).
inline void philox4x32_10(std::uint32_t& c0, std::uint32_t& c1, std::uint32_t& c2,
                          std::uint32_t& c3, std::uint32_t k0, std::uint32_t k1) noexcept {
#pragma GCC unroll 10
  for (int r = 0; r < 10; ++r) {
    const std::uint64_t p0 = static_cast<std::uint64_t>(detail::kPhiloxM0) * c0;
    const std::uint64_t p1 = static_cast<std::uint64_t>(detail::kPhiloxM1) * c2;
    const std::uint32_t n0 = static_cast<std::uint32_t>(p1 >> 32) ^ c1 ^ k0;
    const std::uint32_t n2 = static_cast<std::uint32_t>(p0 >> 32) ^ c3 ^ k1;
    c1 = static_cast<std::uint32_t>(p1);
    c3 = static_cast<std::uint32_t>(p0);
    c0 = n0;
    c2 = n2;
    k0 += detail::kPhiloxW0;
    k1 += detail::kPhiloxW1;
  }
}
// Philox4x32 with 10 rounds: counter c (4 words) -> 4 random words, in place.
inline void philox4x32_10(std::uint32_t c[4], std::uint32_t k0, std::uint32_t k1) noexcept {
  philox4x32_10(c[0], c[1], c[2], c[3], k0, k1);
}

// Two standard normals from two random words (Box-Muller). u1 in (0, 1) so log is finite.
inline void box_muller(std::uint32_t a, std::uint32_t b, float* n0, float* n1) noexcept {
  const float u1 = (static_cast<float>(a >> 8) + 0.5f) * (1.f / 16777216.f);
  const float u2 = static_cast<float>(b >> 8) * (1.f / 16777216.f);
  const float r = std::sqrt(-2.f * fast_log(u1));
  float s, c;
  fast_sincos_turns(u2, &s, &c);
  *n0 = r * c;
  *n1 = r * s;
}

// Standard normals for W consecutive samples starting at `first_sample`, at time step t and
// iteration `iteration`, channels [4*block, 4*block + 4): out[ch * W + lane], ch < 4.
template <int W>
inline void normal_block(const NoiseKey& key, std::uint32_t iteration, std::uint32_t first_sample,
                         std::uint32_t t, std::uint32_t block, float* out) noexcept {
  const auto k0 = static_cast<std::uint32_t>(key.seed);
  const auto k1 = static_cast<std::uint32_t>(key.seed >> 32);
  MPPI_SIMD_LOOP
  for (int j = 0; j < W; ++j) {
    std::uint32_t c0 = first_sample + static_cast<std::uint32_t>(j), c1 = t, c2 = iteration,
                  c3 = block;
    philox4x32_10(c0, c1, c2, c3, k0, k1);
    box_muller(c0, c1, &out[0 * W + j], &out[1 * W + j]);
    box_muller(c2, c3, &out[2 * W + j], &out[3 * W + j]);
  }
}

// One normal, scalar: the reference the batched paths must reproduce exactly.
inline float normal_at(const NoiseKey& key, std::uint32_t iteration, std::uint32_t sample,
                       std::uint32_t t, int channel) noexcept {
  std::uint32_t c[4] = {sample, t, iteration, static_cast<std::uint32_t>(channel / 4)};
  philox4x32_10(c, static_cast<std::uint32_t>(key.seed), static_cast<std::uint32_t>(key.seed >> 32));
  float n[4];
  box_muller(c[0], c[1], &n[0], &n[1]);
  box_muller(c[2], c[3], &n[2], &n[3]);
  return n[channel % 4];
}

}  // namespace mppi
