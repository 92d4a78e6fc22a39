// Mlp: the batched float forward pass against a naive double-precision reference written here
// (vectors of rows, std::tanh), validation messages, and loading from npz.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "base/npz.hpp"
#include "dynamics/mlp.hpp"
#include "test_data.hpp"

namespace {

using mppi::Activation;
using mppi::DenseLayer;
using mppi::Mlp;

std::string fixture(const std::string& name) {
  return (std::filesystem::path(__FILE__).parent_path().parent_path() / "data" / "npz" / name).string();
}

// Independent reference: one sample, double precision, layer matrices as vectors of rows.
struct RefLayer {
  std::vector<std::vector<double>> w;  // w[out][in]
  std::vector<double> b;
  Activation act;
};

std::vector<double> reference_forward(const std::vector<RefLayer>& net, std::vector<double> a) {
  for (const RefLayer& L : net) {
    std::vector<double> z(L.b);
    for (std::size_t o = 0; o < L.w.size(); ++o)
      for (std::size_t i = 0; i < a.size(); ++i) z[o] += L.w[o][i] * a[i];
    for (double& v : z) {
      if (L.act == Activation::kTanh) v = std::tanh(v);
      if (L.act == Activation::kRelu && v < 0) v = 0;
    }
    a = z;
  }
  return a;
}

// Random network with the given sizes; weights ~ U(-1.5, 1.5)/sqrt(n_in) keep tanh unsaturated.
// Weights are rounded to float first so that reference and Mlp use the same parameters.
void random_net(const std::vector<int>& sizes, const std::vector<Activation>& acts, std::mt19937& rng,
                std::vector<RefLayer>* ref, std::vector<DenseLayer>* layers) {
  for (std::size_t l = 0; l + 1 < sizes.size(); ++l) {
    const int n_in = sizes[l], n_out = sizes[l + 1];
    std::uniform_real_distribution<float> wd(-1.5f / std::sqrt(float(n_in)), 1.5f / std::sqrt(float(n_in)));
    std::uniform_real_distribution<float> bd(-0.5f, 0.5f);
    RefLayer r{std::vector<std::vector<double>>(n_out, std::vector<double>(n_in)), std::vector<double>(n_out),
               acts[l]};
    DenseLayer d{n_in, n_out, {}, {}, acts[l]};
    for (int o = 0; o < n_out; ++o) {
      for (int i = 0; i < n_in; ++i) {
        const float w = wd(rng);
        r.w[o][i] = w;
        d.weights.push_back(w);
      }
      const float b = bd(rng);
      r.b[o] = b;
      d.bias.push_back(b);
    }
    ref->push_back(r);
    layers->push_back(d);
  }
}

template <int W>
void check_against_reference(const std::vector<int>& sizes, const std::vector<Activation>& acts,
                             unsigned seed, mppi::MlpKernel kernel = mppi::MlpKernel::kPortable) {
  std::mt19937 rng(seed);
  std::vector<RefLayer> ref;
  std::vector<DenseLayer> layers;
  random_net(sizes, acts, rng, &ref, &layers);
  Mlp mlp(layers);
  REQUIRE(mlp.set_kernel(kernel));
  const int n_in = sizes.front(), n_out = sizes.back();
  REQUIRE(mlp.num_inputs() == n_in);
  REQUIRE(mlp.num_outputs() == n_out);

  std::uniform_real_distribution<float> xd(-2.f, 2.f);
  std::vector<float> in(static_cast<std::size_t>(n_in) * W);
  for (float& v : in) v = xd(rng);
  // Guard values after out and scratch catch writes past the sizes forward() promises.
  constexpr float kGuard = 12345.f;
  const std::size_t scratch_n = mlp.scratch_floats(W);
  std::vector<float> out(static_cast<std::size_t>(n_out) * W + 16, kGuard);
  std::vector<float> scratch(scratch_n + 16, kGuard);
  mlp.forward<W>(in.data(), out.data(), scratch.data());

  double max_err = 0;
  for (int j = 0; j < W; ++j) {
    std::vector<double> x(n_in);
    for (int i = 0; i < n_in; ++i) x[i] = in[static_cast<std::size_t>(i) * W + j];
    const std::vector<double> y = reference_forward(ref, x);
    std::vector<double> y2(n_out);
    mlp.forward_double(x.data(), y2.data());
    for (int o = 0; o < n_out; ++o) {
      max_err = std::max(max_err, std::abs(out[static_cast<std::size_t>(o) * W + j] - y[o]) / (1 + std::abs(y[o])));
      CHECK(y2[o] == Approx(y[o]).margin(1e-12));
    }
  }
  INFO("layers " << sizes.size() - 1 << ", W " << W << ", kernel " << static_cast<int>(kernel)
                  << ": max error " << max_err);
  CHECK(max_err < 1e-6);  // observed ~2e-7 (float sums + fast_tanh)
  for (std::size_t i = static_cast<std::size_t>(n_out) * W; i < out.size(); ++i) CHECK(out[i] == kGuard);
  for (std::size_t i = scratch_n; i < scratch.size(); ++i) CHECK(scratch[i] == kGuard);
}

}  // namespace

