#pragma once
// A small fully connected network (multilayer perceptron) evaluated over a fixed-width SoA
// batch of lanes: out = f_L(W_L ... f_1(W_1 in + b_1) ... + b_L), W stored (out, in) row-major.
// forward<W>() is hot-loop code (no allocation, no exceptions, branch-free over lanes); it is
// built as "for each block of output neurons, for each input: acc[k][lanes] += w[k] * a[lanes]",
// so the lane loop is innermost and compiles to broadcast-FMA over vectors.
// That portable code runs on every CPU; fast_tanh96's float clamp only vectorises on AVX2/SSE with
// -fno-trapping-math (mppi::core sets it); without it the 6-32-32-4 net takes ~160 ns on AVX2.
// On a CPU with AVX-512 (checked once, at construction) forward<W>() for W a multiple of 16
// calls the register-blocked AVX-512 kernel instead (dynamics/mlp_avx512_kernels.hpp: 16
// accumulators, activation fused), one call per forward pass. set_precision(kBf16) selects
// its bf16 variant where the CPU has AVX512-BF16: layers after the first take bf16 inputs and
// weights (vdpbf16ps, FP32 sums) and a cheaper tanh; the first layer stays FP32 (its inputs
// are raw states such as speeds, which bf16's 8-bit mantissa would round by up to 0.2 %).
#include <bit>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "base/batch.hpp"
#include "base/fast_math.hpp"

namespace mppi {

class NpzFile;
class Mlp;

enum class Activation { kTanh, kRelu, kLinear };

// Arithmetic of the hidden layers: FP32 throughout, or bf16 products with FP32 sums.
enum class NetPrecision { kFp32, kBf16 };
// The code forward<W>() runs: portable C++ (any CPU, any W), or the AVX-512 kernels (W a
// multiple of 16; otherwise forward<W>() falls back to the portable code).
enum class MlpKernel { kPortable, kAvx512, kAvx512Bf16 };

namespace detail {
// dynamics/mlp_avx512.cpp and mlp_avx512_bf16.cpp; width a multiple of 16. Only call them when
// cpu_supports(kernel) says so.
void mlp_forward_avx512(const Mlp& net, int width, const float* in, float* out, float* scratch) noexcept;
void mlp_forward_avx512_bf16(const Mlp& net, int width, const float* in, float* out, float* scratch) noexcept;
}  // namespace detail

struct DenseLayer {
  int n_in = 0;
  int n_out = 0;
  std::vector<float> weights;  // n_out x n_in, row-major
  std::vector<float> bias;     // n_out
  Activation activation = Activation::kLinear;
};

class Mlp {
 public:
  Mlp() = default;
  // Checks that every layer is well formed (sizes > 0, weights n_out x n_in, bias n_out, all
  // finite) and that the layers chain (n_in of layer i = n_out of layer i - 1). Throws
  // mppi::Error "Mlp: layer 2 ..." otherwise.
  explicit Mlp(std::vector<DenseLayer> layers);

  // Layers "<prefix>W1", "<prefix>b1", "<prefix>W2", ... of an npz (W shaped (out, in), b (out,)),
  // one per entry of `activations`. Throws mppi::Error naming the file and the array if one is
  // missing, has the wrong shape (does not chain), holds non-finite values, or if the file has
  // more layers under the prefix than activations were given.
  static Mlp from_npz(const NpzFile& npz, const std::string& prefix,
                      const std::vector<Activation>& activations);

  int num_inputs() const { return layers_.empty() ? 0 : layers_.front().n_in; }
  int num_outputs() const { return layers_.empty() ? 0 : layers_.back().n_out; }
  int num_layers() const { return static_cast<int>(layers_.size()); }
  const std::vector<DenseLayer>& layers() const { return layers_; }

  int max_hidden() const { return max_hidden_; }

  // Scratch floats forward<W>() needs for `width` lanes (two hidden-layer buffers).
  std::size_t scratch_floats(int width) const {
    return 2 * static_cast<std::size_t>(max_hidden_) * static_cast<std::size_t>(width);
  }

  // Whether this CPU can run `kernel` (AVX-512 F/BW/DQ/VL; and AVX512-BF16 for the bf16 one).
  static bool cpu_supports(MlpKernel kernel);

  // FP32 (the default) or bf16 hidden layers. kBf16 takes effect only where the CPU supports
  // it (returns false and keeps FP32 otherwise). Set before the rollouts, not during them.
  bool set_precision(NetPrecision precision);
  NetPrecision precision() const {
    return kernel_ == MlpKernel::kAvx512Bf16 ? NetPrecision::kBf16 : NetPrecision::kFp32;
  }
  // Forces a kernel (tests, benchmarks); false (and no change) if the CPU cannot run it.
  bool set_kernel(MlpKernel kernel);
  MlpKernel kernel() const { return kernel_; }

  // Layer l's weights as bf16 pairs for the bf16 kernel: row o holds ceil(n_in / 2) words,
  // word p = bf16(w[o][2p]) | bf16(w[o][2p + 1]) << 16 (0 past n_in), round to nearest even.
  // Empty for layer 0 (it stays FP32).
  const std::vector<std::uint32_t>& bf16_weights(int layer) const { return bf16_weights_[layer]; }

  // in: num_inputs() x W, out: num_outputs() x W (both row-major SoA, out may not alias in),
  // scratch: scratch_floats(W) floats.
  template <int W>
  void forward(const float* in, float* out, float* scratch) const noexcept {
    if constexpr (W % 16 == 0) {
      if (kernel_ == MlpKernel::kAvx512) return detail::mlp_forward_avx512(*this, W, in, out, scratch);
      if (kernel_ == MlpKernel::kAvx512Bf16)
        return detail::mlp_forward_avx512_bf16(*this, W, in, out, scratch);
    }
    forward_portable<W>(in, out, scratch);
  }

