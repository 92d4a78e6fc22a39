#pragma once
// Counter-based Gaussian noise: Philox4x32-10 (Salmon et al., SC'11, the generator of
// Random123) keyed by the seed, with counter (sample, step pair, iteration, channel pair), so
// every draw depends only on its own indices: the same numbers whatever the thread count, and
// the same on the GPU. Each Philox call gives 4 words -> 2 Box-Muller pairs: words 0 and 1 give
// channels 2b and 2b + 1 at the even step 2p, words 2 and 3 the same channels at step 2p + 1
// (counter (sample, p, iteration, b)), so a model with 2 controls needs one call per two steps.
// Written lane-wise so a batch of samples vectorises; tests check it against Random123's own
// philox4x32 and the normal distribution. On x86-64 the Philox words come from AVX-512 / AVX2
// code when the CPU has it (the very same words, see detail::philox_words_dispatch).
#include <bit>
#include <cmath>
#include <cstdint>
#include <utility>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#endif

#include "base/batch.hpp"
#include "base/fast_math.hpp"

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

namespace detail {
// sin and cos of 2 pi u, u in [0, 1): fast_sincos_turns's reduction and polynomials, so the
// same numbers (tests compare all 2^24 values Box-Muller passes), with the quarter-turn rotation
// done by integer bit operations (a swap mask and sign flips) instead of chained selects: fewer
// vector instructions per lane.
inline void sincos_turns(float u, float* sin_out, float* cos_out) noexcept {
  const float q = static_cast<float>(static_cast<int>(u * 4.f + 0.5f));
  const float r = (u - 0.25f * q) * 6.28318530718f;
  const float r2 = r * r;
  const float s = r * (1.f + r2 * (-1.f / 6 + r2 * (1.f / 120 + r2 * (-1.f / 5040 + r2 * (1.f / 362880)))));
  const float c = 1.f + r2 * (-0.5f + r2 * (1.f / 24 + r2 * (-1.f / 720 + r2 * (1.f / 40320))));
  // q = 0: (sin, cos) = (s, c); 1: (c, -s); 2: (-s, -c); 3: (-c, s)
  const auto qi = static_cast<std::uint32_t>(static_cast<int>(q));
  const std::uint32_t swap = 0u - (qi & 1u);  // all ones when q is odd
  const std::uint32_t bs = std::bit_cast<std::uint32_t>(s), bc = std::bit_cast<std::uint32_t>(c);
  *sin_out = std::bit_cast<float>(((bs & ~swap) | (bc & swap)) ^ ((qi & 2u) << 30));
  *cos_out = std::bit_cast<float>(((bc & ~swap) | (bs & swap)) ^ (((qi + 1u) & 2u) << 30));
}
}  // namespace detail

// Two standard normals from two random words (Box-Muller). u1 in (0, 1) so log is finite.
inline void box_muller(std::uint32_t a, std::uint32_t b, float* n0, float* n1) noexcept {
  const float u1 = (static_cast<float>(a >> 8) + 0.5f) * (1.f / 16777216.f);
  const float u2 = static_cast<float>(b >> 8) * (1.f / 16777216.f);
  const float r = std::sqrt(-2.f * fast_log(u1));
  float s, c;
  detail::sincos_turns(u2, &s, &c);
  *n0 = r * c;
  *n1 = r * s;
}