TEST_CASE("mlp: batched forward matches a double reference", "[nn]") {
  const auto T = Activation::kTanh, R = Activation::kRelu, L = Activation::kLinear;
  check_against_reference<64>({6, 32, 32, 4}, {T, T, L}, 1);  // the AutoRally shape
  check_against_reference<64>({7, 16, 9, 2}, {R, T, L}, 2);
  check_against_reference<64>({3, 5}, {R}, 3);                  // one layer, in -> out directly
  check_against_reference<8>({10, 33, 1}, {T, R}, 4);
  check_against_reference<13>({2, 40, 3, 40, 5}, {T, L, R, T}, 5);  // odd width, 4 layers
  check_against_reference<1>({1, 1}, {L}, 6);
}

TEST_CASE("mlp: the AVX-512 FP32 kernel matches a double reference", "[nn]") {
  if (!Mlp::cpu_supports(mppi::MlpKernel::kAvx512)) {
    WARN("no AVX-512 on this CPU: kernel not tested");
    return;
  }
  const auto T = Activation::kTanh, R = Activation::kRelu, L = Activation::kLinear;
  const auto K = mppi::MlpKernel::kAvx512;
  check_against_reference<64>({6, 32, 32, 4}, {T, T, L}, 1, K);
  check_against_reference<64>({7, 16, 9, 2}, {R, T, L}, 2, K);  // 9 = 4 + 4 + 1 neurons
  check_against_reference<16>({3, 5}, {R}, 3, K);                // 5 = 4 + 1
  check_against_reference<80>({10, 33, 1}, {T, R}, 4, K);         // 64 + 16 lanes
  check_against_reference<128>({2, 40, 3, 40, 5}, {T, L, R, T}, 5, K);  // 3 = 2 + 1, 4 layers
  check_against_reference<32>({1, 1}, {L}, 6, K);
  check_against_reference<13>({6, 32, 32, 4}, {T, T, L}, 7, K);  // width not a multiple of 16: portable
}

TEST_CASE("mlp: forward<W> runs the kernel the CPU supports", "[nn]") {
  Mlp mlp({DenseLayer{2, 3, std::vector<float>(6, 0.1f), std::vector<float>(3, 0.f), Activation::kTanh},
            DenseLayer{3, 1, std::vector<float>(3, 0.5f), std::vector<float>(1, 0.f), Activation::kLinear}});
  CHECK(mlp.precision() == mppi::NetPrecision::kFp32);
  CHECK(mlp.kernel() == (Mlp::cpu_supports(mppi::MlpKernel::kAvx512) ? mppi::MlpKernel::kAvx512
                                                                      : mppi::MlpKernel::kPortable));
  const bool bf16 = Mlp::cpu_supports(mppi::MlpKernel::kAvx512Bf16);
  CHECK(mlp.set_precision(mppi::NetPrecision::kBf16) == bf16);
  CHECK(mlp.precision() == (bf16 ? mppi::NetPrecision::kBf16 : mppi::NetPrecision::kFp32));
  CHECK(mlp.set_precision(mppi::NetPrecision::kFp32));
  CHECK(mlp.precision() == mppi::NetPrecision::kFp32);
  CHECK(mlp.set_kernel(mppi::MlpKernel::kPortable));
  CHECK(mlp.kernel() == mppi::MlpKernel::kPortable);
  // bf16 pairs: layer 2 has 3 inputs -> 2 words per row, the last one's high half 0
  REQUIRE(mlp.bf16_weights(1).size() == 2);
  CHECK(mlp.bf16_weights(1)[0] == (0x3f00u | 0x3f00u << 16));  // bf16(0.5) = 0x3f00
  CHECK(mlp.bf16_weights(1)[1] == 0x3f00u);
  CHECK(mlp.bf16_weights(0).empty());
}

