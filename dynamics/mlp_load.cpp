// Mlp construction with validation, loading from npz, and the double-precision evaluation.
#include <algorithm>
#include <cmath>

#include "base/error.hpp"
#include "base/npz.hpp"
#include "dynamics/mlp.hpp"

namespace mppi {

const char* to_string(Activation a) {
  switch (a) {
    case Activation::kTanh: return "tanh";
    case Activation::kRelu: return "relu";
    case Activation::kLinear: return "linear";
  }
  return "?";
}

Mlp::Mlp(std::vector<DenseLayer> layers) : layers_(std::move(layers)) {
  if (layers_.empty()) throw Error("Mlp: no layers");
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    const DenseLayer& L = layers_[l];
    const std::string name = "Mlp: layer " + std::to_string(l + 1) + " ";
    if (L.n_in < 1 || L.n_out < 1)
      throw Error(name + "has " + std::to_string(L.n_in) + " inputs and " + std::to_string(L.n_out) +
                  " outputs (need >= 1 each)");
    if (L.weights.size() != static_cast<std::size_t>(L.n_in) * static_cast<std::size_t>(L.n_out))
      throw Error(name + "has " + std::to_string(L.weights.size()) + " weights, expected " +
                  std::to_string(L.n_out) + " x " + std::to_string(L.n_in));
    if (L.bias.size() != static_cast<std::size_t>(L.n_out))
      throw Error(name + "has " + std::to_string(L.bias.size()) + " biases, expected " +
                  std::to_string(L.n_out));
    if (l > 0 && L.n_in != layers_[l - 1].n_out)
      throw Error(name + "has " + std::to_string(L.n_in) + " inputs but layer " + std::to_string(l) +
                  " has " + std::to_string(layers_[l - 1].n_out) + " outputs");
    const auto finite = [](float v) { return std::isfinite(v); };
    if (!std::all_of(L.weights.begin(), L.weights.end(), finite) ||
        !std::all_of(L.bias.begin(), L.bias.end(), finite))
      throw Error(name + "has non-finite weights or biases");
    if (l + 1 < layers_.size()) max_hidden_ = std::max(max_hidden_, L.n_out);
  }
  bf16_weights_.resize(layers_.size());
  for (std::size_t l = 1; l < layers_.size(); ++l) {
    const DenseLayer& L = layers_[l];
    const int n_pairs = (L.n_in + 1) / 2;
    std::vector<std::uint32_t>& packed = bf16_weights_[l];
    packed.assign(static_cast<std::size_t>(L.n_out) * static_cast<std::size_t>(n_pairs), 0u);
    for (int o = 0; o < L.n_out; ++o)
      for (int i = 0; i < L.n_in; ++i) {
        const std::uint32_t b = to_bf16_bits(L.weights[static_cast<std::size_t>(o) * L.n_in + i]);
        packed[static_cast<std::size_t>(o) * n_pairs + i / 2] |= b << (16 * (i % 2));
      }
  }
  kernel_ = cpu_supports(MlpKernel::kAvx512) ? MlpKernel::kAvx512 : MlpKernel::kPortable;
}

bool Mlp::set_kernel(MlpKernel kernel) {
  if (!cpu_supports(kernel)) return false;
  kernel_ = kernel;
  return true;
}

bool Mlp::set_precision(NetPrecision precision) {
  if (precision == NetPrecision::kBf16) return set_kernel(MlpKernel::kAvx512Bf16);
  if (!set_kernel(MlpKernel::kAvx512)) kernel_ = MlpKernel::kPortable;
  return true;
}

Mlp Mlp::from_npz(const NpzFile& npz, const std::string& prefix, const std::vector<Activation>& activations) {
  if (activations.empty()) throw Error(npz.path() + ": Mlp::from_npz needs at least one activation");
  std::vector<DenseLayer> layers;
  for (std::size_t l = 0; l < activations.size(); ++l) {
    const std::string w_key = prefix + "W" + std::to_string(l + 1);
    const std::string b_key = prefix + "b" + std::to_string(l + 1);
    const NpyArray& w = npz.at(w_key);
    if (w.shape.size() != 2 || w.shape[0] == 0 || w.shape[1] == 0)
      throw Error(npz.path() + ": array '" + w_key + "' must be a non-empty 2-D (out, in) matrix, has " +
                  std::to_string(w.shape.size()) + " dimensions");
    DenseLayer layer;
    layer.n_out = static_cast<int>(w.shape[0]);
    layer.n_in = static_cast<int>(w.shape[1]);
    if (l > 0 && layer.n_in != layers.back().n_out)
      throw Error(npz.path() + ": array '" + w_key + "' has shape (" + std::to_string(w.shape[0]) + "," +
                  std::to_string(w.shape[1]) + "), expected (n," + std::to_string(layers.back().n_out) +
                  ") to follow " + prefix + "W" + std::to_string(l) + " (" +
                  std::to_string(layers.back().n_out) + " outputs)");
    const NpyArray& b = npz.at(b_key, {w.shape[0]});
    layer.weights.assign(w.values.begin(), w.values.end());
    layer.bias.assign(b.values.begin(), b.values.end());
    layer.activation = activations[l];
    // Check finiteness on the float values (a huge double becomes inf).
    const auto finite = [](float v) { return std::isfinite(v); };
    if (!std::all_of(layer.weights.begin(), layer.weights.end(), finite))
      throw Error(npz.path() + ": array '" + w_key + "' holds non-finite values (as float)");
    if (!std::all_of(layer.bias.begin(), layer.bias.end(), finite))
      throw Error(npz.path() + ": array '" + b_key + "' holds non-finite values (as float)");
    layers.push_back(std::move(layer));
  }
  const std::string extra = prefix + "W" + std::to_string(activations.size() + 1);
  if (npz.contains(extra))
    throw Error(npz.path() + ": has a layer '" + extra + "' beyond the " +
                std::to_string(activations.size()) + " activations given");
  return Mlp(std::move(layers));
}

void Mlp::forward_double(const double* in, double* out) const {
  std::vector<double> a(in, in + num_inputs()), next;
  for (const DenseLayer& L : layers_) {
    next.assign(static_cast<std::size_t>(L.n_out), 0.0);
    for (int o = 0; o < L.n_out; ++o) {
      double s = L.bias[o];
      for (int i = 0; i < L.n_in; ++i) s += static_cast<double>(L.weights[o * L.n_in + i]) * a[i];
      switch (L.activation) {
        case Activation::kTanh: s = std::tanh(s); break;
        case Activation::kRelu: s = std::max(s, 0.0); break;
        case Activation::kLinear: break;
      }
      next[o] = s;
    }
    a.swap(next);
  }
  std::copy(a.begin(), a.end(), out);
}

}  // namespace mppi
