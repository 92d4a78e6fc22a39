// mppi-bench: what the vector units give, for the peak figures of docs/BENCHMARKS.md. Twelve
// independent chains of FP32 fused multiply-adds (enough to hide the FMA latency), 256-bit
// (AVX2+FMA) and 512-bit (AVX-512F). items = FMA instructions; FLOP = items x 2 x lanes.
// Equal items/s for both widths means full-width 512-bit FMAs; half for 512-bit means the
// 512-bit ones are split in two (double-pumped). Skipped where the CPU lacks the width.
#include <benchmark/benchmark.h>
#include <immintrin.h>

namespace {

constexpr int kChains = 12;  // independent FMA chains per round
constexpr long kRoundsPerIteration = 4096;

template <class V>
inline void keep(V& v) {
  asm volatile("" : "+v"(v));  // the chains stay in registers and are not folded together
}

// One benchmark body for both widths. GCC inlines an AVX intrinsic only into a function compiled
// for its target, so a template without the attribute cannot hold the body: this macro stamps
// out the whole function, attribute included. VEC: the vector type, P: the intrinsics' prefix
// (_mm256 or _mm512), LANES: floats per vector.
#define MPPI_FMA(P, v) v = P##_fmadd_ps(v, m, c)
#define MPPI_DEFINE_FMA_CHAINS(NAME, TARGET, VEC, P, LANES)                                          \
  __attribute__((target(TARGET))) void NAME(benchmark::State& state) {                               \
    /* Twelve named registers, not an array: an array's chains go through memory. */                \
    VEC a0 = P##_set1_ps(1), a1 = P##_set1_ps(2), a2 = P##_set1_ps(3), a3 = P##_set1_ps(4),           \
        a4 = P##_set1_ps(5), a5 = P##_set1_ps(6), a6 = P##_set1_ps(7), a7 = P##_set1_ps(8),           \
        a8 = P##_set1_ps(9), a9 = P##_set1_ps(10), a10 = P##_set1_ps(11), a11 = P##_set1_ps(12);      \
    const VEC m = P##_set1_ps(0.999999f), c = P##_set1_ps(1e-7f);                                    \
    for (auto _ : state) {                                                                           \
      for (long r = 0; r < kRoundsPerIteration; ++r) {                                               \
        MPPI_FMA(P, a0); MPPI_FMA(P, a1); MPPI_FMA(P, a2); MPPI_FMA(P, a3);                          \
        MPPI_FMA(P, a4); MPPI_FMA(P, a5); MPPI_FMA(P, a6); MPPI_FMA(P, a7);                          \
        MPPI_FMA(P, a8); MPPI_FMA(P, a9); MPPI_FMA(P, a10); MPPI_FMA(P, a11);                        \
        keep(a0), keep(a1), keep(a2), keep(a3), keep(a4), keep(a5);                                  \
        keep(a6), keep(a7), keep(a8), keep(a9), keep(a10), keep(a11);                                \
      }                                                                                              \
    }                                                                                                \
    float sink[LANES];                                                                               \
    P##_storeu_ps(sink, P##_add_ps(a0, a11));                                                        \
    benchmark::DoNotOptimize(sink[0]);                                                               \
    const double fmas = static_cast<double>(state.iterations()) * kRoundsPerIteration * kChains;     \
    state.SetItemsProcessed(static_cast<int64_t>(fmas));                                             \
    state.counters["GFLOPs"] =                                                                       \
        benchmark::Counter(fmas * 2 * LANES, benchmark::Counter::kIsRate, benchmark::Counter::kIs1000); \
  }

MPPI_DEFINE_FMA_CHAINS(fma_chains_256, "avx2,fma", __m256, _mm256, 8)
MPPI_DEFINE_FMA_CHAINS(fma_chains_512, "avx512f", __m512, _mm512, 16)
#undef MPPI_DEFINE_FMA_CHAINS
#undef MPPI_FMA

void BM_FmaPeak256(benchmark::State& state) {
  if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) {
    state.SkipWithError("no AVX2+FMA on this CPU");
    return;
  }
  fma_chains_256(state);
}

void BM_FmaPeak512(benchmark::State& state) {
  if (!__builtin_cpu_supports("avx512f")) {
    state.SkipWithError("no AVX-512F on this CPU");
    return;
  }
  fma_chains_512(state);
}

}  // namespace

BENCHMARK(BM_FmaPeak256);
BENCHMARK(BM_FmaPeak512);