namespace {
// x rounded to bf16 (8 significant bits), to nearest, ties to even: the oracle for the bf16
// kernel's rounding of weights and activations, written without the library's helper.
double round_bf16(double x) {
  if (x == 0) return 0;
  int e = 0;
  const double m = std::frexp(x, &e);  // |m| in [0.5, 1)
  return std::ldexp(std::nearbyint(std::ldexp(m, 8)), e - 8);
}

// What the bf16 kernel computes, in double: layer 1 as is, later layers with bf16 weights and
// bf16 inputs (the previous layer's activations rounded), sums exact.
std::vector<double> reference_forward_bf16(std::vector<RefLayer> net, std::vector<double> a) {
  for (std::size_t l = 0; l < net.size(); ++l) {
    RefLayer& L = net[l];
    if (l > 0) {
      for (auto& row : L.w)
        for (double& w : row) w = round_bf16(w);
      for (double& v : a) v = round_bf16(v);
    }
    std::vector<double> z(L.b);
    for (std::size_t o = 0; o < L.w.size(); ++o)
      for (std::size_t i = 0; i < a.size(); ++i) z[o] += L.w[o][i] * a[i];
    for (double& v : z) {
      if (L.act == Activation::kTanh) v = std::tanh(v);
      if (L.act == Activation::kRelu && v < 0) v = 0;
    }
    a = z;
  }
  return a;
}

// The bf16 kernel against (a) the bf16-rounding reference above, (b) the exact double network.
template <int W>
void check_bf16(const std::vector<int>& sizes, const std::vector<Activation>& acts, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<RefLayer> ref;
  std::vector<DenseLayer> layers;
  random_net(sizes, acts, rng, &ref, &layers);
  Mlp mlp(layers);
  REQUIRE(mlp.set_precision(mppi::NetPrecision::kBf16));
  const int n_in = sizes.front(), n_out = sizes.back();
  std::uniform_real_distribution<float> xd(-2.f, 2.f);
  std::vector<float> in(static_cast<std::size_t>(n_in) * W);
  for (float& v : in) v = xd(rng);
  constexpr float kGuard = 12345.f;
  const std::size_t scratch_n = mlp.scratch_floats(W);
  std::vector<float> out(static_cast<std::size_t>(n_out) * W + 16, kGuard);
  std::vector<float> scratch(scratch_n + 16, kGuard);
  mlp.forward<W>(in.data(), out.data(), scratch.data());
  double err_rounded = 0, err_exact = 0;
  for (int j = 0; j < W; ++j) {
    std::vector<double> x(n_in);
    for (int i = 0; i < n_in; ++i) x[i] = in[static_cast<std::size_t>(i) * W + j];
    const std::vector<double> y_rounded = reference_forward_bf16(ref, x);
    const std::vector<double> y_exact = reference_forward(ref, x);
    for (int o = 0; o < n_out; ++o) {
      const double v = out[static_cast<std::size_t>(o) * W + j];
      err_rounded = std::max(err_rounded, std::abs(v - y_rounded[o]) / (1 + std::abs(y_rounded[o])));
      err_exact = std::max(err_exact, std::abs(v - y_exact[o]) / (1 + std::abs(y_exact[o])));
    }
  }
  INFO("layers " << sizes.size() - 1 << ", W " << W << ": max error against the bf16-rounding reference "
                 << err_rounded << ", against the exact network " << err_exact);
  // fast_tanh_lowp (4.8e-5) moves a few activations by one bf16 step (2^-8 relative) against
  // std::tanh; observed up to ~1e-3. A wrongly packed pair or lane gives O(0.1 .. 1).
  CHECK(err_rounded < 4e-3);
  CHECK(err_exact < 2e-2);  // bf16 rounding itself: observed ~5e-3
  for (std::size_t i = static_cast<std::size_t>(n_out) * W; i < out.size(); ++i) CHECK(out[i] == kGuard);
  for (std::size_t i = scratch_n; i < scratch.size(); ++i) CHECK(scratch[i] == kGuard);
}
}  // namespace

TEST_CASE("mlp: the bf16 kernel matches a bf16-rounding double reference", "[nn]") {
  if (!Mlp::cpu_supports(mppi::MlpKernel::kAvx512Bf16)) {
    WARN("no AVX512-BF16 on this CPU: kernel not tested");
    return;
  }
  const auto T = Activation::kTanh, R = Activation::kRelu, L = Activation::kLinear;
  check_bf16<64>({6, 32, 32, 4}, {T, T, L}, 11);  // the AutoRally shape
  check_bf16<64>({7, 17, 9, 2}, {R, T, L}, 12);   // odd inputs of layers 2 and 3: padded pairs
  check_bf16<16>({3, 5}, {R}, 13);                // one layer: FP32 only
  check_bf16<80>({10, 33, 1}, {T, R}, 14);
  check_bf16<128>({2, 40, 3, 40, 5}, {T, L, R, T}, 15);
}

