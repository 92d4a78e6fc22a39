// The lane-wise Philox must be bit-identical to Random123's reference philox4x32-10, and the
// Box-Muller normals must look standard normal.
#include <Random123/philox.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "mppi/noise.hpp"

TEST_CASE("philox4x32_10 matches Random123", "[core][noise]") {
  r123::Philox4x32 reference;
  for (std::uint32_t i = 0; i < 200; ++i) {
    const r123::Philox4x32::ctr_type ctr = {{i * 7919u, i ^ 0xdeadbeefu, 3u * i + 1, 42u}};
    const r123::Philox4x32::key_type key = {{0x12345678u + i, 0x9abcdef0u - i}};
    const auto expected = reference(ctr, key);
    std::uint32_t c[4] = {ctr[0], ctr[1], ctr[2], ctr[3]};
    mppi::philox4x32_10(c, key[0], key[1]);
    for (int w = 0; w < 4; ++w) REQUIRE(c[w] == expected[w]);
  }
}

TEST_CASE("batched normals equal the scalar reference draw", "[core][noise]") {
  const mppi::NoiseKey key{0x0123456789abcdefULL};
  float block[4 * 64];
  for (std::uint32_t t : {0u, 5u, 99u}) {
    mppi::normal_block<64>(key, 17u, 128u, t, 0u, block);
    for (int j = 0; j < 64; ++j)
      for (int c = 0; c < 4; ++c)
        REQUIRE(block[c * 64 + j] == mppi::normal_at(key, 17u, 128u + j, t, c));
  }
}

TEST_CASE("normals have mean 0, variance 1 and Gaussian tails", "[core][noise]") {
  const mppi::NoiseKey key{7};
  const int n_blocks = 4096;
  std::vector<float> all;
  all.reserve(n_blocks * 4 * 64);
  float block[4 * 64];
  for (int b = 0; b < n_blocks; ++b) {
    mppi::normal_block<64>(key, 0u, 64u * b, 0u, 0u, block);
    all.insert(all.end(), block, block + 4 * 64);
  }
  double mean = 0, var = 0;
  int beyond2 = 0;
  for (float v : all) mean += v;
  mean /= all.size();
  for (float v : all) {
    var += (v - mean) * (v - mean);
    beyond2 += std::abs(v) > 2.f;
  }
  var /= all.size();
  const double n = static_cast<double>(all.size());  // ~1M draws
  CHECK(std::abs(mean) < 5.0 / std::sqrt(n));
  CHECK(std::abs(var - 1.0) < 0.01);
  // P(|Z| > 2) = 0.0455003
  CHECK(std::abs(beyond2 / n - 0.0455003) < 0.002);
  // Draws with a different seed differ.
  CHECK(mppi::normal_at(mppi::NoiseKey{8}, 0, 0, 0, 0) != mppi::normal_at(key, 0, 0, 0, 0));
}
