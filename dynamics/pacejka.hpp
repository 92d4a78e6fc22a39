#pragma once
// The tyre model of the AutoRally paper ("Tire Force Model", after Velenis 2010): slips as
// non-dimensional relative velocities, Pacejka's Magic Formula on the total slip, and the
// friction force split along the slip direction. Header-only; templated on the scalar so
// that the batched model runs it in float (fast branch-free math) and the reference and
// diagnostics in double (libm).
#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "base/fast_math.hpp"
#include "dynamics/fast_trig.hpp"

namespace mppi {

// Scalar math of the physics models, overloaded on precision: float -> the branch-free
// approximations (vectorise in lane loops, ~1e-7 error), double -> libm.
namespace phys {
inline float atan(float x) noexcept { return fast_atan(x); }
inline double atan(double x) noexcept { return std::atan(x); }
inline float tanh(float x) noexcept { return fast_tanh(x); }
inline double tanh(double x) noexcept { return std::tanh(x); }
inline float sqrt(float x) noexcept { return fast_sqrt(x); }
inline double sqrt(double x) noexcept { return std::sqrt(x); }
inline void sincos(float x, float* s, float* c) noexcept { fast_sincos(x, s, c); }
inline void sincos(double x, double* s, double* c) noexcept {
  *s = std::sin(x);
  *c = std::cos(x);
}
template <class T>
inline T sin(T x) noexcept {
  T s, c;
  sincos(x, &s, &c);
  return s;
}
}  // namespace phys

// Magic Formula coefficients; defaults are the paper's identified AutoRally values (tyre table).
struct PacejkaParams {
  double B = 1.1559;    // stiffness factor [-]
  double C = 1.1924;    // shape factor [-]
  double D = 0.9956;    // peak factor [-]
  double E = -0.8505;   // curvature factor [-]
  double Sh = -0.0540;  // horizontal shift [-], slip units (the paper's table says "m")
  double Sv = 0.1444;   // vertical shift [-], friction units (the paper's table says "m")

  bool is_valid(std::string* why) const;
};

template <class T>
struct PacejkaCoeffs {
  T B, C, D, E, Sh, Sv;
  static PacejkaCoeffs from(const PacejkaParams& p) noexcept {
    return {static_cast<T>(p.B), static_cast<T>(p.C), static_cast<T>(p.D),
            static_cast<T>(p.E), static_cast<T>(p.Sh), static_cast<T>(p.Sv)};
  }
};

// Friction coefficient from the total slip s >= 0 (paper eq. MF):
//   mu = D sin(C atan(B S_E - E (B S_E - atan S_E))) + S_v,  S_E = s - S_h.
// With the paper's values mu(0) = 0.2268 (not 0): see tyre_friction for what that implies.
template <class T>
inline T magic_formula_mu(T total_slip, const PacejkaCoeffs<T>& p) noexcept {
  const T se = total_slip - p.Sh;
  const T bse = p.B * se;
  return p.D * phys::sin(p.C * phys::atan(bse - p.E * (bse - phys::atan(se)))) + p.Sv;
}

// One tyre's slips and friction coefficients (force / normal load).
template <class T>
struct TyreFriction {
  T slip_x;  // longitudinal slip s_x [-]
  T slip_y;  // lateral slip s_y [-]
  T slip;    // total slip s = |(s_x, s_y)| [-]
  T mu;      // Magic Formula coefficient mu(s) [-]
  T mu_x;    // f_x / f_z [-], tyre frame, forward positive
  T mu_y;    // f_y / f_z [-], tyre frame, left positive
};

// Slips and friction of one tyre from its tyre-frame velocity (v_x forward, v_y left, at the
// contact patch) and its rim speed omega R. The paper writes
//   s_x = (V_x - omega R) / (omega R),  s_y = V_y / (omega R),  f_k = -(s_k / s) mu(s) f_z.
// Two regularisations, only where that is singular:
//  * denominator max(|omega R|, v_floor) instead of omega R: finite at a locked or still wheel;
//    |.| keeps the force opposing the contact-patch sliding velocity when rolling backwards;
//    the floor bounds the slip stiffness d s / d omega ~ 1 / v_floor, which is what keeps
//    explicit Euler at the controller's 0.02 s stable (see SingleTrackParams).
//  * s_k / s is undefined at s = 0 while mu(0) != 0 (a Coulomb-like jump). We use
//    f_k = -(s_k / s) mu(s) tanh(s / eps) f_z: identical to the paper for s >> eps
//    (tanh(3) = 0.995), zero at s = 0, Lipschitz (slope mu(0)/eps at 0), and computed as
//    s_k * tanh(s/eps) / max(s, 1e-12) so that no 0/0 occurs.
// Branch-free; noexcept; used per lane.
template <class T>
inline TyreFriction<T> tyre_friction(T v_x_mps, T v_y_mps, T rim_speed_mps, T slip_speed_floor_mps,
                                     T inv_slip_blend, const PacejkaCoeffs<T>& p) noexcept {
  TyreFriction<T> f;
  const T inv_den = T(1) / std::max(std::abs(rim_speed_mps), slip_speed_floor_mps);
  f.slip_x = (v_x_mps - rim_speed_mps) * inv_den;
  f.slip_y = v_y_mps * inv_den;
  f.slip = phys::sqrt(f.slip_x * f.slip_x + f.slip_y * f.slip_y);
  f.mu = magic_formula_mu(f.slip, p);
  const T scale = -f.mu * phys::tanh(f.slip * inv_slip_blend) / std::max(f.slip, T(1e-12));
  f.mu_x = f.slip_x * scale;
  f.mu_y = f.slip_y * scale;
  return f;
}

inline bool PacejkaParams::is_valid(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  for (double v : {B, C, D, E, Sh, Sv})
    if (!std::isfinite(v)) return fail("tyre: Pacejka coefficients must be finite");
  if (!(B > 0)) return fail("tyre: B (stiffness factor) must be > 0");
  if (!(C > 0 && C < 2)) return fail("tyre: C (shape factor) must be in (0, 2)");
  if (!(D > 0)) return fail("tyre: D (peak factor) must be > 0");
  if (!(E < 1)) return fail("tyre: E (curvature factor) must be < 1");
  // A tyre that pushes along the slip (mu < 0) would feed energy in: refuse it. The sampled check
  // costs some 10^4 transcendental calls, and a fit builds thousands of models of a few tyres:
  // the last tyres that passed are remembered (per thread, exact match only).
  const std::array<double, 6> key{B, C, D, E, Sh, Sv};
  constexpr std::size_t kRemembered = 8;
  thread_local std::array<std::array<double, 6>, kRemembered> passed{};
  thread_local std::size_t passed_count = 0;
  for (std::size_t i = 0; i < std::min(passed_count, kRemembered); ++i)
    if (passed[i] == key) return true;
  const auto c = PacejkaCoeffs<double>::from(*this);
  for (int i = 0; i <= 4000; ++i) {
    const double s = 0.01 * i;  // [0, 40]
    if (!(magic_formula_mu(s, c) >= 0))
      return fail("tyre: mu(s) must be >= 0 for slips in [0, 40] (negative at s = " +
                  std::to_string(s) + ")");
  }
  passed[passed_count++ % kRemembered] = key;
  return true;
}

}  // namespace mppi