namespace detail {
// Philox4x32-10 of the counters (first + j, t, iteration, block), j in [0, W), key (k0, k1):
// word w of lane j -> words[w * W + j]. Portable lane loop; the SIMD versions below give the
// same words (integer arithmetic, exact).
template <int W>
inline void philox_words(std::uint32_t k0, std::uint32_t k1, std::uint32_t iteration,
                         std::uint32_t first, std::uint32_t t, std::uint32_t block,
                         std::uint32_t* words) noexcept {
  MPPI_SIMD_LOOP
  for (int j = 0; j < W; ++j) {
    std::uint32_t c0 = first + static_cast<std::uint32_t>(j), c1 = t, c2 = iteration, c3 = block;
    philox4x32_10(c0, c1, c2, c3, k0, k1);
    words[0 * W + j] = c0;
    words[1 * W + j] = c1;
    words[2 * W + j] = c2;
    words[3 * W + j] = c3;
  }
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(MPPI_NO_SIMD_PHILOX)
#define MPPI_SIMD_PHILOX 1
// GCC 12's own avx512fintrin.h trips -Wmaybe-uninitialized (its _mm512_undefined_* helpers).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
// The auto-vectorised loop above widens every 32 x 32 -> 64-bit product to 64-bit lanes; these
// keep 32-bit lanes (mullo for the low words, two vpmuludq + a shuffle/blend for the high
// words). The AVX-512 one is 2.2x faster per word than the auto-vectorised loop on Zen 5. The
// path is chosen at run time (philox_words_dispatch), so the library still runs on any x86-64.

// The high words of c * m on 16 lanes: vpmuludq on the even lanes and on the odd lanes
// shuffled down, the even products' high halves shuffled back into place under a mask.
__attribute__((target("avx512f"), always_inline)) inline __m512i philox_hi16(__m512i c, __m512i m) noexcept {
  const __m512i even = _mm512_mul_epu32(c, m);
  const __m512i odd = _mm512_mul_epu32(_mm512_shuffle_epi32(c, _MM_PERM_DDBB), m);
  return _mm512_mask_shuffle_epi32(odd, 0x5555, even, _MM_PERM_DDBB);
}

// One Philox round on 16 lanes.
struct Philox16 {
  __m512i c0, c1, c2, c3;
};
__attribute__((target("avx512f"), always_inline)) inline void philox_round16(
    Philox16& p, __m512i m0, __m512i m1, __m512i ka, __m512i kb) noexcept {
  const __m512i hi0 = philox_hi16(p.c0, m0);
  const __m512i hi1 = philox_hi16(p.c2, m1);
  const __m512i lo0 = _mm512_mullo_epi32(p.c0, m0);
  const __m512i lo1 = _mm512_mullo_epi32(p.c2, m1);
  p.c0 = _mm512_ternarylogic_epi32(hi1, p.c1, ka, 0x96);  // hi1 ^ c1 ^ k0
  p.c2 = _mm512_ternarylogic_epi32(hi0, p.c3, kb, 0x96);  // hi0 ^ c3 ^ k1
  p.c1 = lo1;
  p.c3 = lo0;
}

// Rounds 1 and 2 for the counters (c0 + lane, t, iteration, block): only c0 differs between
// lanes, so round 1's product of c2 and round 2's product of c0 are the same in every lane and
// are done once, in scalar code (the same words, fewer vector multiplies).
__attribute__((target("avx512f"), always_inline)) inline Philox16 philox_head16(
    __m512i c0, std::uint32_t t, std::uint32_t iteration, std::uint32_t block, std::uint32_t k0,
    std::uint32_t k1, __m512i m0) noexcept {
  // round 1: c0' = hi(M1 c2) ^ c1 ^ k0 and c1' = lo(M1 c2) are uniform
  const std::uint64_t p1 = static_cast<std::uint64_t>(kPhiloxM1) * iteration;
  const std::uint32_t c0_1 = static_cast<std::uint32_t>(p1 >> 32) ^ t ^ k0;
  const std::uint32_t c1_1 = static_cast<std::uint32_t>(p1);
  const __m512i c2_1 = _mm512_xor_si512(philox_hi16(c0, m0), _mm512_set1_epi32(static_cast<int>(block ^ k1)));
  const __m512i c3_1 = _mm512_mullo_epi32(c0, m0);
  // round 2: the product of c0' is uniform
  const std::uint32_t ka = k0 + kPhiloxW0, kb = k1 + kPhiloxW1;
  const __m512i m1 = _mm512_set1_epi32(static_cast<int>(kPhiloxM1));
  const __m512i hi1 = philox_hi16(c2_1, m1);
  const std::uint64_t p0 = static_cast<std::uint64_t>(kPhiloxM0) * c0_1;
  Philox16 r;
  r.c0 = _mm512_xor_si512(hi1, _mm512_set1_epi32(static_cast<int>(c1_1 ^ ka)));
  r.c1 = _mm512_mullo_epi32(c2_1, m1);
  r.c2 = _mm512_ternarylogic_epi32(c3_1, _mm512_set1_epi32(static_cast<int>(static_cast<std::uint32_t>(p0 >> 32))),
                                   _mm512_set1_epi32(static_cast<int>(kb)), 0x96);
  r.c3 = _mm512_set1_epi32(static_cast<int>(static_cast<std::uint32_t>(p0)));
  return r;
}

// Rounds 1 .. `rounds` of two interleaved 16-lane streams (interleaved to hide the multiplies'
// latency): a for the counters (first + lane, t, iteration, block), b for first + 16 + lane.
// ka, kb: the keys of the next round.
__attribute__((target("avx512f"), always_inline)) inline void philox_first_rounds16(
    std::uint32_t k0, std::uint32_t k1, std::uint32_t iteration, std::uint32_t first, std::uint32_t t,
    std::uint32_t block, int rounds, __m512i m0, __m512i m1, Philox16& a, Philox16& b, std::uint32_t& ka,
    std::uint32_t& kb) noexcept {
  const __m512i lane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  a = philox_head16(_mm512_add_epi32(_mm512_set1_epi32(static_cast<int>(first)), lane), t, iteration, block, k0, k1, m0);
  b = philox_head16(_mm512_add_epi32(_mm512_set1_epi32(static_cast<int>(first + 16u)), lane), t, iteration, block, k0,
                    k1, m0);
  ka = k0 + 2 * kPhiloxW0;
  kb = k1 + 2 * kPhiloxW1;
  for (int r = 2; r < rounds; ++r) {
    const __m512i bka = _mm512_set1_epi32(static_cast<int>(ka));
    const __m512i bkb = _mm512_set1_epi32(static_cast<int>(kb));
    philox_round16(a, m0, m1, bka, bkb);
    philox_round16(b, m0, m1, bka, bkb);
    ka += kPhiloxW0;
    kb += kPhiloxW1;
  }
}

// lanes: a multiple of 32.
__attribute__((target("avx512f"))) inline void philox_words_avx512(
    std::uint32_t k0, std::uint32_t k1, std::uint32_t iteration, std::uint32_t first,
    std::uint32_t t, std::uint32_t block, int lanes, std::uint32_t* words) noexcept {
  const __m512i m0 = _mm512_set1_epi32(static_cast<int>(kPhiloxM0));
  const __m512i m1 = _mm512_set1_epi32(static_cast<int>(kPhiloxM1));
  for (int v = 0; v < lanes; v += 32) {
    Philox16 a, b;
    std::uint32_t ka, kb;
    philox_first_rounds16(k0, k1, iteration, first + static_cast<std::uint32_t>(v), t, block, 10, m0, m1, a, b, ka, kb);
    for (const auto& [p, off] : {std::pair<const Philox16&, int>{a, v}, {b, v + 16}}) {
      _mm512_storeu_si512(words + 0 * lanes + off, p.c0);
      _mm512_storeu_si512(words + 1 * lanes + off, p.c1);
      _mm512_storeu_si512(words + 2 * lanes + off, p.c2);
      _mm512_storeu_si512(words + 3 * lanes + off, p.c3);
    }
  }
}

// Words 0 and 1 only (words + 0 * lanes, words + 1 * lanes; the same as philox_words_avx512's),
// for the last step of an odd horizon, whose Box-Muller pair uses only those. The last three
// rounds skip what cannot reach them: round 10 needs only c1, c2 of round 9; round 9 gives c1
// and c2 from c0, c2, c3 of round 8, which needs no c1.
// lanes: a multiple of 32.
__attribute__((target("avx512f"))) inline void philox_words01_avx512(
    std::uint32_t k0, std::uint32_t k1, std::uint32_t iteration, std::uint32_t first,
    std::uint32_t t, std::uint32_t block, int lanes, std::uint32_t* words) noexcept {
  const __m512i m0 = _mm512_set1_epi32(static_cast<int>(kPhiloxM0));
  const __m512i m1 = _mm512_set1_epi32(static_cast<int>(kPhiloxM1));
  for (int v = 0; v < lanes; v += 32) {
    Philox16 a, b;
    std::uint32_t ka, kb;
    philox_first_rounds16(k0, k1, iteration, first + static_cast<std::uint32_t>(v), t, block, 7, m0, m1, a, b, ka, kb);
    const __m512i ka8 = _mm512_set1_epi32(static_cast<int>(ka));
    const __m512i kb8 = _mm512_set1_epi32(static_cast<int>(kb));
    const __m512i kb9 = _mm512_set1_epi32(static_cast<int>(kb + kPhiloxW1));
    const __m512i ka10 = _mm512_set1_epi32(static_cast<int>(ka + 2 * kPhiloxW0));
    for (Philox16* p : {&a, &b}) {
      // round 8: c0, c2, c3
      const __m512i c0_8 = _mm512_ternarylogic_epi32(philox_hi16(p->c2, m1), p->c1, ka8, 0x96);
      const __m512i c2_8 = _mm512_ternarylogic_epi32(philox_hi16(p->c0, m0), p->c3, kb8, 0x96);
      const __m512i c3_8 = _mm512_mullo_epi32(p->c0, m0);
      // round 9: c1, c2
      const __m512i c1_9 = _mm512_mullo_epi32(c2_8, m1);
      const __m512i c2_9 = _mm512_ternarylogic_epi32(philox_hi16(c0_8, m0), c3_8, kb9, 0x96);
      // round 10: c0, c1
      p->c0 = _mm512_ternarylogic_epi32(philox_hi16(c2_9, m1), c1_9, ka10, 0x96);
      p->c1 = _mm512_mullo_epi32(c2_9, m1);
    }
    _mm512_storeu_si512(words + 0 * lanes + v, a.c0);
    _mm512_storeu_si512(words + 1 * lanes + v, a.c1);
    _mm512_storeu_si512(words + 0 * lanes + v + 16, b.c0);
    _mm512_storeu_si512(words + 1 * lanes + v + 16, b.c1);
  }
}

// lanes: a multiple of 8.
__attribute__((target("avx2"))) inline void philox_words_avx2(
    std::uint32_t k0, std::uint32_t k1, std::uint32_t iteration, std::uint32_t first,
    std::uint32_t t, std::uint32_t block, int lanes, std::uint32_t* words) noexcept {
  const __m256i m0 = _mm256_set1_epi32(static_cast<int>(kPhiloxM0));
  const __m256i m1 = _mm256_set1_epi32(static_cast<int>(kPhiloxM1));
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  for (int v = 0; v < lanes; v += 8) {
    __m256i c0 = _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(first + static_cast<std::uint32_t>(v))), lane);
    __m256i c1 = _mm256_set1_epi32(static_cast<int>(t));
    __m256i c2 = _mm256_set1_epi32(static_cast<int>(iteration));
    __m256i c3 = _mm256_set1_epi32(static_cast<int>(block));
    std::uint32_t ka = k0, kb = k1;
    for (int r = 0; r < 10; ++r) {
      const __m256i lo0 = _mm256_mullo_epi32(c0, m0);
      const __m256i hi0 = _mm256_blend_epi32(_mm256_srli_epi64(_mm256_mul_epu32(c0, m0), 32),
                                             _mm256_mul_epu32(_mm256_srli_epi64(c0, 32), m0), 0xAA);
      const __m256i lo1 = _mm256_mullo_epi32(c2, m1);
      const __m256i hi1 = _mm256_blend_epi32(_mm256_srli_epi64(_mm256_mul_epu32(c2, m1), 32),
                                             _mm256_mul_epu32(_mm256_srli_epi64(c2, 32), m1), 0xAA);
      c0 = _mm256_xor_si256(_mm256_xor_si256(hi1, c1), _mm256_set1_epi32(static_cast<int>(ka)));
      c2 = _mm256_xor_si256(_mm256_xor_si256(hi0, c3), _mm256_set1_epi32(static_cast<int>(kb)));
      c1 = lo1;
      c3 = lo0;
      ka += kPhiloxW0;
      kb += kPhiloxW1;
    }
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(words + 0 * lanes + v), c0);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(words + 1 * lanes + v), c1);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(words + 2 * lanes + v), c2);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(words + 3 * lanes + v), c3);
  }
}

