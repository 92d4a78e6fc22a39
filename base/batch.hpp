#pragma once
// Structure-of-arrays views over a fixed-width batch of samples ("lanes").
// Component i of lane j lives at data[i * W + j]; W is a compile-time constant so that
// every per-lane loop has a known trip count and vectorises (see MPPI_SIMD_LOOP).
#include <cstddef>

namespace mppi {

// Lanes processed together by the CPU backend: one rollout chunk. 64 floats = 4 AVX-512
// registers per component; a 32-wide hidden layer of the AutoRally net is then 8 KiB (L1).
inline constexpr int kChunk = 64;

template <int N, int W>
struct Batch {
  float* data;  // N x W, row-major
  static constexpr int kRows = N;
  static constexpr int kWidth = W;
  float* operator[](int i) const noexcept { return data + static_cast<std::ptrdiff_t>(i) * W; }
};

template <int N, int W>
struct ConstBatch {
  const float* data;  // N x W, row-major
  static constexpr int kRows = N;
  static constexpr int kWidth = W;
  ConstBatch(const float* d) noexcept : data(d) {}  // NOLINT: implicit on purpose
  ConstBatch(Batch<N, W> b) noexcept : data(b.data) {}  // NOLINT
  const float* operator[](int i) const noexcept { return data + static_cast<std::ptrdiff_t>(i) * W; }
};

}  // namespace mppi

// Put before a loop over lanes: asks the compiler to vectorise it (needs -fopenmp-simd or
// -fopenmp). Loop bodies must be branch-free: use std::min/std::max and selects, not if/?:
// on floats, or AVX2 code paths will not vectorise.
#define MPPI_SIMD_LOOP _Pragma("omp simd")
