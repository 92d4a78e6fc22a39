// Mlp's bf16 AVX-512 forward pass (dynamics/mlp_avx512_kernels.hpp): the first layer in FP32,
// the others as vdpbf16ps dot products of bf16 pairs with FP32 sums, tanh by fast_tanh_lowp.
// Compiled for AVX512-BF16 by target attribute; Mlp only calls it where
// Mlp::cpu_supports(MlpKernel::kAvx512Bf16) holds (__builtin_cpu_supports("avx512bf16")).
#include "dynamics/mlp.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define MPPI_MLP_BF16
#define MPPI_MLP_TARGET \
  __attribute__((target("avx512f,avx512bw,avx512dq,avx512vl,avx512bf16,avx2,fma")))
#include "dynamics/mlp_avx512_kernels.hpp"

namespace mppi::detail {

MPPI_MLP_TARGET void mlp_forward_avx512_bf16(const Mlp& net, int width, const float* in, float* out,
                                             float* scratch) noexcept {
  const std::vector<DenseLayer>& layers = net.layers();
  const int n = static_cast<int>(layers.size());
  // ceil(n / 2) pair rows of a hidden layer fit in the n rows of floats each buffer has
  const std::ptrdiff_t buffer = static_cast<std::ptrdiff_t>(net.max_hidden()) * width;
  const float* src_f32 = in;  // the first layer reads FP32 inputs
  const std::uint32_t* src_pairs = nullptr;
  for (int l = 0; l < n; ++l) {
    LayerOut dst;
    if (l + 1 == n) dst.f32 = out;
    else dst.pairs = reinterpret_cast<std::uint32_t*>(scratch + (l & 1) * buffer);
    layer<true>(layers[l], src_f32, src_pairs, net.bf16_weights(l).data(), dst, width);
    src_f32 = nullptr;
    src_pairs = dst.pairs;
  }
}

}  // namespace mppi::detail

#else

namespace mppi::detail {
void mlp_forward_avx512_bf16(const Mlp&, int, const float*, float*, float*) noexcept {}
}  // namespace mppi::detail

#endif
