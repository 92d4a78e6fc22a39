#pragma once
// The minimum-time lap as a nonlinear programme: stations along the centreline, their variables
// (laptime/spatial_single_track.hpp's layout), trapezoidal defects between neighbours, the lap
// time and its derivatives. Independent of the solver (laptime/min_time_lap.cpp drives it).
// Closed (a flying lap: the last station joins the first) or open (a standing start: the stations
// run from the first to the last, whose state is free; variables may be fixed, e.g. the start).
#include <utility>
#include <vector>

#include "dynamics/single_track.hpp"

namespace mppi::laptime {

struct CollocationStation {
  double kappa_1pm = 0.0;        // centreline curvature at the station (left turns positive)
  double ds_m = 0.0;             // arc length to the next station (unused on an open problem's last)
  double min_offset_m = 0.0;     // bounds of n
  double max_offset_m = 0.0;
};

class Collocation {
 public:
  Collocation(const SingleTrackParams& vehicle, std::vector<CollocationStation> stations,
              double command_smoothing_s, bool closed = true);

  int stations() const { return static_cast<int>(stations_.size()); }
  bool closed() const { return closed_; }
  int intervals() const { return closed_ ? stations() : stations() - 1; }
  int variables() const;
  int constraints() const;            // var::kStates defects per interval
  int jacobian_nonzeros() const;      // 2 var::kCount per defect row
  const CollocationStation& station(int i) const { return stations_[static_cast<std::size_t>(i)]; }
  const SingleTrackCoeffs<double>& coeffs() const { return k_; }

  // Holds variable `variable` (laptime/spatial_single_track.hpp's var::) of station `station` at
  // `value` (both bounds). Throws mppi::Error for an index out of range.
  void fix(int station, int variable, double value);
  void bounds(double* lo, double* hi) const;
  double lap_time_s(const double* z) const;        // the objective without the smoothing term
  double objective(const double* z) const;
  void objective_gradient(const double* z, double* grad) const;
  void defects(const double* z, double* c) const;
  // Row and column of each nonzero of the defects' Jacobian, then their values in that order.
  void jacobian_structure(int* rows, int* cols) const;
  void jacobian_values(const double* z, double* values) const;

 private:
  double station_weight_m(int i) const;  // half the arc to each neighbour
  // d(state)/ds at station i (var::kStates rows) and its derivative in the station's variables
  // (var::kStates x var::kCount, row-major), by central differences.
  void derivative_and_jacobian(const double* zi, int i, double* g, double* dg_dz) const;

  SingleTrackCoeffs<double> k_;
  std::vector<CollocationStation> stations_;
  double command_smoothing_s_;
  bool closed_ = true;
  std::vector<std::pair<int, double>> fixed_;  // (variable index in z, value)
};

}  // namespace mppi::laptime
