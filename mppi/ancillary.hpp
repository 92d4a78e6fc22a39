#pragma once
// The weights of the ancillary feedback controller of Tube-MPPI / Robust MPPI: a time-varying
// LQR along the nominal plan (mppi/lqr.hpp) with the cost
//   sum_t (dx_t' Q dx_t + du_t' R du_t) + dx_T' (terminal_scale Q) dx_T,
// dx = x - x_nom, du = u - u_nom. Its gains K_t give u_t = u_nom_t + K_t (x_t - x_nom_t).
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace mppi {

struct AncillaryWeights {
  std::vector<float> q_diag;  // per state, >= 0; empty: 1 on every state
  std::vector<float> r_diag;  // per control, > 0; empty: 1 on every control
  float terminal_scale = 1.f;  // Qf = terminal_scale * Q, >= 0
};

// True if w fits a model with nx states and nu controls; else false with the reason in *why
// (naming the field).
inline bool check_ancillary_weights(const AncillaryWeights& w, int nx, int nu, std::string* why) {
  auto fail = [&](const std::string& reason) {
    if (why) *why = "ancillary weights: " + reason;
    return false;
  };
  if (!w.q_diag.empty() && w.q_diag.size() != static_cast<std::size_t>(nx))
    return fail("q_diag has " + std::to_string(w.q_diag.size()) + " entries, the model has " +
                std::to_string(nx) + " states");
  if (!w.r_diag.empty() && w.r_diag.size() != static_cast<std::size_t>(nu))
    return fail("r_diag has " + std::to_string(w.r_diag.size()) + " entries, the model has " +
                std::to_string(nu) + " controls");
  for (std::size_t i = 0; i < w.q_diag.size(); ++i)
    if (!(std::isfinite(w.q_diag[i]) && w.q_diag[i] >= 0.f))
      return fail("q_diag[" + std::to_string(i) + "] must be finite and >= 0");
  for (std::size_t i = 0; i < w.r_diag.size(); ++i)
    if (!(std::isfinite(w.r_diag[i]) && w.r_diag[i] > 0.f))
      return fail("r_diag[" + std::to_string(i) + "] must be finite and > 0");
  if (!(std::isfinite(w.terminal_scale) && w.terminal_scale >= 0.f))
    return fail("terminal_scale must be finite and >= 0");
  return true;
}

}  // namespace mppi
