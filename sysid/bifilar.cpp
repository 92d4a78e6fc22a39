#include "sysid/bifilar.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "base/error.hpp"

namespace mppi::sysid {

namespace {
void require_positive(double v, const char* what) {
  if (!(std::isfinite(v) && v > 0)) throw Error(std::string("bifilar: ") + what + " must be > 0");
}
}  // namespace

double bifilar_inertia(double mass_kg, double period_s, double r1_m, double r2_m, double height_m,
                       double gravity_mps2) {
  require_positive(mass_kg, "mass");
  require_positive(period_s, "period");
  require_positive(r1_m, "R1");
  require_positive(r2_m, "R2");
  require_positive(height_m, "h");
  require_positive(gravity_mps2, "g");
  const double pi = std::numbers::pi;
  return mass_kg * gravity_mps2 * r1_m * r2_m * period_s * period_s / (4 * pi * pi * height_m);
}

double bifilar_inertia_parallel(double mass_kg, double period_s, double half_separation_m,
                                double wire_length_m, double gravity_mps2) {
  return bifilar_inertia(mass_kg, period_s, half_separation_m, half_separation_m, wire_length_m,
                         gravity_mps2);
}

double bifilar_height(double wire_length_m, double r1_m, double r2_m) {
  require_positive(wire_length_m, "d");
  const double offset = r1_m - r2_m;
  if (!(std::abs(offset) < wire_length_m)) throw Error("bifilar: |R1 - R2| must be < d");
  return std::sqrt(wire_length_m * wire_length_m - offset * offset);
}

double bifilar_period(double inertia_kgm2, double mass_kg, double r1_m, double r2_m,
                      double height_m, double gravity_mps2) {
  require_positive(inertia_kgm2, "inertia");
  // I is proportional to T^2: scale from the inertia at T = 1 s.
  return std::sqrt(inertia_kgm2 / bifilar_inertia(mass_kg, 1.0, r1_m, r2_m, height_m, gravity_mps2));
}

std::vector<BifilarRow> autorally_bifilar_table() {
  const double m = 21.88, front_pair = 2 * 0.82, rear_pair = 2 * 0.89;
  //        axis   T     b      d      mass        MOI    dT     db      dd      dI
  return {{"I_x", 2.63, 0.14, 1.90, m, 0.347, 0.01, 0.01, 0.01, 0.001},
          {"I_y", 2.12, 0.295, 1.88, m, 1.131, 0.01, 0.001, 0.01, 0.001},
          {"I_z", 2.48, 0.26, 1.93, m, 1.124, 0.01, 0.01, 0.01, 0.001},
          {"I_f", 1.81, 0.182, 0.935, front_pair, 0.048, 0.01, 0.001, 0.001, 0.001},
          {"I_r", 1.67, 0.182, 0.915, rear_pair, 0.044, 0.01, 0.001, 0.001, 0.001}};
}

BifilarCheck check_bifilar_row(const BifilarRow& r, double g) {
  BifilarCheck c;
  c.computed_kgm2 = bifilar_inertia_parallel(r.mass_kg, r.period_s, r.half_separation_m, r.wire_length_m, g);
  c.relative_diff = c.computed_kgm2 / r.printed_kgm2 - 1;
  // I is monotone in each of T, b (increasing) and d (decreasing): the box corners bound it.
  c.min_kgm2 = bifilar_inertia_parallel(r.mass_kg, r.period_s - r.period_step / 2,
                                        r.half_separation_m - r.separation_step / 2,
                                        r.wire_length_m + r.length_step / 2, g);
  c.max_kgm2 = bifilar_inertia_parallel(r.mass_kg, r.period_s + r.period_step / 2,
                                        r.half_separation_m + r.separation_step / 2,
                                        r.wire_length_m - r.length_step / 2, g);
  const double lo = r.printed_kgm2 - r.printed_step / 2, hi = r.printed_kgm2 + r.printed_step / 2;
  c.consistent = c.max_kgm2 >= lo && c.min_kgm2 <= hi;
  c.period_for_printed_s = bifilar_period(r.printed_kgm2, r.mass_kg, r.half_separation_m,
                                          r.half_separation_m, r.wire_length_m, g);
  // R1 R2 = (b + e)(b - e) = b^2 - e^2 must equal b^2 I_printed / I_computed.
  const double e2 = r.half_separation_m * r.half_separation_m * (1 - r.printed_kgm2 / c.computed_kgm2);
  c.cg_offset_for_printed_m = e2 >= 0 ? std::sqrt(e2) : std::numeric_limits<double>::quiet_NaN();
  return c;
}

}  // namespace mppi::sysid
