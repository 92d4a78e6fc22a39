// AutoRallyNetwork: loading the npz and the one-time conversion to the library's conventions.
#include <cmath>

#include "base/error.hpp"
#include "base/npz.hpp"
#include "dynamics/autorally_nn.hpp"

namespace mppi {

namespace {
// Network input / output positions of the two quantities whose sign differs between AutoRally
// (yaw_mder = -yaw rate, steering right +) and the library (yaw rate CCW +, steer left +).
constexpr int kInYawRate = 3;
constexpr int kInSteer = 4;
constexpr int kOutYawRate = 3;
}  // namespace

AutoRallyNetwork::AutoRallyNetwork(Mlp net_library_frame) : net_(std::move(net_library_frame)) {
  if (net_.num_inputs() != kNetIn || net_.num_outputs() != kNetOut)
    throw Error("AutoRallyNetwork: the network must map 6 inputs to 4 outputs, has " +
                std::to_string(net_.num_inputs()) + " -> " + std::to_string(net_.num_outputs()));
}

AutoRallyNetwork AutoRallyNetwork::load(const std::string& npz_path) {
  const NpzFile npz = NpzFile::load(npz_path);
  // Exact shapes first, for messages like "array 'dynamics_W2' has shape (16,32), expected (32,32)".
  const std::size_t kHidden = 32;
  npz.at("dynamics_W1", {kHidden, kNetIn});
  npz.at("dynamics_b1", {kHidden});
  npz.at("dynamics_W2", {kHidden, kHidden});
  npz.at("dynamics_b2", {kHidden});
  npz.at("dynamics_W3", {kNetOut, kHidden});
  npz.at("dynamics_b3", {kNetOut});
  const Mlp raw = Mlp::from_npz(npz, "dynamics_", {Activation::kTanh, Activation::kTanh, Activation::kLinear});

  std::vector<DenseLayer> layers = raw.layers();
  DenseLayer& first = layers.front();
  for (int o = 0; o < first.n_out; ++o) {
    first.weights[o * first.n_in + kInYawRate] *= -1.f;  // input yaw_mder = -yaw_rate
    first.weights[o * first.n_in + kInSteer] *= -1.f;    // input steering = -steer_left
  }
  DenseLayer& last = layers.back();
  for (int i = 0; i < last.n_in; ++i) last.weights[kOutYawRate * last.n_in + i] *= -1.f;
  last.bias[kOutYawRate] *= -1.f;  // output d(yaw_mder)/dt = -d(yaw_rate)/dt
  return AutoRallyNetwork(Mlp(std::move(layers)));
}

void AutoRallyNetwork::derivatives(const double* x, const double* u, double* dx) const {
  const double in[kNetIn] = {x[state::kRoll], x[state::kVx], x[state::kVy], x[state::kYawRate],
                             u[control::kSteer], u[control::kThrottle]};
  double out[kNetOut];
  net_.forward_double(in, out);
  const double yaw = x[state::kYaw], vx = x[state::kVx], vy = x[state::kVy];
  dx[state::kX] = std::cos(yaw) * vx - std::sin(yaw) * vy;
  dx[state::kY] = std::sin(yaw) * vx + std::cos(yaw) * vy;
  dx[state::kYaw] = x[state::kYawRate];
  dx[state::kRoll] = out[0];
  dx[state::kVx] = out[1];
  const double extra_force = static_cast<double>(lateral_force_scale_) - 1.0;
  dx[state::kVy] = out[2] + extra_force * (out[2] + vx * x[state::kYawRate]);
  dx[state::kYawRate] = static_cast<double>(lateral_force_scale_) * out[3];
}

bool AutoRallyNetwork::set_param(std::string_view key, double value, std::string* why) {
  if (key != kLateralForceScaleKey) {
    if (why) *why = "the AutoRally network has no parameter \"" + std::string(key) + "\" (it has \"" +
                    std::string(kLateralForceScaleKey) + "\")";
    return false;
  }
  if (!(value >= kMinLateralForceScale && value <= kMaxLateralForceScale)) {
    if (why)
      *why = std::string(kLateralForceScaleKey) + " must be in [" + std::to_string(kMinLateralForceScale) + ", " +
             std::to_string(kMaxLateralForceScale) + "], got " + std::to_string(value);
    return false;
  }
  lateral_force_scale_ = static_cast<float>(value);
  return true;
}

void AutoRallyNetwork::derivatives_autorally_frame(const double s[7], const double u[2], double out[4]) const {
  // s = [x, y, yaw, roll, u_x, u_y, yaw_mder]; u = [steering (right +), throttle]
  const double in[kNetIn] = {s[3], s[4], s[5], -s[6], -u[0], u[1]};
  double lib[kNetOut];
  net_.forward_double(in, lib);
  out[0] = lib[0];
  out[1] = lib[1];
  out[2] = lib[2];
  out[3] = -lib[3];
}

}  // namespace mppi
