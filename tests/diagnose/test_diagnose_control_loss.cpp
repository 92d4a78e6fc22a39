// Rows of lost control (spins) are found by the body slip angle, and a recording whose car spins
// before its crashes is diagnosed on the rest of its data.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <string>

#include "diagnose/control_loss.hpp"
#include "sysid/prepared_recording.hpp"
#include "diagnose/diagnose.hpp"
#include "diagnose/model_family.hpp"
#include "evidence/generator.hpp"
#include "evidence/truth_effects.hpp"
#include "diagnose_fixtures.hpp"

using namespace mppi;
using namespace mppi::diagnose;

namespace {

PreparedRecording straight_at(double vx_mps, std::size_t rows) {
  PreparedRecording d;
  d.dt_s = 0.02;
  for (std::size_t k = 0; k < rows; ++k) {
    d.t.push_back(0.02 * static_cast<double>(k));
    d.vx.push_back(vx_mps);
    d.vy.push_back(0.0);
  }
  return d;
}

}  // namespace

TEST_CASE("rows of lost control: body slip above the limit at speed, with a guard either side", "[diagnose]") {
  PreparedRecording d = straight_at(5.0, 300);
  for (std::size_t k = 100; k < 105; ++k) d.vy[k] = 10.0;  // atan(10 / 5) = 63 deg: a spin
  for (std::size_t k = 200; k < 210; ++k) {               // reversing with a little slip: 5.7 deg
    d.vx[k] = -5.0;
    d.vy[k] = 0.5;
  }
  for (std::size_t k = 250; k < 260; ++k) {  // 69 deg, but at 0.85 m/s: slip means nothing there
    d.vx[k] = 0.3;
    d.vy[k] = 0.8;
  }
  for (std::size_t k = 280; k < 282; ++k) d.vy[k] = 6.0;  // 50 deg: a drift, kept
  const std::vector<char> lost = control_loss_rows(d);
  REQUIRE(lost.size() == 300);
  // 0.5 s guard = 25 rows: rows 75 .. 129.
  for (std::size_t k = 0; k < 300; ++k) {
    INFO("row " << k);
    CHECK(lost[k] == (k >= 75 && k <= 129 ? 1 : 0));
  }
  ControlLossOptions off;
  off.max_body_slip_deg = 0;
  for (char c : control_loss_rows(d, off)) CHECK(c == 0);
  ControlLossOptions strict;
  strict.max_body_slip_deg = 45;  // now the 50 deg drift counts too (rows 255 .. 281 + 25, clipped)
  const auto more = control_loss_rows(d, strict);
  CHECK(more[280] == 1);
  CHECK(more[299] == 1);
  CHECK(more[254] == 0);
}

TEST_CASE("lost-control options out of range are refused by name", "[diagnose]") {
  PreparedRecording d = straight_at(5.0, 100);
  d.source = "drive.csv";
  const auto refused = [&](double slip_deg, double speed_mps, double guard_s) {
    ControlLossOptions o;
    o.max_body_slip_deg = slip_deg;
    o.min_speed_mps = speed_mps;
    o.guard_s = guard_s;
    return o;
  };
  CHECK_THROWS_WITH(control_loss_rows(d, refused(95, 1, 0.5)), Catch::Contains("drive.csv") && Catch::Contains("got 95 deg"));
  CHECK_THROWS_WITH(control_loss_rows(d, refused(std::nan(""), 1, 0.5)), Catch::Contains("[0, 90] deg"));
  CHECK_THROWS_WITH(control_loss_rows(d, refused(60, -1, 0.5)), Catch::Contains("got 60 deg, -1 m/s"));
  CHECK_THROWS_WITH(control_loss_rows(d, refused(60, 1, -0.5)), Catch::Contains("-0.5 s"));
  CHECK_THROWS_WITH(control_loss_rows(d, refused(60, 1, INFINITY)), Catch::Contains("guard >= 0 s"));
  CHECK(control_loss_rows(d, refused(0, 1, 0.5)) == std::vector<char>(100, 0));  // 0: off
}

// The independent generator's pursuit driver spins a car with a 0.1 play in its steering 8 times
// in 40 s on Marietta. Fitted with the spins, every candidate bends towards them (a play of 0.3 at
// its range limit, a delay of 0.15 s) and fails on the later data, so nothing is named.
TEST_CASE("a steering play is named on a recording whose car spins before its crashes", "[diagnose][slow]") {
  const mppi::test::ScratchDir dir("mppi_control_loss_test");
  const evidence::EvidenceResult rec =
      mppi::test::independent_recording(dir / "spins.csv", "steer_backlash=0.1", 1, "marietta", "ccw", "pursuit");
  REQUIRE(rec.crashes >= 5);
  const DiagnoseResult r = mppi::test::diagnose_independent(rec);
  const std::string named = mppi::test::joined(r.selection.selected);
  INFO("named: " << named << "; rows of lost control " << r.control_loss_rows << "; held-out reduction "
                 << r.heldout_rmse_reduction);
  CHECK(r.control_loss_rows > 100);
  REQUIRE(r.selection.selected.size() == 1);
  CHECK(r.selection.selected[0] == "steer_backlash");
  // The fitted play is 0.14 (the slides that stay in the data, below the spin limit, widen it).
  CHECK(r.selection.final_effects.steer_backlash == Approx(0.1).margin(0.05));
  CHECK(r.heldout_rmse_reduction > 0.15);
}

// The fast case of the one above: 20 s (6 crashes); the candidates: the steering's forms of
// dynamics and map, the tyre, the payload and the drag; two resamples. With the rows of lost
// control kept in the fits, the play ends at its range limit and a lag is chosen in its place.
TEST_CASE("a steering play is named on a short recording whose car spins before its crashes", "[diagnose]") {
  const mppi::test::ScratchDir dir("mppi_control_loss_short_test");
  const evidence::EvidenceResult rec = mppi::test::independent_recording(dir / "spins.csv", "steer_backlash=0.1", 1,
                                                                         "marietta", "ccw", "pursuit", 20.0);
  REQUIRE(rec.crashes >= 3);
  DiagnoseOptions opt;
  opt.selection.candidates = {"steer_delay", "steer_lag",    "steer_rate_limit", "steer_backlash", "steer_gain",
                              "steer_offset", "tire_saturation", "payload",       "aero_drag"};
  opt.selection.stability_resamples = 2;
  const DiagnoseResult r = mppi::test::diagnose_independent(rec, opt);
  const std::string named = mppi::test::joined(r.selection.selected);
  INFO("named: " << named << "; rows of lost control " << r.control_loss_rows << "; held-out reduction "
                 << r.heldout_rmse_reduction);
  CHECK(r.control_loss_rows > 100);
  REQUIRE(r.selection.selected.size() == 1);
  CHECK(r.selection.selected[0] == "steer_backlash");
  CHECK(r.selection.final_effects.steer_backlash == Approx(0.1).margin(0.05));
  CHECK(r.heldout_rmse_reduction > 0.15);
}
