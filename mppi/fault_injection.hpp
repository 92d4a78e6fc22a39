#pragma once
// A backend decorator that fails like a lost device: its first `healthy_calls` rollout() or
// iterate() calls go to the wrapped backend, every later one throws mppi::Error, and so do cost
// changes after that (a lost device stays lost). Used to test that Controller::step() turns backend failures into a status and
// falls back to the CPU backend (Controller::inject_device_loss, mppi-sim
// --inject-device-loss-at-step).
#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "base/error.hpp"
#include "mppi/backend.hpp"

namespace mppi {

class DeviceLossInjector final : public Backend {
 public:
  DeviceLossInjector(std::unique_ptr<Backend> inner, std::uint64_t healthy_calls)
      : inner_(std::move(inner)), healthy_calls_(healthy_calls) {
    if (!inner_) throw Error("DeviceLossInjector: no backend");
  }

  const char* name() const override { return inner_->name(); }
  const RolloutShape& shape() const override { return inner_->shape(); }
  void rollout(std::span<const float> x0, std::span<const float> controls,
               std::span<float> costs) override {
    count_call();
    inner_->rollout(x0, controls, costs);
  }
  bool has_iterate() const override { return inner_->has_iterate(); }
  bool supports_augmented_sampling() const override { return inner_->supports_augmented_sampling(); }
  void iterate(const IterationInput& in, IterationOutput& out) override {
    count_call();
    inner_->iterate(in, out);
  }
  std::span<const float> sampled_controls() const override { return inner_->sampled_controls(); }
  bool copy_sampled_controls(std::span<const int> samples, std::span<float> out) const override {
    return inner_->copy_sampled_controls(samples, out);
  }
  bool set_model_param(std::string_view key, double value, std::string* why) override {
    if (calls_ > healthy_calls_) throw_lost();
    return inner_->set_model_param(key, value, why);
  }
  bool predict_step(std::span<const float> x0, std::span<const float> u, std::span<float> x1,
                    std::string* why) override {
    if (calls_ > healthy_calls_) throw_lost();
    return inner_->predict_step(x0, u, x1, why);
  }
  bool set_cost_param(std::string_view key, double value, std::string* why) override {
    if (calls_ > healthy_calls_) throw_lost();
    return inner_->set_cost_param(key, value, why);
  }
  bool set_cost_map(std::shared_ptr<const CostMap> map, std::string* why) override {
    if (calls_ > healthy_calls_) throw_lost();
    return inner_->set_cost_map(std::move(map), why);
  }

 private:
  void count_call() {
    if (calls_++ >= healthy_calls_) throw_lost();
  }
  [[noreturn]] void throw_lost() const {
    throw Error(std::string(inner_->name()) + " backend: device lost (VK_ERROR_DEVICE_LOST, injected after " +
                std::to_string(healthy_calls_) + " calls)");
  }

  std::unique_ptr<Backend> inner_;
  std::uint64_t healthy_calls_;
  std::uint64_t calls_ = 0;
};

}  // namespace mppi
