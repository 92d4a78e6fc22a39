// The AVX-512 forward pass of an Mlp (dynamics/mlp.hpp), included by dynamics/mlp_avx512.cpp
// (FP32) and dynamics/mlp_avx512_bf16.cpp (BF16 dot products) after each defines
// MPPI_MLP_TARGET, the target attribute its functions are compiled for. Everything here has
// internal linkage, so the two translation units' copies (built for different targets) never
// merge at link time. Not a public header.
//
// Blocking: 4 output neurons x 64 lanes (4 zmm) = 16 accumulators in registers, independent
// FMA chains; per input, 4 vector loads and 4 weight broadcasts (vbroadcastss / vpbroadcastd
// from memory) feed 16 FMAs. Remainders: 2 and 1 output neurons, 16-lane
// blocks when the width is not a multiple of 64. The activation is applied to the accumulators
// before they are stored (no second pass over the layer).
//
// BF16 (vdpbf16ps): a layer's input is stored as bf16 pairs, one 32-bit word per (pair p,
// lane j) = (x[2p][j] low half, x[2p+1][j] high half), rows of W words; its weights as the
// matching pairs (w[o][2p], w[o][2p+1]) (Mlp::bf16_weights). One vdpbf16ps then adds both
// products of a pair to 16 FP32 accumulators. The previous layer writes its activations
// straight into this layout (cvtne2ps + a word permute); an odd neuron count pads with 0.
#ifndef MPPI_MLP_TARGET
#error "define MPPI_MLP_TARGET before including mlp_avx512_kernels.hpp"
#endif
#include <immintrin.h>

#include <cstddef>
#include <cstdint>

#include "dynamics/mlp.hpp"

