#include "laptime/collocation.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

#include "base/error.hpp"
#include "laptime/spatial_single_track.hpp"

namespace mppi::laptime {
namespace {

constexpr int kNz = var::kCount;
constexpr int kNs = var::kStates;

}  // namespace

Collocation::Collocation(const SingleTrackParams& vehicle, std::vector<CollocationStation> stations,
                         double command_smoothing_s, bool closed)
    : stations_(std::move(stations)), command_smoothing_s_(command_smoothing_s), closed_(closed) {
  std::string why;
  if (!vehicle.is_valid(&why)) throw Error("min_time_lap: invalid vehicle parameters: " + why);
  if (stations_.size() < 8) throw Error("min_time_lap: needs at least 8 stations");
  if (!(std::isfinite(command_smoothing_s_) && command_smoothing_s_ >= 0.0))
    throw Error("min_time_lap: command_smoothing_s must be finite and >= 0");
  k_ = SingleTrackCoeffs<double>::from(vehicle);
}

int Collocation::variables() const { return stations() * kNz; }
int Collocation::constraints() const { return intervals() * kNs; }
int Collocation::jacobian_nonzeros() const { return constraints() * 2 * kNz; }

double Collocation::station_weight_m(int i) const {
  const int n = stations();
  const bool has_previous = closed_ || i > 0, has_next = closed_ || i < n - 1;
  return 0.5 * ((has_previous ? stations_[static_cast<std::size_t>((i + n - 1) % n)].ds_m : 0.0) +
                (has_next ? stations_[static_cast<std::size_t>(i)].ds_m : 0.0));
}

void Collocation::fix(int station, int variable, double value) {
  if (station < 0 || station >= stations() || variable < 0 || variable >= kNz)
    throw Error("min_time_lap: cannot fix variable " + std::to_string(variable) + " of station " +
                std::to_string(station) + " (" + std::to_string(stations()) + " stations)");
  fixed_.emplace_back(station * kNz + variable, value);
}

void Collocation::bounds(double* lo, double* hi) const {
  // Wide boxes on the dynamic states: they keep the solver off singular points (a car standing
  // or turned across the road) and never bind on a lap.
  const double state_lo[kNz] = {0, -1.2, 0.5, -8.0, -15.0, 0.0, 0.0, -1.0, -1.0};
  const double state_hi[kNz] = {0, 1.2, 40.0, 8.0, 15.0, 500.0, 500.0, 1.0, 1.0};
  for (int i = 0; i < stations(); ++i) {
    for (int v = 0; v < kNz; ++v) {
      lo[i * kNz + v] = state_lo[v];
      hi[i * kNz + v] = state_hi[v];
    }
    lo[i * kNz + var::kOffset] = stations_[static_cast<std::size_t>(i)].min_offset_m;
    hi[i * kNz + var::kOffset] = stations_[static_cast<std::size_t>(i)].max_offset_m;
  }
  for (const auto& [index, value] : fixed_) lo[index] = hi[index] = value;
}

double Collocation::lap_time_s(const double* z) const {
  double t = 0.0;
  for (int i = 0; i < stations(); ++i)
    t += station_weight_m(i) / centreline_speed_mps(z + i * kNz, stations_[static_cast<std::size_t>(i)].kappa_1pm);
  return t;
}

double Collocation::objective(const double* z) const {
  double smooth = 0.0;
  const int n = stations();
  for (int i = 0; i < intervals(); ++i) {
    const double* a = z + i * kNz;
    const double* b = z + ((i + 1) % n) * kNz;
    for (int v : {var::kSteer, var::kThrottle}) smooth += (b[v] - a[v]) * (b[v] - a[v]);
  }
  return lap_time_s(z) + command_smoothing_s_ * smooth;
}

void Collocation::objective_gradient(const double* z, double* grad) const {
  const int n = stations();
  std::fill(grad, grad + variables(), 0.0);
  for (int i = 0; i < n; ++i) {
    const double* zi = z + i * kNz;
    double* gi = grad + i * kNz;
    const double kappa = stations_[static_cast<std::size_t>(i)].kappa_1pm;
    const double w = station_weight_m(i);
    // w / sdot = w (1 - n kappa) / D, D = vx cos xi - vy sin xi
    const double sx = std::sin(zi[var::kHeadingError]), cx = std::cos(zi[var::kHeadingError]);
    const double vx = zi[var::kVx], vy = zi[var::kVy];
    const double d = vx * cx - vy * sx;
    const double a = 1.0 - zi[var::kOffset] * kappa;
    gi[var::kOffset] += -w * kappa / d;
    gi[var::kHeadingError] += -w * a * (-vx * sx - vy * cx) / (d * d);
    gi[var::kVx] += -w * a * cx / (d * d);
    gi[var::kVy] += w * a * sx / (d * d);
    if (i >= intervals()) continue;  // an open problem's last station has no next
    const double* zn = z + ((i + 1) % n) * kNz;
    double* gn = grad + ((i + 1) % n) * kNz;
    for (int v : {var::kSteer, var::kThrottle}) {
      const double diff = zn[v] - zi[v];
      gn[v] += 2.0 * command_smoothing_s_ * diff;
      gi[v] -= 2.0 * command_smoothing_s_ * diff;
    }
  }
}

void Collocation::derivative_and_jacobian(const double* zi, int i, double* g, double* dg_dz) const {
  const double kappa = stations_[static_cast<std::size_t>(i)].kappa_1pm;
  spatial_derivative(k_, zi, kappa, g);
  double z[kNz], gp[kNs], gm[kNs];
  std::copy(zi, zi + kNz, z);
  for (int v = 0; v < kNz; ++v) {
    const double h = 1e-6 * std::max(1.0, std::abs(zi[v]));
    z[v] = zi[v] + h;
    spatial_derivative(k_, z, kappa, gp);
    z[v] = zi[v] - h;
    spatial_derivative(k_, z, kappa, gm);
    z[v] = zi[v];
    for (int r = 0; r < kNs; ++r) dg_dz[r * kNz + v] = (gp[r] - gm[r]) / (2.0 * h);
  }
}

void Collocation::defects(const double* z, double* c) const {
  const int n = stations();
  std::vector<double> g(static_cast<std::size_t>(n) * kNs);
  for (int i = 0; i < n; ++i)
    spatial_derivative(k_, z + i * kNz, stations_[static_cast<std::size_t>(i)].kappa_1pm, &g[static_cast<std::size_t>(i) * kNs]);
  for (int i = 0; i < intervals(); ++i) {
    const int j = (i + 1) % n;
    const double half_ds = 0.5 * stations_[static_cast<std::size_t>(i)].ds_m;
    for (int r = 0; r < kNs; ++r)
      c[i * kNs + r] = z[j * kNz + r] - z[i * kNz + r] -
                       half_ds * (g[static_cast<std::size_t>(i) * kNs + r] + g[static_cast<std::size_t>(j) * kNs + r]);
  }
}

// Row i * kNs + r: first the kNz columns of station i, then those of station i + 1.
void Collocation::jacobian_structure(int* rows, int* cols) const {
  const int n = stations();
  int k = 0;
  for (int i = 0; i < intervals(); ++i) {
    const int j = (i + 1) % n;
    for (int r = 0; r < kNs; ++r) {
      for (int v = 0; v < kNz; ++v, ++k) {
        rows[k] = i * kNs + r;
        cols[k] = i * kNz + v;
      }
      for (int v = 0; v < kNz; ++v, ++k) {
        rows[k] = i * kNs + r;
        cols[k] = j * kNz + v;
      }
    }
  }
}

void Collocation::jacobian_values(const double* z, double* values) const {
  const int n = stations();
  std::vector<double> g(static_cast<std::size_t>(n) * kNs), dg(static_cast<std::size_t>(n) * kNs * kNz);
  for (int i = 0; i < n; ++i)
    derivative_and_jacobian(z + i * kNz, i, &g[static_cast<std::size_t>(i) * kNs], &dg[static_cast<std::size_t>(i) * kNs * kNz]);
  int k = 0;
  for (int i = 0; i < intervals(); ++i) {
    const int j = (i + 1) % n;
    const double half_ds = 0.5 * stations_[static_cast<std::size_t>(i)].ds_m;
    const double* dgi = &dg[static_cast<std::size_t>(i) * kNs * kNz];
    const double* dgj = &dg[static_cast<std::size_t>(j) * kNs * kNz];
    for (int r = 0; r < kNs; ++r) {
      for (int v = 0; v < kNz; ++v, ++k) values[k] = (v == r ? -1.0 : 0.0) - half_ds * dgi[r * kNz + v];
      for (int v = 0; v < kNz; ++v, ++k) values[k] = (v == r ? 1.0 : 0.0) - half_ds * dgj[r * kNz + v];
    }
  }
}

}  // namespace mppi::laptime
