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

__attribute__((target("avx2,fma"))) void fma_chains_256(benchmark::State& state) {
  // Twelve named registers, not an array: an array's chains go through memory.
  __m256 a0 = _mm256_set1_ps(1), a1 = _mm256_set1_ps(2), a2 = _mm256_set1_ps(3), a3 = _mm256_set1_ps(4),
         a4 = _mm256_set1_ps(5), a5 = _mm256_set1_ps(6), a6 = _mm256_set1_ps(7), a7 = _mm256_set1_ps(8),
         a8 = _mm256_set1_ps(9), a9 = _mm256_set1_ps(10), a10 = _mm256_set1_ps(11), a11 = _mm256_set1_ps(12);
  const __m256 m = _mm256_set1_ps(0.999999f), c = _mm256_set1_ps(1e-7f);
  for (auto _ : state) {
    for (long r = 0; r < kRoundsPerIteration; ++r) {
#define MPPI_FMA(v) v = _mm256_fmadd_ps(v, m, c)
      MPPI_FMA(a0); MPPI_FMA(a1); MPPI_FMA(a2); MPPI_FMA(a3); MPPI_FMA(a4); MPPI_FMA(a5);
      MPPI_FMA(a6); MPPI_FMA(a7); MPPI_FMA(a8); MPPI_FMA(a9); MPPI_FMA(a10); MPPI_FMA(a11);
#undef MPPI_FMA
      keep(a0), keep(a1), keep(a2), keep(a3), keep(a4), keep(a5);
      keep(a6), keep(a7), keep(a8), keep(a9), keep(a10), keep(a11);
    }
  }
  float sink[8];
  _mm256_storeu_ps(sink, _mm256_add_ps(a0, a11));
  benchmark::DoNotOptimize(sink[0]);
  const double fmas = static_cast<double>(state.iterations()) * kRoundsPerIteration * kChains;
  state.SetItemsProcessed(static_cast<int64_t>(fmas));
  state.counters["GFLOPs"] = benchmark::Counter(fmas * 2 * 8, benchmark::Counter::kIsRate, benchmark::Counter::kIs1000);
}

__attribute__((target("avx512f"))) void fma_chains_512(benchmark::State& state) {
  // Twelve named registers, not an array: an array's chains go through memory.
  __m512 a0 = _mm512_set1_ps(1), a1 = _mm512_set1_ps(2), a2 = _mm512_set1_ps(3), a3 = _mm512_set1_ps(4),
         a4 = _mm512_set1_ps(5), a5 = _mm512_set1_ps(6), a6 = _mm512_set1_ps(7), a7 = _mm512_set1_ps(8),
         a8 = _mm512_set1_ps(9), a9 = _mm512_set1_ps(10), a10 = _mm512_set1_ps(11), a11 = _mm512_set1_ps(12);
  const __m512 m = _mm512_set1_ps(0.999999f), c = _mm512_set1_ps(1e-7f);
  for (auto _ : state) {
    for (long r = 0; r < kRoundsPerIteration; ++r) {
#define MPPI_FMA(v) v = _mm512_fmadd_ps(v, m, c)
      MPPI_FMA(a0); MPPI_FMA(a1); MPPI_FMA(a2); MPPI_FMA(a3); MPPI_FMA(a4); MPPI_FMA(a5);
      MPPI_FMA(a6); MPPI_FMA(a7); MPPI_FMA(a8); MPPI_FMA(a9); MPPI_FMA(a10); MPPI_FMA(a11);
#undef MPPI_FMA
      keep(a0), keep(a1), keep(a2), keep(a3), keep(a4), keep(a5);
      keep(a6), keep(a7), keep(a8), keep(a9), keep(a10), keep(a11);
    }
  }
  float sink[16];
  _mm512_storeu_ps(sink, _mm512_add_ps(a0, a11));
  benchmark::DoNotOptimize(sink[0]);
  const double fmas = static_cast<double>(state.iterations()) * kRoundsPerIteration * kChains;
  state.SetItemsProcessed(static_cast<int64_t>(fmas));
  state.counters["GFLOPs"] = benchmark::Counter(fmas * 2 * 16, benchmark::Counter::kIsRate, benchmark::Counter::kIs1000);
}

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