// GCC 12 warns (falsely) that the undefined pass-through vector of _mm512_min/max_ps is used.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace mppi::detail {
namespace {

// mppi::fast_tanh96 ([9/6] rational on a clamped argument, max abs error 4.5e-7).
MPPI_MLP_TARGET inline __m512 tanh_fp32(__m512 x) {
  const __m512 c = _mm512_set1_ps(kTanhClamp);
  x = _mm512_min_ps(_mm512_max_ps(x, _mm512_sub_ps(_mm512_setzero_ps(), c)), c);
  const __m512 x2 = _mm512_mul_ps(x, x);
  __m512 p = _mm512_fmadd_ps(_mm512_set1_ps(kTanhP[4]), x2, _mm512_set1_ps(kTanhP[3]));
  p = _mm512_fmadd_ps(p, x2, _mm512_set1_ps(kTanhP[2]));
  p = _mm512_fmadd_ps(p, x2, _mm512_set1_ps(kTanhP[1]));
  p = _mm512_fmadd_ps(p, x2, _mm512_set1_ps(kTanhP[0]));
  p = _mm512_mul_ps(p, x);
  __m512 q = _mm512_add_ps(x2, _mm512_set1_ps(kTanhQ[2]));
  q = _mm512_fmadd_ps(q, x2, _mm512_set1_ps(kTanhQ[1]));
  q = _mm512_fmadd_ps(q, x2, _mm512_set1_ps(kTanhQ[0]));
  return _mm512_div_ps(p, q);
}

// mppi::fast_tanh_lowp: [5/4] rational, 5 multiplies or FMAs, one add and a division.
MPPI_MLP_TARGET inline __m512 tanh_lowp(__m512 x) {
  const __m512 c = _mm512_set1_ps(kTanhLowpClamp);
  x = _mm512_min_ps(_mm512_max_ps(x, _mm512_sub_ps(_mm512_setzero_ps(), c)), c);
  const __m512 x2 = _mm512_mul_ps(x, x);
  __m512 p = _mm512_fmadd_ps(_mm512_set1_ps(kTanhLowpP[2]), x2, _mm512_set1_ps(kTanhLowpP[1]));
  p = _mm512_fmadd_ps(p, x2, _mm512_set1_ps(kTanhLowpP[0]));
  p = _mm512_mul_ps(p, x);
  __m512 q = _mm512_add_ps(x2, _mm512_set1_ps(kTanhLowpQ[1]));
  q = _mm512_fmadd_ps(q, x2, _mm512_set1_ps(kTanhLowpQ[0]));
  return _mm512_div_ps(p, q);
}

template <bool kLowpTanh>
MPPI_MLP_TARGET inline __m512 activate(Activation act, __m512 v) {
  switch (act) {  // per block, not per lane
    case Activation::kTanh: return kLowpTanh ? tanh_lowp(v) : tanh_fp32(v);
    case Activation::kRelu: return _mm512_max_ps(v, _mm512_setzero_ps());
    case Activation::kLinear: break;
  }
  return v;
}

// acc[k][v] = b[k] + sum_i w[k][i] src[i][l0 + 16 v ...], FP32 inputs (rows of `width` floats).
template <int OB, int NV>
MPPI_MLP_TARGET inline void block_fp32(const float* w, int n_in, const float* b, const float* src,
                                       int width, int l0, __m512 (&acc)[OB][NV]) {
#pragma GCC unroll 4
  for (int k = 0; k < OB; ++k)
#pragma GCC unroll 4
    for (int v = 0; v < NV; ++v) acc[k][v] = _mm512_set1_ps(b[k]);
  for (int i = 0; i < n_in; ++i) {
    const float* a = src + static_cast<std::ptrdiff_t>(i) * width + l0;
    __m512 x[NV];
#pragma GCC unroll 4
    for (int v = 0; v < NV; ++v) x[v] = _mm512_loadu_ps(a + 16 * v);
#pragma GCC unroll 4
    for (int k = 0; k < OB; ++k) {
      const __m512 wk = _mm512_set1_ps(w[static_cast<std::ptrdiff_t>(k) * n_in + i]);
#pragma GCC unroll 4
      for (int v = 0; v < NV; ++v) acc[k][v] = _mm512_fmadd_ps(wk, x[v], acc[k][v]);
    }
  }
}

#ifdef MPPI_MLP_BF16
// acc[k][v] = b[k] + sum_p (wp[k][p] . src[p][l0 + 16 v ...]) over bf16 pairs.
template <int OB, int NV>
MPPI_MLP_TARGET inline void block_bf16(const std::uint32_t* wp, int n_pairs, const float* b,
                                       const std::uint32_t* src, int width, int l0,
                                       __m512 (&acc)[OB][NV]) {
#pragma GCC unroll 4
  for (int k = 0; k < OB; ++k)
#pragma GCC unroll 4
    for (int v = 0; v < NV; ++v) acc[k][v] = _mm512_set1_ps(b[k]);
  for (int p = 0; p < n_pairs; ++p) {
    const std::uint32_t* a = src + static_cast<std::ptrdiff_t>(p) * width + l0;
    __m512bh x[NV];
#pragma GCC unroll 4
    for (int v = 0; v < NV; ++v) x[v] = (__m512bh)_mm512_loadu_si512(a + 16 * v);
#pragma GCC unroll 4
    for (int k = 0; k < OB; ++k) {
      const __m512bh wk = (__m512bh)_mm512_set1_epi32(
          static_cast<int>(wp[static_cast<std::ptrdiff_t>(k) * n_pairs + p]));
#pragma GCC unroll 4
      for (int v = 0; v < NV; ++v) acc[k][v] = _mm512_dpbf16_ps(acc[k][v], x[v], wk);
    }
  }
}

// 16 lanes of two neurons as bf16 pairs (lo in the low half of each 32-bit word).
MPPI_MLP_TARGET inline __m512i to_bf16_pairs(__m512 lo, __m512 hi) {
  // cvtne2ps(hi, lo) = words [lo0 .. lo15, hi0 .. hi15]; interleave to [lo0, hi0, lo1, hi1, ...]
  const __m512i interleave = _mm512_set_epi16(31, 15, 30, 14, 29, 13, 28, 12, 27, 11, 26, 10, 25, 9, 24, 8,
                                              23, 7, 22, 6, 21, 5, 20, 4, 19, 3, 18, 2, 17, 1, 16, 0);
  return _mm512_permutexvar_epi16(interleave, (__m512i)_mm512_cvtne2ps_pbh(hi, lo));
}
#endif

// Where a layer's outputs go: FP32 rows (dst_f32, n_out x width) or bf16 pair rows
// (dst_pairs, ceil(n_out / 2) x width words) for a following bf16 layer.
struct LayerOut {
  float* f32 = nullptr;
  std::uint32_t* pairs = nullptr;
};

template <bool kLowpTanh, int OB, int NV>
MPPI_MLP_TARGET inline void store_block(Activation act, __m512 (&acc)[OB][NV], LayerOut dst, int width,
                                        int o, int l0) {
#pragma GCC unroll 4
  for (int k = 0; k < OB; ++k)
#pragma GCC unroll 4
    for (int v = 0; v < NV; ++v) acc[k][v] = activate<kLowpTanh>(act, acc[k][v]);
#ifdef MPPI_MLP_BF16
  if (dst.pairs) {  // o is even: blocks of 4, then 2, then 1
#pragma GCC unroll 4
    for (int k = 0; k < OB; k += 2)
#pragma GCC unroll 4
      for (int v = 0; v < NV; ++v) {
        const __m512 hi = OB == 1 ? _mm512_setzero_ps() : acc[OB == 1 ? 0 : k + 1][v];
        _mm512_storeu_si512(dst.pairs + static_cast<std::ptrdiff_t>((o + k) / 2) * width + l0 + 16 * v,
                            to_bf16_pairs(acc[k][v], hi));
      }
    return;
  }
#endif
#pragma GCC unroll 4
  for (int k = 0; k < OB; ++k)
#pragma GCC unroll 4
    for (int v = 0; v < NV; ++v)
      _mm512_storeu_ps(dst.f32 + static_cast<std::ptrdiff_t>(o + k) * width + l0 + 16 * v, acc[k][v]);
}

// Output neurons [o, o + OB) over lanes [l0, l0 + 16 NV). Input either FP32 rows (src_f32) or
// bf16 pair rows (src_pairs, with the layer's packed weights wp).
template <bool kLowpTanh, int OB, int NV>
MPPI_MLP_TARGET inline void layer_block(const DenseLayer& L, const float* src_f32,
                                        const std::uint32_t* src_pairs, const std::uint32_t* wp,
                                        LayerOut dst, int width, int o, int l0) {
  __m512 acc[OB][NV];
  const float* b = L.bias.data() + o;
#ifdef MPPI_MLP_BF16
  if (src_pairs) {
    const int n_pairs = (L.n_in + 1) / 2;
    block_bf16<OB, NV>(wp + static_cast<std::ptrdiff_t>(o) * n_pairs, n_pairs, b, src_pairs, width, l0, acc);
  } else
#endif
  {
    (void)src_pairs, (void)wp;
    block_fp32<OB, NV>(L.weights.data() + static_cast<std::ptrdiff_t>(o) * L.n_in, L.n_in, b, src_f32,
                       width, l0, acc);
  }
  store_block<kLowpTanh, OB, NV>(L.activation, acc, dst, width, o, l0);
}

// One layer over lanes [0, width) (a multiple of 16).
template <bool kLowpTanh, int NV>
MPPI_MLP_TARGET inline void layer_lanes(const DenseLayer& L, const float* src_f32,
                                        const std::uint32_t* src_pairs, const std::uint32_t* wp,
                                        LayerOut dst, int width, int l0) {
  int o = 0;
  for (; o + 4 <= L.n_out; o += 4) layer_block<kLowpTanh, 4, NV>(L, src_f32, src_pairs, wp, dst, width, o, l0);
  if (o + 2 <= L.n_out) {
    layer_block<kLowpTanh, 2, NV>(L, src_f32, src_pairs, wp, dst, width, o, l0);
    o += 2;
  }
  if (o < L.n_out) layer_block<kLowpTanh, 1, NV>(L, src_f32, src_pairs, wp, dst, width, o, l0);
}

template <bool kLowpTanh>
MPPI_MLP_TARGET inline void layer(const DenseLayer& L, const float* src_f32, const std::uint32_t* src_pairs,
                                  const std::uint32_t* wp, LayerOut dst, int width) {
  int l0 = 0;
  for (; l0 + 64 <= width; l0 += 64) layer_lanes<kLowpTanh, 4>(L, src_f32, src_pairs, wp, dst, width, l0);
  for (; l0 < width; l0 += 16) layer_lanes<kLowpTanh, 1>(L, src_f32, src_pairs, wp, dst, width, l0);
}

}  // namespace
}  // namespace mppi::detail

#pragma GCC diagnostic pop
