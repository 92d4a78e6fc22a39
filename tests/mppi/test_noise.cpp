// The lane-wise Philox must be bit-identical to Random123's reference philox4x32-10, and the
// Box-Muller normals must look standard normal.
#include <Random123/philox.h>

#include <catch2/catch.hpp>
#include <algorithm>
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
  for (std::uint32_t pair : {0u, 5u, 49u})
    for (std::uint32_t channel_pair : {0u, 3u}) {
      mppi::normal_block<64>(key, 17u, 128u, pair, channel_pair, block);
      for (int j = 0; j < 64; ++j)
        for (int s = 0; s < 2; ++s)
          for (int i = 0; i < 2; ++i)
            REQUIRE(block[(2 * s + i) * 64 + j] ==
                    mppi::normal_at(key, 17u, 128u + j, 2 * pair + s, static_cast<int>(2 * channel_pair) + i));
    }
}

// The counter layout, from Random123's philox4x32 and the Box-Muller formula in double
// precision: the normal of (sample, t, channel) uses counter (sample, t / 2, iteration,
// channel / 2), words 0, 1 for an even t and 2, 3 for an odd one; channel % 2 picks the cosine
// (0) or sine (1) branch.
TEST_CASE("normal_at follows the documented counter layout", "[core][noise]") {
  r123::Philox4x32 philox;
  const std::uint64_t seed = 0x0123456789abcdefULL;
  const mppi::NoiseKey key{seed};
  const std::uint32_t iteration = 3;
  double worst = 0;
  for (std::uint32_t sample : {0u, 1u, 777u})
    for (std::uint32_t t = 0; t < 6; ++t)
      for (int channel = 0; channel < 5; ++channel) {
        const r123::Philox4x32::ctr_type ctr = {{sample, t / 2, iteration, static_cast<std::uint32_t>(channel / 2)}};
        const r123::Philox4x32::key_type k = {{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32)}};
        const auto w = philox(ctr, k);
        const std::uint32_t a = w[2 * (t % 2)], b = w[2 * (t % 2) + 1];
        const double u1 = ((a >> 8) + 0.5) / 16777216.0, u2 = (b >> 8) / 16777216.0;
        const double r = std::sqrt(-2.0 * std::log(u1)), angle = 2.0 * 3.14159265358979323846 * u2;
        const double expected = channel % 2 == 0 ? r * std::cos(angle) : r * std::sin(angle);
        worst = std::max(worst, std::abs(mppi::normal_at(key, iteration, sample, t, channel) - expected));
      }
  CHECK(worst < 1e-5);
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

// Pearson correlation of x and y.
static double correlation(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= n;
  my /= n;
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
  }
  return sxy / std::sqrt(sxx * syy);
}

// Independent N(0, 1) draws have correlation ~ N(0, 1/n) between any two of them, and so have
// their squares (which would show a shared radius or angle). Pairs drawn from one Philox call
// (the two steps of a pair, the two channels of a pair) and from neighbouring calls
// (consecutive step pairs, samples, iterations and channel pairs).
TEST_CASE("normals of neighbouring steps, channels, samples and iterations are uncorrelated", "[core][noise]") {
  const mppi::NoiseKey key{11};
  constexpr int W = 64;
  const int blocks = 1024;  // 65,536 samples
  float a[4 * W], b[4 * W], c[4 * W], d[4 * W];
  enum { kStep, kChannel, kStepPair, kSample, kIteration, kChannelPair, kCount };
  std::vector<double> x[kCount], y[kCount];
  for (int blk = 0; blk < blocks; ++blk) {
    const auto first = static_cast<std::uint32_t>(W * blk);
    mppi::normal_block<W>(key, 4u, first, 7u, 1u, a);  // steps 14, 15, channels 2, 3
    mppi::normal_block<W>(key, 4u, first, 8u, 1u, b);  // steps 16, 17
    mppi::normal_block<W>(key, 5u, first, 7u, 1u, c);  // next iteration
    mppi::normal_block<W>(key, 4u, first, 7u, 0u, d);  // channels 0, 1
    for (int j = 0; j < W; ++j) {
      x[kStep].push_back(a[0 * W + j]), y[kStep].push_back(a[2 * W + j]);
      x[kChannel].push_back(a[2 * W + j]), y[kChannel].push_back(a[3 * W + j]);
      x[kStepPair].push_back(a[3 * W + j]), y[kStepPair].push_back(b[1 * W + j]);
      if (j + 1 < W) x[kSample].push_back(a[1 * W + j]), y[kSample].push_back(a[1 * W + j + 1]);
      x[kIteration].push_back(a[0 * W + j]), y[kIteration].push_back(c[0 * W + j]);
      x[kChannelPair].push_back(a[1 * W + j]), y[kChannelPair].push_back(d[1 * W + j]);
    }
  }
  for (int k = 0; k < kCount; ++k) {
    std::vector<double> x2 = x[k], y2 = y[k];
    for (double& v : x2) v *= v;
    for (double& v : y2) v *= v;
    const double bound = 5.0 / std::sqrt(static_cast<double>(x[k].size()));
    INFO("pair kind " << k << ", n = " << x[k].size());
    CHECK(std::abs(correlation(x[k], y[k])) < bound);
    CHECK(std::abs(correlation(x2, y2)) < bound);
  }
}