// 2: AVX-512F, 1: AVX2, 0: portable. Decided once per process.
inline int philox_simd_level() noexcept {
  static const int level = __builtin_cpu_supports("avx512f") ? 2 : __builtin_cpu_supports("avx2") ? 1 : 0;
  return level;
}
#pragma GCC diagnostic pop
#endif

// philox_words<W> on the fastest path this CPU has. words_needed = 2: only words 0 and 1 are
// needed (the others may be left unwritten).
template <int W>
inline void philox_words_dispatch(std::uint32_t k0, std::uint32_t k1, std::uint32_t iteration,
                                  std::uint32_t first, std::uint32_t t, std::uint32_t block,
                                  std::uint32_t* words, int words_needed = 4) noexcept {
  (void)words_needed;
#ifdef MPPI_SIMD_PHILOX
  if constexpr (W % 8 == 0) {
    const int level = philox_simd_level();
    if (W % 32 == 0 && level == 2) {
      if (words_needed <= 2) return philox_words01_avx512(k0, k1, iteration, first, t, block, W, words);
      return philox_words_avx512(k0, k1, iteration, first, t, block, W, words);
    }
    if (level >= 1) return philox_words_avx2(k0, k1, iteration, first, t, block, W, words);
  }
#endif
  philox_words<W>(k0, k1, iteration, first, t, block, words);
}
}  // namespace detail