  // The portable code, whatever kernel() is (tests compare the two).
  template <int W>
  void forward_portable(const float* in, float* out, float* scratch) const noexcept {
    const float* src = in;
    const int n = num_layers();
    for (int l = 0; l < n; ++l) {
      float* dst = l + 1 == n ? out : scratch + (l & 1) * max_hidden_ * W;
      dense<W>(layers_[l], src, dst);
      src = dst;
    }
  }

  // One input vector, evaluated in double precision with std::tanh (tests, diagnostics; it
  // allocates). in: num_inputs(), out: num_outputs().
  void forward_double(const double* in, double* out) const;

 private:
  // dense() works on blocks of kOutBlock output neurons x kLaneBlock lanes: each load of an
  // input row segment feeds kOutBlock FMAs, and the 4 x 16 accumulators stay in registers as
  // independent FMA chains (AVX-512: 4 zmm, AVX2: 8 ymm). Measured on Zen 5 for the 6-32-32-4
  // net at W = 64, the matrix part took ~30 ns/sample against ~45 for one neuron x 64 lanes.
  static constexpr int kOutBlock = 4;
  template <int W>
  static constexpr int kLaneBlock = W % 16 == 0 ? 16 : W;

  template <int LB>
  static void activate(Activation act, const float* acc, float* d) noexcept {
    switch (act) {  // per layer, not per lane
      case Activation::kTanh:
        MPPI_SIMD_LOOP
        for (int j = 0; j < LB; ++j) d[j] = fast_tanh96(acc[j]);
        break;
      case Activation::kRelu:
        // max(x, 0) on the bits: clear x if its sign bit is set. Integer ops vectorise with
        // any floating-point flags (a float compare does not under -ftrapping-math on AVX2).
        MPPI_SIMD_LOOP
        for (int j = 0; j < LB; ++j) {
          const auto bits = std::bit_cast<std::int32_t>(acc[j]);
          d[j] = std::bit_cast<float>(bits & ~(bits >> 31));
        }
        break;
      case Activation::kLinear:
        MPPI_SIMD_LOOP
        for (int j = 0; j < LB; ++j) d[j] = acc[j];
        break;
    }
  }

  // dst[o][lanes] = act(b[o] + sum_i w[o][i] src[i][lanes]); src: n_in x W, dst: n_out x W.
  template <int W>
  static void dense(const DenseLayer& layer, const float* src, float* dst) noexcept {
    constexpr int LB = kLaneBlock<W>;
    constexpr int OB = kOutBlock;
    const int n_in = layer.n_in, n_out = layer.n_out;
    const float* w = layer.weights.data();
    const float* b = layer.bias.data();
    for (int l0 = 0; l0 < W; l0 += LB) {
      int o = 0;
      for (; o + OB <= n_out; o += OB) {
        float acc[OB][LB];
#pragma GCC unroll 8
        for (int k = 0; k < OB; ++k) {
          const float bias = b[o + k];
          MPPI_SIMD_LOOP
          for (int j = 0; j < LB; ++j) acc[k][j] = bias;
        }
        for (int i = 0; i < n_in; ++i) {
          const float* a = src + static_cast<std::ptrdiff_t>(i) * W + l0;
#pragma GCC unroll 8
          for (int k = 0; k < OB; ++k) {
            const float wk = w[static_cast<std::ptrdiff_t>(o + k) * n_in + i];
            MPPI_SIMD_LOOP
            for (int j = 0; j < LB; ++j) acc[k][j] += wk * a[j];
          }
        }
#pragma GCC unroll 8
        for (int k = 0; k < OB; ++k)
          activate<LB>(layer.activation, acc[k], dst + static_cast<std::ptrdiff_t>(o + k) * W + l0);
      }
      for (; o < n_out; ++o) {  // remaining neurons, one at a time
        float acc[LB];
        const float bias = b[o];
        MPPI_SIMD_LOOP
        for (int j = 0; j < LB; ++j) acc[j] = bias;
        const float* w_row = w + static_cast<std::ptrdiff_t>(o) * n_in;
        for (int i = 0; i < n_in; ++i) {
          const float wi = w_row[i];
          const float* a = src + static_cast<std::ptrdiff_t>(i) * W + l0;
          MPPI_SIMD_LOOP
          for (int j = 0; j < LB; ++j) acc[j] += wi * a[j];
        }
        activate<LB>(layer.activation, acc, dst + static_cast<std::ptrdiff_t>(o) * W + l0);
      }
    }
  }

  std::vector<DenseLayer> layers_;
  int max_hidden_ = 0;  // widest hidden (non-output) layer
  MlpKernel kernel_ = MlpKernel::kPortable;
  std::vector<std::vector<std::uint32_t>> bf16_weights_;  // per layer, see bf16_weights()
};

// float -> bf16 bits, round to nearest even (as vcvtne2ps2bf16 does for finite values).
inline std::uint16_t to_bf16_bits(float v) {
  const std::uint32_t bits = std::bit_cast<std::uint32_t>(v);
  return static_cast<std::uint16_t>((bits + 0x7fffu + ((bits >> 16) & 1u)) >> 16);
}
inline float from_bf16_bits(std::uint16_t b) { return std::bit_cast<float>(static_cast<std::uint32_t>(b) << 16); }

const char* to_string(Activation a);

}  // namespace mppi
