// The bf16 variant of the bare limit (bare_limit.hpp): the same 6-32-32-4 rollout with the
// first layer in FP32 FMAs and the other two as vdpbf16ps dot products of bf16 pairs (FP32
// sums), tanh by mppi::fast_tanh_lowp, the layer sizes compile-time constants and every loop
// unrolled. Written with intrinsics under a target attribute; BareLimit only runs it where
// __builtin_cpu_supports("avx512bf16") holds.
#include "bare_limit.hpp"

#include <cstdint>
#include <cstring>

#include "base/fast_math.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"  // GCC 12, _mm512_min/max_ps

namespace mppi::bench::detail {
namespace {

#define BF16_TARGET __attribute__((target("avx512f,avx512bw,avx512dq,avx512vl,avx512bf16,fma")))

constexpr int kW = BareLimit::kLanes;  // 64 lanes = 4 zmm per row
constexpr int kNV = kW / 16;
constexpr int kH = MlpWeights::kHidden;

BF16_TARGET inline __m512 tanh_lowp(__m512 x) {
  const __m512 c = _mm512_set1_ps(kTanhLowpClamp);
  x = _mm512_min_ps(_mm512_max_ps(x, _mm512_sub_ps(_mm512_setzero_ps(), c)), c);
  const __m512 x2 = _mm512_mul_ps(x, x);
  __m512 p = _mm512_fmadd_ps(_mm512_set1_ps(kTanhLowpP[2]), x2, _mm512_set1_ps(kTanhLowpP[1]));
  p = _mm512_mul_ps(_mm512_fmadd_ps(p, x2, _mm512_set1_ps(kTanhLowpP[0])), x);
  const __m512 q = _mm512_fmadd_ps(_mm512_add_ps(x2, _mm512_set1_ps(kTanhLowpQ[1])), x2,
                                   _mm512_set1_ps(kTanhLowpQ[0]));
  return _mm512_div_ps(p, q);
}

// tanh of 4 neurons x 64 lanes, stored as 2 rows of bf16 pairs
BF16_TARGET inline void tanh_to_pairs(__m512 (&acc)[4][kNV], std::uint32_t (*dst)[kW]) {
  const __m512i interleave = _mm512_set_epi16(31, 15, 30, 14, 29, 13, 28, 12, 27, 11, 26, 10, 25, 9, 24, 8,
                                              23, 7, 22, 6, 21, 5, 20, 4, 19, 3, 18, 2, 17, 1, 16, 0);
#pragma GCC unroll 4
  for (int k = 0; k < 4; k += 2)
#pragma GCC unroll 4
    for (int v = 0; v < kNV; ++v) {
      const __m512bh packed = _mm512_cvtne2ps_pbh(tanh_lowp(acc[k + 1][v]), tanh_lowp(acc[k][v]));
      _mm512_storeu_si512(dst[k / 2] + 16 * v, _mm512_permutexvar_epi16(interleave, (__m512i)packed));
    }
}

// acc[o][.] = b[o] + sum_p wp[o][p] . x[p][.] for 4 neurons, over kH / 2 pair rows
BF16_TARGET inline void dot_pairs(const std::uint32_t (*wp)[kH / 2], const float* b,
                                  const std::uint32_t (*x)[kW], __m512 (&acc)[4][kNV]) {
#pragma GCC unroll 4
  for (int o = 0; o < 4; ++o)
#pragma GCC unroll 4
    for (int v = 0; v < kNV; ++v) acc[o][v] = _mm512_set1_ps(b[o]);
#pragma GCC unroll 2
  for (int p = 0; p < kH / 2; ++p) {
    __m512bh xv[kNV];
#pragma GCC unroll 4
    for (int v = 0; v < kNV; ++v) xv[v] = (__m512bh)_mm512_loadu_si512(x[p] + 16 * v);
#pragma GCC unroll 4
    for (int o = 0; o < 4; ++o) {
      const __m512bh w = (__m512bh)_mm512_set1_epi32(static_cast<int>(wp[o][p]));
#pragma GCC unroll 4
      for (int v = 0; v < kNV; ++v) acc[o][v] = _mm512_dpbf16_ps(acc[o][v], xv[v], w);
    }
  }
}

}  // namespace

BF16_TARGET void bare_chunk_bf16(const MlpWeights& w, const BareBf16Weights& wb, const float* init,
                                 float* out, int padded, int k0, int steps, float dt) noexcept {
  alignas(64) float in[MlpWeights::kIn][kW];
  alignas(64) std::uint32_t h1[kH / 2][kW];
  alignas(64) std::uint32_t h2[kH / 2][kW];
  for (int r = 0; r < MlpWeights::kIn; ++r)
    std::memcpy(in[r], init + static_cast<std::size_t>(r) * padded + k0, sizeof in[r]);
  const __m512 dtv = _mm512_set1_ps(dt);
  for (int t = 0; t < steps; ++t) {
    __m512 acc[4][kNV];
#pragma GCC unroll 1
    for (int ob = 0; ob < kH; ob += 4) {  // layer 1: FP32
#pragma GCC unroll 4
      for (int o = 0; o < 4; ++o)
#pragma GCC unroll 4
        for (int v = 0; v < kNV; ++v) acc[o][v] = _mm512_set1_ps(w.b1[ob + o]);
#pragma GCC unroll 6
      for (int i = 0; i < MlpWeights::kIn; ++i) {
        __m512 xv[kNV];
#pragma GCC unroll 4
        for (int v = 0; v < kNV; ++v) xv[v] = _mm512_load_ps(in[i] + 16 * v);
#pragma GCC unroll 4
        for (int o = 0; o < 4; ++o) {
          const __m512 wo = _mm512_set1_ps(w.w1[ob + o][i]);
#pragma GCC unroll 4
          for (int v = 0; v < kNV; ++v) acc[o][v] = _mm512_fmadd_ps(wo, xv[v], acc[o][v]);
        }
      }
      tanh_to_pairs(acc, h1 + ob / 2);
    }
#pragma GCC unroll 1
    for (int ob = 0; ob < kH; ob += 4) {  // layer 2: bf16
      dot_pairs(wb.w2 + ob, w.b2 + ob, h1, acc);
      tanh_to_pairs(acc, h2 + ob / 2);
    }
    dot_pairs(wb.w3, w.b3, h2, acc);  // layer 3: bf16, linear; Euler on the 4 states
#pragma GCC unroll 4
    for (int s = 0; s < MlpWeights::kOut; ++s)
#pragma GCC unroll 4
      for (int v = 0; v < kNV; ++v)
        _mm512_store_ps(in[s] + 16 * v, _mm512_fmadd_ps(dtv, acc[s][v], _mm512_load_ps(in[s] + 16 * v)));
  }
  for (int s = 0; s < MlpWeights::kOut; ++s)
    std::memcpy(out + static_cast<std::size_t>(s) * padded + k0, in[s], sizeof in[s]);
}

bool cpu_has_bf16() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
         __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl") &&
         __builtin_cpu_supports("avx512bf16");
}

}  // namespace mppi::bench::detail

#pragma GCC diagnostic pop

#else

namespace mppi::bench::detail {
void bare_chunk_bf16(const MlpWeights&, const BareBf16Weights&, const float*, float*, int, int, int,
                     float) noexcept {}
bool cpu_has_bf16() { return false; }
}  // namespace mppi::bench::detail

#endif
