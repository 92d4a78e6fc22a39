#pragma once
// Moments of inertia from a bifilar (two-wire) torsional pendulum, after Genta 1994 as the
// AutoRally paper uses it ("Moment of Inertia Estimation with Bifilar Pendulum"):
//   I = m g R1 R2 T^2 / (4 pi^2 h)       (general: wires R1 and R2 from the CG, height h)
//   h = sqrt(d^2 - (R1 - R2)^2)          (the paper's correction for non-vertical wires)
//   I = m g b^2 T^2 / (4 pi^2 d)         (parallel wires, R1 = R2 = b: h = d; bifilar_inertia_parallel)
// plus the paper's measurements and a rounding analysis of its moment-of-inertia table
// (docs/PHYSICS.md discusses the result).
#include <string>
#include <vector>

namespace mppi::sysid {

// General form. Throws mppi::Error for a non-positive or non-finite argument.
double bifilar_inertia(double mass_kg, double period_s, double r1_m, double r2_m, double height_m,
                       double gravity_mps2 = 9.81);
// Parallel, symmetric wires: R1 = R2 = b, h = d.
double bifilar_inertia_parallel(double mass_kg, double period_s, double half_separation_m,
                                double wire_length_m, double gravity_mps2 = 9.81);
// h = sqrt(d^2 - (R1 - R2)^2); throws if |R1 - R2| >= d.
double bifilar_height(double wire_length_m, double r1_m, double r2_m);
// The period that a body of inertia I would show (inverse of the general form).
double bifilar_period(double inertia_kgm2, double mass_kg, double r1_m, double r2_m,
                      double height_m, double gravity_mps2 = 9.81);

// One row of the paper's bifilar table with the precision its numbers were printed to.
struct BifilarRow {
  std::string axis;          // I_x, I_y, I_z, I_f, I_r
  double period_s;           // T (mean of 60 periods)
  double half_separation_m;  // b
  double wire_length_m;      // d
  double mass_kg;            // the mass on the wires: whole car, or a wheel pair
  double printed_kgm2;       // the MOI the paper prints
  double period_step, separation_step, length_step, printed_step;  // last printed digit
};
// The paper's table (T, b, d, MOI), with m = 21.88 kg for the body axes and the wheel pairs'
// masses (2 x 0.82 kg front, 2 x 0.89 kg rear) from the robot-parameter table, g = 9.81.
std::vector<BifilarRow> autorally_bifilar_table();

struct BifilarCheck {
  double computed_kgm2;      // I from the printed T, b, d, m
  double relative_diff;      // computed / printed - 1
  double min_kgm2, max_kgm2;  // I over the rounding box of T, b, d (+- half a last digit)
  bool consistent;           // that range meets the printed value's rounding interval
  double period_for_printed_s;  // T that gives exactly the printed I (other values as printed)
  double cg_offset_for_printed_m;  // e with R1 = b + e, R2 = b - e giving the printed I (NaN if none)
};
BifilarCheck check_bifilar_row(const BifilarRow& row, double gravity_mps2 = 9.81);

}  // namespace mppi::sysid
