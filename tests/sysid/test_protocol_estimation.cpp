// The paper's protocol end to end, shortened: part A's full-vehicle plant with known
// parameters and sensor noise through the five manoeuvres (8 s of each, interleaved), the ALM-UKF on the
// full-vehicle and double-track models, validation on the held-out segment.
#include <catch2/catch.hpp>

#include "sysid/protocol.hpp"
#include "sysid/vehicle_estimation.hpp"

#include <algorithm>

using namespace mppi;
using namespace mppi::sysid;

TEST_CASE("ALM-UKF on the simulated protocol recovers the full vehicle's parameters", "[sysid][estimate][protocol]") {
  FullVehicleParams truth;
  truth.base.mass_kg = 20.6;
  truth.base.yaw_inertia_kgm2 = 1.02;
  truth.base.cg_height_m = 0.096;
  truth.base.tyre.D = 0.92;
  ProtocolOptions opt;
  opt.manoeuvre_duration_s = 8.0;
  opt.validation_duration_s = 6.0;
  const ProtocolRun run = run_protocol(truth, opt);

  const FullVehicleParams nominal;  // the paper's measured values: the filter's start
  const std::vector<std::string> names = {"mass_kg", "yaw_inertia_kgm2", "cg_height_m", "tyre.D"};
  const std::vector<double> expected = {20.6, 1.02, 0.096, 0.92};
  EstimateSettings st;
  st.process_noise_scale = 0.1;
  st.param_walk_std_per_s = 0.001;
  const VehicleModelSpec fv = full_vehicle_spec(nominal, names);
  const EstimateResult res = estimate_parameters(fv, prepare(run.training, "protocol training", 3), st);
  for (std::size_t i = 0; i < names.size(); ++i) {
    INFO(names[i] << ": " << res.final_values[i] << " (truth " << expected[i] << ", nominal " << fv.nominal[i] << ")");
    CHECK(res.final_values[i] == Approx(expected[i]).epsilon(0.02));
  }
  CHECK(res.rejected_steps == 0);
  // Held-out segment: the estimated model predicts the yaw rate and lateral velocity better.
  const PreparedRecording val = prepare(run.validation, "protocol validation", 3);
  const ValidationResult ve = validate_parameters(fv, res.final_values, val, 0, val.rows(), 1.0);
  const ValidationResult vn = validate_parameters(fv, fv.nominal, val, 0, val.rows(), 1.0);
  for (int c : {0, 1, 4, 5}) {
    INFO(ve.channels[c] << " open loop: estimated " << ve.open_loop_rms[c] << ", nominal " << vn.open_loop_rms[c]);
    CHECK(ve.open_loop_rms[c] < vn.open_loop_rms[c]);
  }
}

// The paper's "parameters converge within 20 s", shortened to two 20 s cycles (40 s): the car
// of docs/results/estimation/protocol_truth_full_vehicle.yaml, all ten parameters of the
// documented run, the documented tuning. Oracle: the known true values; each estimate must
// stay within 5% of its truth from 20 s on (dampers: 15%, see below). The same check on the sequential layout of the
// same 40 s (sliding only from 24 s) must fail for the tyre: the test can tell the layouts apart.
namespace {

FullVehicleParams protocol_truth_car() {
  FullVehicleParams p;
  p.base.mass_kg = 20.6093;
  p.base.yaw_inertia_kgm2 = 1.024;
  p.base.cg_height_m = 0.0961;
  p.base.rear_wheel_inertia_kgm2 = 0.0499;
  p.base.cg_to_front_axle_m = 0.37;
  p.base.cg_to_rear_axle_m = 0.23;
  p.base.tyre.B = 1.35;
  p.base.tyre.C = 1.25;
  p.base.tyre.D = 0.92;
  p.front_damper_Nspm = 90.0;
  p.rear_damper_Nspm = 140.0;
  return p;
}

// Per parameter: the time (s from the start) after which the estimate stays within 5% of the truth.
std::vector<double> truth_convergence(ProtocolLayout layout, const std::vector<std::string>& names,
                                      std::vector<double>* truth_values, EstimateResult* result) {
  const FullVehicleParams truth = protocol_truth_car();
  ProtocolOptions opt;
  opt.layout = layout;
  opt.manoeuvre_duration_s = 8.0;  // 40 s: two cycles of five 4 s pieces
  opt.validation_duration_s = 0.0;
  const ProtocolRun run = run_protocol(truth, opt);
  const VehicleModelSpec fv = full_vehicle_spec(FullVehicleParams{}, names);
  *truth_values = full_vehicle_spec(truth, names).nominal;
  EstimateSettings st;
  st.process_noise_scale = 0.1;
  st.param_walk_std_per_s = 0.001;
  *result = estimate_parameters(fv, prepare(run.training, "protocol training", 3), st);
  std::vector<double> out;
  for (std::size_t i = 0; i < names.size(); ++i)
    out.push_back(convergence_time_to(*result, i, 0.05, (*truth_values)[i]) - result->t.front());
  return out;
}

}  // namespace

TEST_CASE("Interleaved protocol: the parameters converge to their truth within 20 s", "[sysid][estimate][protocol]") {
  const std::vector<std::string> names = {"mass_kg", "yaw_inertia_kgm2", "rear_wheel_inertia_kgm2", "cg_height_m",
                                          "cg_to_front_axle_m", "tyre.B", "tyre.C", "tyre.D",
                                          "front_damper_Nspm", "rear_damper_Nspm"};
  std::vector<double> truth;
  EstimateResult res;
  const std::vector<double> conv = truth_convergence(ProtocolLayout::interleaved, names, &truth, &res);
  for (std::size_t i = 0; i < 8; ++i) {
    INFO(names[i] << ": within 5% of truth " << truth[i] << " after " << conv[i] << " s, final "
                  << res.final_values[i]);
    CHECK(conv[i] <= 20.0);
  }
  // The dampers are information-limited, not excitation-limited: at 20 s their 2 sd is ~17%
  // of the value (docs/ESTIMATION.md), so a 5% band is noise; they must be within 15% by 20 s
  // (measured 8.1 s front, 6.2 s rear) and their 2 sd at 20 s must cover the truth.
  std::size_t k20 = 0;
  while (k20 + 1 < res.t.size() && res.t[k20] < 20.0) ++k20;
  for (std::size_t i = 8; i < 10; ++i) {
    const double c15 = convergence_time_to(res, i, 0.15, truth[i]) - res.t.front();
    INFO(names[i] << ": within 15% of truth " << truth[i] << " after " << c15 << " s; at 20 s "
                  << res.history[k20][i] << " +- " << 2 * res.history_std[k20][i] << " (2 sd)");
    CHECK(c15 <= 20.0);
    CHECK(std::abs(res.history[k20][i] - truth[i]) < 2 * res.history_std[k20][i]);
  }
  CHECK(res.rejected_steps == 0);

  std::vector<double> truth_seq;
  EstimateResult res_seq;
  const std::vector<double> conv_seq = truth_convergence(ProtocolLayout::sequential, names, &truth_seq, &res_seq);
  const double tyre_seq = std::max({conv_seq[5], conv_seq[6], conv_seq[7]});
  INFO("sequential: tyre B, C, D within 5% after " << conv_seq[5] << ", " << conv_seq[6] << ", " << conv_seq[7] << " s");
  CHECK(tyre_seq > 20.0);
}
