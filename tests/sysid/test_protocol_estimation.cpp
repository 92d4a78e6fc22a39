// The paper's protocol end to end, shortened: part A's full-vehicle plant with known
// parameters and sensor noise through the five manoeuvres (8 s each), the ALM-UKF on the
// full-vehicle and double-track models, validation on the held-out segment.
#include <catch2/catch.hpp>

#include "sysid/protocol.hpp"
#include "sysid/vehicle_estimation.hpp"

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
  const EstimateResult res = estimate_parameters(fv, run.training, st);
  for (std::size_t i = 0; i < names.size(); ++i) {
    INFO(names[i] << ": " << res.final_values[i] << " (truth " << expected[i] << ", nominal " << fv.nominal[i] << ")");
    CHECK(res.final_values[i] == Approx(expected[i]).epsilon(0.02));
  }
  CHECK(res.rejected_steps == 0);
  // Held-out segment: the estimated model predicts the yaw rate and lateral velocity better.
  const auto& val = run.validation;
  const ValidationResult ve = validate_parameters(fv, res.final_values, val, 0, val.rows(), 1.0);
  const ValidationResult vn = validate_parameters(fv, fv.nominal, val, 0, val.rows(), 1.0);
  for (int c : {0, 1, 4, 5}) {
    INFO(ve.channels[c] << " open loop: estimated " << ve.open_loop_rms[c] << ", nominal " << vn.open_loop_rms[c]);
    CHECK(ve.open_loop_rms[c] < vn.open_loop_rms[c]);
  }
}
