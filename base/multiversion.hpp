#pragma once
// Run-time CPU dispatch for the hot per-chunk kernels. The library is built for the baseline
// x86-64 by default (users' CPUs differ); MPPI_MULTIVERSION makes GCC/Clang emit the kernel
// three times (AVX-512, AVX2+FMA, baseline) and pick one when the program loads. `flatten`
// inlines the whole model/cost call tree into each clone so all of it gets the wider vectors.
// Define MPPI_NO_MULTIVERSION (or build with MPPI_NATIVE) to compile just one version.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && \
    !defined(MPPI_NO_MULTIVERSION) && !defined(__AVX512F__)
#define MPPI_MULTIVERSION \
  __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default"), flatten))
#else
#define MPPI_MULTIVERSION __attribute__((flatten))
#endif
