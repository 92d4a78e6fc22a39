// Mlp's FP32 AVX-512 forward pass (dynamics/mlp_avx512_kernels.hpp) and the CPU check.
// Compiled for AVX-512 by target attribute, not by flags: the rest of the library stays
// baseline x86-64 and Mlp only calls this where cpu_supports() says the CPU has AVX-512.
#include "dynamics/mlp.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define MPPI_MLP_TARGET __attribute__((target("avx512f,avx512bw,avx512dq,avx512vl,avx2,fma")))
#include "dynamics/mlp_avx512_kernels.hpp"

namespace mppi {

bool Mlp::cpu_supports(MlpKernel kernel) {
  __builtin_cpu_init();
  const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
                      __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl");
  switch (kernel) {
    case MlpKernel::kPortable: return true;
    case MlpKernel::kAvx512: return avx512;
    case MlpKernel::kAvx512Bf16: return avx512 && __builtin_cpu_supports("avx512bf16");
  }
  return false;
}

namespace detail {

MPPI_MLP_TARGET void mlp_forward_avx512(const Mlp& net, int width, const float* in, float* out,
                                        float* scratch) noexcept {
  const std::vector<DenseLayer>& layers = net.layers();
  const int n = static_cast<int>(layers.size());
  const std::ptrdiff_t buffer = static_cast<std::ptrdiff_t>(net.max_hidden()) * width;
  const float* src = in;
  for (int l = 0; l < n; ++l) {
    float* dst = l + 1 == n ? out : scratch + (l & 1) * buffer;
    layer<false>(layers[l], src, nullptr, nullptr, LayerOut{dst, nullptr}, width);
    src = dst;
  }
}

}  // namespace detail
}  // namespace mppi

#else  // not x86-64: the portable code only

namespace mppi {
bool Mlp::cpu_supports(MlpKernel kernel) { return kernel == MlpKernel::kPortable; }
namespace detail {
void mlp_forward_avx512(const Mlp&, int, const float*, float*, float*) noexcept {}
}  // namespace detail
}  // namespace mppi

#endif
