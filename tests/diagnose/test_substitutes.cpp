// Substitutes among the stability resamples (diagnose/substitutes.hpp): the rule on constructed
// resamples, the partial correction it turns the names into, and end to end on the independent
// generator's payload offered only terms that mimic it.
#include <algorithm>
#include <catch2/catch.hpp>

#include "diagnose/substitutes.hpp"
#include "diagnose_fixtures.hpp"

using mppi::diagnose::find_substitutes;
using mppi::diagnose::Selection;
using mppi::diagnose::SubstitutePair;

namespace {
std::string actuator(const std::string& id) {
  if (id == "steer_delay" || id == "steer_lag" || id == "steer_backlash") return "steer";
  if (id == "throttle_delay" || id == "throttle_lag") return "throttle";
  return "";
}
}  // namespace

TEST_CASE("substitutes: a rival that takes a named effect's place and never sits beside it", "[diagnose]") {
  // As on a payload offered no payload: the throttle map in four resamples, a weaker motor in the
  // other two, never together; the steering play in five, and the one without it chose a lag.
  const std::vector<std::vector<std::string>> resamples = {
      {"throttle_gain", "steer_backlash"}, {"throttle_gain", "steer_backlash"}, {"motor_voltage_sag", "steer_lag"},
      {"throttle_gain", "steer_backlash"}, {"throttle_gain", "steer_backlash", "steer_gain"},
      {"motor_voltage_sag", "steer_backlash"}};
  const auto pairs = find_substitutes({"throttle_gain", "steer_backlash"}, {"throttle_gain", "steer_backlash"},
                                      resamples, actuator);
  REQUIRE(pairs.size() == 1);
  CHECK(pairs[0].named == "throttle_gain");
  CHECK(pairs[0].substitute == "motor_voltage_sag");
}

TEST_CASE("substitutes: none for a stable effect, another form of its actuator, a companion or a co-chosen effect",
          "[diagnose]") {
  // Chosen in every resample: nothing took its place.
  CHECK(find_substitutes({"payload"}, {"payload"}, {{"payload"}, {"payload", "steer_gain"}, {"payload"}}, actuator)
            .empty());
  // Left out once, where the steering's lag stood in: one physical explanation in two forms.
  CHECK(find_substitutes({"steer_delay"}, {"steer_delay"}, {{"steer_delay"}, {"steer_lag"}, {"steer_delay"}}, actuator)
            .empty());
  // The rival also appears beside it: an extra, not a substitute.
  CHECK(find_substitutes({"aero_drag"}, {"aero_drag"}, {{"aero_drag", "gyro_bias"}, {"gyro_bias"}, {"aero_drag"}},
                         actuator)
            .empty());
  // The rival was chosen on all the data too: both are in the correction.
  CHECK(find_substitutes({"aero_drag"}, {"aero_drag", "rolling_resistance"}, {{"aero_drag"}, {"rolling_resistance"}},
                         actuator)
            .empty());
  // Left out without a rival: the data were thinner, not ambiguous.
  CHECK(find_substitutes({"grip_patch"}, {"grip_patch"}, {{"grip_patch"}, {}, {"grip_patch"}}, actuator).empty());
}

TEST_CASE("substitutes: a substituted name becomes a partial correction, the others stay named", "[diagnose]") {
  Selection s;
  s.selected = {"steer_delay", "throttle_gain", "throttle_offset"};
  s.verdict = "named: steer_delay, throttle_gain, throttle_offset";
  mppi::diagnose::mark_partial_where_substituted({}, &s);
  CHECK(s.selected.size() == 3);
  CHECK(s.partial.empty());
  CHECK(s.ambiguous.empty());
  mppi::diagnose::mark_partial_where_substituted({{"throttle_gain", "motor_voltage_sag"}}, &s);
  CHECK(s.selected == std::vector<std::string>{"steer_delay", "throttle_offset"});
  CHECK(s.partial == std::vector<std::string>{"throttle_gain"});
  CHECK(s.ambiguous == "throttle_gain or motor_voltage_sag");
  CHECK(s.verdict ==
        "named: steer_delay, throttle_offset; ambiguous (throttle_gain or motor_voltage_sag): throttle_gain a partial "
        "correction");
  // Every name substituted: nothing is named.
  mppi::diagnose::mark_partial_where_substituted(
      {{"steer_delay", "steer_gain"}, {"throttle_offset", "motor_voltage_sag"}}, &s);
  CHECK(s.selected.empty());
  CHECK(s.partial == std::vector<std::string>{"throttle_gain", "steer_delay", "throttle_offset"});
  CHECK(s.verdict == "ambiguous (steer_delay or steer_gain; throttle_offset or motor_voltage_sag); partial correction: "
                     "steer_delay, throttle_offset");
}

// The independent generator's payload (evidence/: its own car physics) with every default
// candidate but the payload: the resamples split between a throttle map and a weaker motor, each
// of which mimics a heavier car on the throttle, so nothing is named (the long look is off: the
// substitutes alone decide); without the rule a mimic is named, and with the payload among the
// candidates it is named.
TEST_CASE("substitutes: a payload offered only its mimics is named by none of them", "[diagnose][no-asan]") {
  const mppi::test::ScratchDir dir("mppi_substitutes");
  const auto rec = mppi::test::independent_recording(dir / "payload.csv", "payload_mass_scale=1.25,payload_yaw_inertia_scale=1.4",
                                                     3, "gazebo", "cw", "pursuit", 60.0);
  mppi::diagnose::DiagnoseOptions mimics;
  for (const mppi::EffectSpec& e : mppi::diagnose::effect_library())
    if (e.default_candidate && e.id != "payload") mimics.selection.candidates.push_back(e.id);
  mimics.unexplained.long_horizon_s = 0;
  mppi::diagnose::DiagnoseOptions unguarded = mimics;
  unguarded.selection.withhold_substituted = false;
  const auto r_unguarded = mppi::test::diagnose_independent(rec, unguarded);
  INFO("without the rule: " << r_unguarded.selection.verdict);
  CHECK_FALSE(r_unguarded.selection.selected.empty());
  const auto r_mimics = mppi::test::diagnose_independent(rec, mimics);
  INFO("mimics: " << r_mimics.selection.verdict);
  // The throttle's mimics are ambiguous and not named.
  for (const char* mimic : {"throttle_gain", "throttle_offset", "motor_voltage_sag"})
    CHECK(std::find(r_mimics.selection.selected.begin(), r_mimics.selection.selected.end(), mimic) ==
          r_mimics.selection.selected.end());
  CHECK_FALSE(r_mimics.selection.partial.empty());
  CHECK_THAT(r_mimics.selection.ambiguous, Catch::Contains("throttle_gain or "));
}
