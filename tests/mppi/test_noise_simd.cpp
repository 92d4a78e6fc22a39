// The SIMD Philox paths give exactly the words of the portable lane loop (and so of
// Random123, see test_noise.cpp), on every path this CPU can run; normal_block with one
// step (one Box-Muller pair) gives the same numbers as the scalar reference.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <vector>

#include "mppi/noise.hpp"

TEST_CASE("SIMD Philox words equal the portable ones", "[noise]") {
  constexpr int W = 64;
  for (const auto& [k0, k1, it, first, t, block] :
       {std::array<std::uint32_t, 6>{1, 0, 0, 0, 0, 0}, {0xDEADBEEF, 0x12345678, 77, 4096, 99, 1},
        {0xFFFFFFFF, 0xFFFFFFFF, 0xFFFFFFF0, 0xFFFFFFE0, 5, 3}}) {
    std::vector<std::uint32_t> ref(4 * W), got(4 * W);
    mppi::detail::philox_words<W>(k0, k1, it, first, t, block, ref.data());
#ifdef MPPI_SIMD_PHILOX
    if (__builtin_cpu_supports("avx2")) {
      mppi::detail::philox_words_avx2(k0, k1, it, first, t, block, W, got.data());
      CHECK(got == ref);
    }
    if (__builtin_cpu_supports("avx512f")) {
      mppi::detail::philox_words_avx512(k0, k1, it, first, t, block, W, got.data());
      CHECK(got == ref);
    }
#endif
    mppi::detail::philox_words_dispatch<W>(k0, k1, it, first, t, block, got.data());
    CHECK(got == ref);
    // words 0 and 1 only (a model with <= 2 controls)
    const std::vector<std::uint32_t> ref01(ref.begin(), ref.begin() + 2 * W);
#ifdef MPPI_SIMD_PHILOX
    if (__builtin_cpu_supports("avx512f")) {
      std::fill(got.begin(), got.end(), 0u);
      mppi::detail::philox_words01_avx512(k0, k1, it, first, t, block, W, got.data());
      CHECK(std::vector<std::uint32_t>(got.begin(), got.begin() + 2 * W) == ref01);
    }
#endif
    std::fill(got.begin(), got.end(), 0u);
    mppi::detail::philox_words_dispatch<W>(k0, k1, it, first, t, block, got.data(), 2);
    CHECK(std::vector<std::uint32_t>(got.begin(), got.begin() + 2 * W) == ref01);
  }
}

TEST_CASE("Box-Muller's sin and cos equal fast_sincos_turns on every value it passes", "[noise]") {
  // u2 = (word >> 8) / 2^24: all 2^24 values, bit for bit
  int differ = 0;
  for (std::uint32_t b = 0; b < (1u << 24); ++b) {
    const float u = static_cast<float>(b) * (1.f / 16777216.f);
    float s0, c0, s1, c1;
    mppi::fast_sincos_turns(u, &s0, &c0);
    mppi::detail::sincos_turns(u, &s1, &c1);
    differ += std::bit_cast<std::uint32_t>(s0) != std::bit_cast<std::uint32_t>(s1) ||
              std::bit_cast<std::uint32_t>(c0) != std::bit_cast<std::uint32_t>(c1);
  }
  CHECK(differ == 0);
}

TEST_CASE("normal_block with one step gives the even step of the reference", "[noise]") {
  constexpr int W = 64;
  const mppi::NoiseKey key{0x1234567890ABCDEFull};
  std::vector<float> out(4 * W);
  for (std::uint32_t pair : {0u, 13u}) {
    mppi::normal_block<W>(key, 5u, 640u, pair, 2u, out.data(), 1);
    for (int c = 0; c < 2; ++c)
      for (int j = 0; j < W; ++j)
        REQUIRE(out[c * W + j] == mppi::normal_at(key, 5u, 640u + j, 2 * pair, 4 + c));
  }
}
