// Drives a double integrator to the origin with the installed header-only core; exits 0 only
// if the controller pushes the state the right way.
#include <cstdio>

#include <mppi/controller.hpp>

struct Integrator {
  static constexpr int kNx = 2, kNu = 1;
  std::size_t scratch_floats(int) const { return 0; }
  template <int W>
  void step(mppi::Batch<2, W> x, mppi::ConstBatch<1, W> u, float dt, float*) const noexcept {
    for (int j = 0; j < W; ++j) { x[0][j] += dt * x[1][j]; x[1][j] += dt * u[0][j]; }
  }
};
struct Cost {
  template <int Nx, int Nu, int W>
  void accumulate(mppi::ConstBatch<Nx, W> x, mppi::ConstBatch<Nu, W>, int, float* c) const noexcept {
    for (int j = 0; j < W; ++j) c[j] += x[0][j] * x[0][j];
  }
};

int main() {
  mppi::ControllerOptions o;
  o.num_samples = 256; o.horizon = 20; o.dt_s = 0.1f; o.lambda = 0.1f;
  o.noise_std = {1.f}; o.control_min = {-5.f}; o.control_max = {5.f}; o.safe_control = {0.f};
  auto controller = mppi::make_cpu_controller(Integrator{}, Cost{}, o);
  const float x0[2] = {1.f, 0.f};
  const float u = controller.step(x0)[0];
  std::printf("u0 = %f\n", u);
  return u < -0.1f ? 0 : 1;
}