// Standard normals for W consecutive samples starting at `first_sample`, at iteration
// `iteration`, steps 2 * step_pair and 2 * step_pair + 1, channels 2 * channel_pair and
// 2 * channel_pair + 1: out[(2 * s + i) * W + lane] is step 2 * step_pair + s, channel
// 2 * channel_pair + i (one Philox call per lane). steps = 1 gives the first step only (its
// Box-Muller pair uses words 0 and 1 only, so the last step of an odd horizon skips half the
// work).
template <int W>
inline void normal_block(const NoiseKey& key, std::uint32_t iteration, std::uint32_t first_sample,
                         std::uint32_t step_pair, std::uint32_t channel_pair, float* out,
                         int steps = 2) noexcept {
  alignas(64) std::uint32_t words[4 * W];
  detail::philox_words_dispatch<W>(static_cast<std::uint32_t>(key.seed),
                                   static_cast<std::uint32_t>(key.seed >> 32), iteration,
                                   first_sample, step_pair, channel_pair, words, 2 * steps);
  MPPI_SIMD_LOOP
  for (int j = 0; j < W; ++j) box_muller(words[j], words[W + j], &out[0 * W + j], &out[1 * W + j]);
  if (steps > 1) {
    MPPI_SIMD_LOOP
    for (int j = 0; j < W; ++j)
      box_muller(words[2 * W + j], words[3 * W + j], &out[2 * W + j], &out[3 * W + j]);
  }
}

// One normal, scalar: the reference the batched paths must reproduce exactly.
inline float normal_at(const NoiseKey& key, std::uint32_t iteration, std::uint32_t sample,
                       std::uint32_t t, int channel) noexcept {
  const auto pair = static_cast<std::uint32_t>(channel / 2);
  std::uint32_t c[4] = {sample, t / 2, iteration, pair};
  philox4x32_10(c, static_cast<std::uint32_t>(key.seed), static_cast<std::uint32_t>(key.seed >> 32));
  const int w = 2 * static_cast<int>(t % 2);  // words 0, 1 for an even step, 2, 3 for an odd one
  float n[2];
  box_muller(c[w], c[w + 1], &n[0], &n[1]);
  return n[channel % 2];
}

}  // namespace mppi
