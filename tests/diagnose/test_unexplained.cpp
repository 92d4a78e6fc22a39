// "Unexplained mismatch" (diagnose/unexplained.hpp): which of the corrected model's remaining
// findings are reported as what no named effect explains; and end to end, on the independent
// generator's payload, with and without the payload among the candidates.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

#include "diagnose/unexplained.hpp"
#include "diagnose_fixtures.hpp"

using mppi::diagnose::Mismatch;
using mppi::diagnose::unexplained_mismatch;

namespace {
Mismatch finding(const std::string& channel, const std::string& where, double magnitude, double z) {
  return {channel, where, magnitude, std::abs(magnitude), z, "m/s^2"};
}
}  // namespace

TEST_CASE("unexplained: clear findings that are not a small remainder of the nominal mismatch", "[diagnose]") {
  const std::vector<Mismatch> nominal = {finding("vx", "overall", -0.5, -9.0), finding("vx", "speed in [4, 6] m/s", 0.8, 7.0),
                                         finding("yaw_rate", "overall", 0.2, 6.0)};
  const std::vector<Mismatch> remaining = {
      finding("vx", "overall", -0.1, -8.0),                 // a fifth of 0.8 is 0.16: a small remainder
      finding("vx", "t in [10, 12] s", 0.3, 5.5),           // large and clear
      finding("yaw_rate", "steer in [0.2, 0.5] 1", 0.15, 4.9),  // large but not clear (z < 5)
      finding("yaw_rate", "overall", -0.06, -12.0),         // clear, 0.3 of the nominal 0.2: kept
      finding("vy", "place x in [0, 3] m, y in [1, 4] m", 0.01, 5.1),  // a channel the nominal got right
  };
  const auto u = unexplained_mismatch(nominal, remaining);
  REQUIRE(u.size() == 3);
  CHECK(u[0].where == "overall");  // strongest first: z -12 (yaw_rate), 5.5 (vx), 5.1 (vy)
  CHECK(u[0].channel == "yaw_rate");
  CHECK(u[1].where == "t in [10, 12] s");
  CHECK(u[2].channel == "vy");
  mppi::diagnose::UnexplainedOptions strict;
  strict.min_z = 6.0;
  strict.max_listed = 5;
  CHECK(unexplained_mismatch(nominal, remaining, strict).size() == 1);
  CHECK(unexplained_mismatch(nominal, {}).empty());
  CHECK(mppi::diagnose::unexplained_summary({}) == "none");
  CHECK(mppi::diagnose::unexplained_summary(u).find("yaw_rate, overall: -0.06 m/s^2 (z -12.0)") == 0);
}

TEST_CASE("unexplained: the long look joins the short one, each judged against its own nominal findings", "[diagnose]") {
  const std::vector<Mismatch> nominal_short = {finding("vx", "overall", -0.5, -9.0)};
  const std::vector<Mismatch> remaining_short = {finding("vx", "overall", -0.05, -6.0)};  // a tenth: a remainder
  const std::vector<Mismatch> nominal_long = {finding("vx", "throttle in [0.4, 0.9] 1", 0.3, 12.0)};
  const std::vector<Mismatch> remaining_long = {finding("vx", "throttle in [0.4, 0.9] 1", 0.1, 7.0),  // a third: kept
                                                finding("yaw_rate", "overall", 0.02, 4.5)};         // not clear
  const auto u = mppi::diagnose::unexplained_of_both(
      nominal_short, remaining_short, mppi::diagnose::long_horizon_unexplained(nominal_long, remaining_long));
  REQUIRE(u.size() == 1);
  CHECK(u[0].where == "throttle in [0.4, 0.9] 1 (1-s predictions, all rows)");
  const auto long_look = mppi::diagnose::long_horizon_unexplained(nominal_long, remaining_long);
  REQUIRE(long_look.size() == 1);
  CHECK(long_look[0].where == u[0].where);
  // The same short remainder beside a smaller nominal mismatch (0.2: a fourth of it) is kept.
  CHECK(mppi::diagnose::unexplained_of_both({finding("vx", "overall", -0.2, -9.0)}, remaining_short, {}).size() == 1);
}

TEST_CASE("unexplained: the named effects become a partial correction only where a mismatch remains", "[diagnose]") {
  mppi::diagnose::Selection s;
  s.selected = {"throttle_gain", "throttle_offset"};
  s.verdict = "named: throttle_gain, throttle_offset";
  mppi::diagnose::mark_partial_where_unexplained({}, &s);
  CHECK(s.selected.size() == 2);
  CHECK(s.partial.empty());
  mppi::diagnose::mark_partial_where_unexplained({finding("vx", "speed in [4, 8] m/s", 0.2, 7.3)}, &s);
  CHECK(s.selected.empty());
  CHECK(s.partial == std::vector<std::string>{"throttle_gain", "throttle_offset"});
  CHECK(s.verdict == "unexplained mismatch (vx, speed in [4, 8] m/s); partial correction: throttle_gain, throttle_offset");
  REQUIRE_FALSE(s.log.empty());
  CHECK(s.log.back().find("explain it in part") != std::string::npos);
}

// The independent generator's payload (evidence/: its own car physics): offered only terms that
// cannot explain a heavier car, the diagnosis reports the mismatch it leaves as unexplained; with
// the payload among the candidates it names it, and nothing clear is left.
TEST_CASE("unexplained: a payload the candidates cannot explain is reported, and not once it is named", "[diagnose]") {
  const mppi::test::ScratchDir dir("mppi_unexplained");
  const auto rec = mppi::test::independent_recording(dir / "payload.csv", "payload_mass_scale=1.5,payload_yaw_inertia_scale=1.5",
                                                     3, "gazebo", "ccw", "human", 60.0);
  mppi::diagnose::DiagnoseOptions without;
  without.selection.candidates = {"steer_offset", "aero_drag", "gyro_bias"};
  const auto r_without = mppi::test::diagnose_independent(rec, without);
  INFO("without: named " << mppi::test::joined(r_without.selection.selected) << "; unexplained "
                         << mppi::diagnose::unexplained_summary(r_without.unexplained));
  CHECK_FALSE(r_without.unexplained.empty());
  CHECK(r_without.selection.selected.empty());  // what it chose is at most a partial correction
  mppi::diagnose::DiagnoseOptions with = without;
  with.selection.candidates.push_back("payload");
  const auto r_with = mppi::test::diagnose_independent(rec, with);
  INFO("with: named " << mppi::test::joined(r_with.selection.selected) << "; unexplained "
                      << mppi::diagnose::unexplained_summary(r_with.unexplained));
  CHECK(std::find(r_with.selection.selected.begin(), r_with.selection.selected.end(), "payload") !=
        r_with.selection.selected.end());
  CHECK(r_with.unexplained.empty());
}
