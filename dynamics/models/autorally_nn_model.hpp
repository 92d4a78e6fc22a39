#pragma once
// The AutoRally neural network (dynamics/autorally_nn.hpp) as the registry knows it.
#include <cstddef>
#include <string>
#include <vector>

#include "dynamics/autorally_nn.hpp"
#include "dynamics/model_descriptor.hpp"

namespace mppi::models {

struct AutoRallyNetworkModel : WeightsFileDescriptor<AutoRallyNetworkModel, AutoRallyNetwork> {
  static constexpr const char* kName = "autorally-nn";
  static constexpr const char* kSummary = "the AutoRally car's neural network (6-32-32-4, tanh), learned from real driving";
  static constexpr const char* kDefaultFile = "autorally/models/autorally_nnet_09_12_2018.npz";

  // GPU twin: vulkan/shaders/models/autorally_nn.glsl, a 6-H1-H2-4 tanh-tanh-linear MLP. Each
  // layer as W with every row padded to a multiple of 4 floats, then b padded to a multiple of
  // 4 (the shader reads 4 weights at a time); H1, H2 are shader constants.
  static constexpr const char* kGpuKernel = "autorally_nn";
  static std::vector<GpuField<Model>> gpu_fields() { return {}; }
  static bool gpu_tail(const Model& m, GpuTail& tail, std::string* why) {
    const std::vector<DenseLayer>& layers = m.network().layers();
    auto fail = [&](const std::string& msg) {
      if (why) *why = "no GPU twin for this network: " + msg;
      return false;
    };
    if (layers.size() != 3)
      return fail("the shader runs 3 layers, the network has " + std::to_string(layers.size()));
    if (layers[0].activation != Activation::kTanh || layers[1].activation != Activation::kTanh ||
        layers[2].activation != Activation::kLinear)
      return fail("the shader runs tanh, tanh, linear layers");
    const int h1 = layers[0].n_out, h2 = layers[1].n_out;
    if (h1 > 128 || h2 > 128) return fail("hidden layers wider than 128");
    tail.constant_a = h1;
    tail.constant_b = h2;
    auto pad4 = [](int n) { return (n + 3) / 4 * 4; };
    for (const DenseLayer& l : layers) {
      for (int o = 0; o < l.n_out; ++o) {
        const auto row = l.weights.begin() + static_cast<std::ptrdiff_t>(o) * l.n_in;
        tail.floats.insert(tail.floats.end(), row, row + l.n_in);
        tail.floats.resize(tail.floats.size() + static_cast<std::size_t>(pad4(l.n_in) - l.n_in), 0.f);
      }
      tail.floats.insert(tail.floats.end(), l.bias.begin(), l.bias.end());
      tail.floats.resize(tail.floats.size() + static_cast<std::size_t>(pad4(l.n_out) - l.n_out), 0.f);
    }
    return true;
  }
};
MPPI_REGISTER_MODEL(AutoRallyNetworkModel);

}  // namespace mppi::models