TEST_CASE("mlp: relu and linear layers, hand-computed", "[nn]") {
  // y = relu(W1 x + b1) with W1 = [[1, -1], [2, 0.5]], b1 = [0, -1]; then linear z = [3, -1] y + 0.5.
  // x = (1, 2): W1 x + b1 = (-1, 2)   -> relu (0, 2) -> z = -2 + 0.5 = -1.5
  // x = (3, -2): W1 x + b1 = (5, 4)   -> relu (5, 4) -> z = 15 - 4 + 0.5 = 11.5
  const Mlp mlp({DenseLayer{2, 2, {1, -1, 2, 0.5f}, {0, -1}, Activation::kRelu},
                 DenseLayer{2, 1, {3, -1}, {0.5f}, Activation::kLinear}});
  const float in[2 * 2] = {1, 3, 2, -2};  // 2 inputs x 2 lanes
  float out[2] = {};
  std::vector<float> scratch(mlp.scratch_floats(2));
  mlp.forward<2>(in, out, scratch.data());
  CHECK(out[0] == -1.5f);
  CHECK(out[1] == 11.5f);
}

TEST_CASE("mlp: construction validates sizes and values", "[nn]") {
  const DenseLayer ok{2, 3, std::vector<float>(6, 0.1f), std::vector<float>(3, 0.f), Activation::kTanh};
  CHECK_THROWS_WITH(Mlp(std::vector<DenseLayer>{}), "Mlp: no layers");
  CHECK_THROWS_WITH(Mlp({ok, DenseLayer{4, 1, std::vector<float>(4, 0.f), {0.f}, Activation::kLinear}}),
                    "Mlp: layer 2 has 4 inputs but layer 1 has 3 outputs");
  CHECK_THROWS_WITH(Mlp({DenseLayer{2, 3, std::vector<float>(5, 0.f), std::vector<float>(3, 0.f)}}),
                    "Mlp: layer 1 has 5 weights, expected 3 x 2");
  CHECK_THROWS_WITH(Mlp({DenseLayer{2, 3, std::vector<float>(6, 0.f), std::vector<float>(2, 0.f)}}),
                    "Mlp: layer 1 has 2 biases, expected 3");
  CHECK_THROWS_WITH(Mlp({DenseLayer{0, 3, {}, std::vector<float>(3, 0.f)}}),
                    "Mlp: layer 1 has 0 inputs and 3 outputs (need >= 1 each)");
  DenseLayer nan_layer{3, 3, std::vector<float>(9, 0.f), std::vector<float>(3, 0.f)};
  nan_layer.weights[4] = std::nanf("");
  CHECK_THROWS_WITH(Mlp({ok, DenseLayer{3, 3, std::vector<float>(9, 0.f), std::vector<float>(3, 0.f)}, nan_layer}),
                    Catch::Contains("layer 3") && Catch::Contains("non-finite"));
  const Mlp two({ok, DenseLayer{3, 5, std::vector<float>(15, 0.f), std::vector<float>(5, 0.f)}});
  CHECK(two.scratch_floats(64) == 2 * 3 * 64);  // one hidden layer of 3
}

TEST_CASE("mlp: from_npz reads the key scheme and reports bad files", "[nn]") {
  const auto T = Activation::kTanh, L = Activation::kLinear;
  const mppi::NpzFile small = mppi::NpzFile::load(fixture("mlp_small.npz"));
  const Mlp mlp = Mlp::from_npz(small, "net_", {T, L});
  REQUIRE(mlp.num_layers() == 2);
  const float in[2] = {0.5f, -1.f};
  float out[1];
  std::vector<float> scratch(mlp.scratch_floats(1));
  mlp.forward<1>(in, out, scratch.data());
  CHECK(out[0] == Approx(-0.5358958562939985).margin(2e-6));  // printed by make_fixtures.py (numpy)

  CHECK_THROWS_WITH(Mlp::from_npz(small, "net_", {T}),
                    small.path() + ": has a layer 'net_W2' beyond the 1 activations given");
  CHECK_THROWS_WITH(Mlp::from_npz(small, "net_", {T, T, L}), Catch::StartsWith(small.path() + ": missing array 'net_W3'"));
  CHECK_THROWS_WITH(Mlp::from_npz(small, "other_", {T}), Catch::Contains("missing array 'other_W1'"));
  const mppi::NpzFile bad = mppi::NpzFile::load(fixture("mlp_bad_chain.npz"));
  CHECK_THROWS_WITH(Mlp::from_npz(bad, "net_", {T, L}),
                    bad.path() + ": array 'net_W2' has shape (1,4), expected (n,3) to follow net_W1 (3 outputs)");

  const mppi::NpzFile ar = mppi::NpzFile::load(mppi::test::data_path("autorally/models/autorally_nnet_09_12_2018.npz"));
  const Mlp net = Mlp::from_npz(ar, "dynamics_", {T, T, L});
  CHECK(net.num_inputs() == 6);
  CHECK(net.num_outputs() == 4);
  CHECK(net.layers()[1].n_in == 32);
  CHECK(net.layers()[1].n_out == 32);
  CHECK(net.layers()[2].bias[0] == static_cast<float>(0.07772222691295132));
}
