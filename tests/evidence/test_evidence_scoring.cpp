// How the evidence sweep scores a diagnosis, and the passes over place-dependent effects that the
// generator reports. Oracles: the passes are counted again here from the noise-free recording and
// the truth file's discs (not from the generator's internal states); the scoring rules are checked
// on hand-built runs whose right answer is known.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "diagnose/evidence_sweep.hpp"
#include "evidence/generator.hpp"
#include "sim/recording.hpp"

using namespace mppi;

namespace {

diagnose::EvidenceRun run_of(std::vector<std::string> effects, std::vector<std::string> named) {
  diagnose::EvidenceRun r;
  r.c.effects = std::move(effects);
  r.named = std::move(named);
  return r;
}

// One effect whose discs the car passed this many times each.
std::vector<evidence::PlacePasses> passes(const std::string& effect, std::vector<int> per_disc) {
  evidence::PlacePasses p{effect, {}};
  for (int count : per_disc) {
    p.disc_passes_s.emplace_back();
    for (int i = 0; i < count; ++i) p.disc_passes_s.back().push_back({10.0 * i, 10.0 * i + 2});
  }
  return {p};
}

}  // namespace

TEST_CASE("evidence scoring: a place effect the car crossed once need not be named, but naming it stays right",
          "[evidence][scoring]") {
  using diagnose::score_evidence_run;
  SECTION("crossed once, nothing named: right, not right in the strict count") {
    auto r = run_of({"grip_patches"}, {});
    score_evidence_run(passes("grip_patches", {1}), &r);
    CHECK(r.right);
    CHECK_FALSE(r.right_strict);
    CHECK_FALSE(r.wrong);
    CHECK(r.crossed_once == std::vector<std::string>{"grip_patches"});
  }
  SECTION("crossed once and named: right in both counts") {
    auto r = run_of({"grip_patches"}, {"grip_patch"});
    score_evidence_run(passes("grip_patches", {1}), &r);
    CHECK(r.right);
    CHECK(r.right_strict);
  }
  SECTION("crossed once, a wrong effect named: neither right nor clean") {
    auto r = run_of({"bump"}, {"steer_offset"});
    score_evidence_run(passes("bump", {1}), &r);
    CHECK_FALSE(r.right);
    CHECK(r.wrong);
  }
  SECTION("never on it at all counts as crossed once") {
    auto r = run_of({"bump"}, {});
    score_evidence_run(passes("bump", {0}), &r);
    CHECK(r.right);
    CHECK(r.crossed_once == std::vector<std::string>{"bump"});
  }
  SECTION("three patches crossed once each: still crossed once (no place seen twice)") {
    auto r = run_of({"grip_patches"}, {});
    score_evidence_run(passes("grip_patches", {1, 1, 1}), &r);
    CHECK(r.right);
    auto twice = run_of({"grip_patches"}, {});
    score_evidence_run(passes("grip_patches", {1, 2, 0}), &twice);
    CHECK_FALSE(twice.right);
  }
  SECTION("crossed twice: it must be named") {
    auto r = run_of({"bump"}, {});
    score_evidence_run(passes("bump", {2}), &r);
    CHECK_FALSE(r.right);
    CHECK(r.crossed_once.empty());
    auto named = run_of({"bump"}, {"road_grade"});  // the cruder account of the same physics
    score_evidence_run(passes("bump", {2}), &named);
    CHECK(named.right);
  }
  SECTION("a pair: the effect crossed once is excused, the other is still required") {
    auto missing = run_of({"sensor_time_offset", "grip_patches"}, {"grip_patch"});
    score_evidence_run(passes("grip_patches", {1}), &missing);
    CHECK_FALSE(missing.right);
    auto found = run_of({"sensor_time_offset", "grip_patches"}, {"time_offset"});
    score_evidence_run(passes("grip_patches", {1}), &found);
    CHECK(found.right);
    CHECK_FALSE(found.right_strict);
  }
  SECTION("effects that are not place effects and effect-free runs score as before") {
    auto delay = run_of({"steer_delay"}, {});
    score_evidence_run({}, &delay);
    CHECK_FALSE(delay.right);
    auto clean = run_of({}, {"aero_drag"});
    score_evidence_run({}, &clean);
    CHECK_FALSE(clean.right);
    CHECK(clean.wrong);
  }
}

TEST_CASE("evidence: the truth file lists the car's passes over grip patches and a bump, as the recording shows them",
          "[evidence]") {
  const std::string dir = (std::filesystem::temp_directory_path() / "mppi_evidence_passes_test").string();
  std::filesystem::remove_all(dir);
  int crossed_once = 0, crossed_more = 0;
  // Seed 5: CCRF (a long lap, not closed in 40 s); seed 3: the Gazebo oval (lapped several times).
  for (const std::uint64_t seed : {5u, 3u}) {
    evidence::EvidenceOptions o;
    o.seed = seed;
    o.duration_s = 40;
    o.truth_names = evidence::set_truth_effects("bump_height_m=0.25,grip_patch_scale=0.8", &o.truth);
    const std::string csv = dir + "/s" + std::to_string(seed) + ".csv";
    const evidence::EvidenceResult g = evidence::generate_evidence(o, csv);
    const sim::Recording clean = sim::RecordingReader::read(g.clean_csv);
    nlohmann::json truth;
    std::ifstream(g.truth_json) >> truth;
    REQUIRE(g.place_passes.size() == 2);
    for (const auto& e : truth.at("effects")) {
      // The discs where the effect acts: each patch with its blended edge, the bump's extent.
      const auto& sizes = e.at("sizes");
      std::vector<std::array<double, 3>> discs;
      std::vector<nlohmann::json> listed;
      if (e.at("name") == "bump") {
        discs.push_back({sizes.at("centre_m")[0], sizes.at("centre_m")[1], sizes.at("bump_radius_m")});
        listed.push_back(sizes.at("passes_s"));
      } else {
        for (const auto& p : sizes.at("patches")) {
          discs.push_back({p.at("centre_m")[0], p.at("centre_m")[1],
                           p.at("radius_m").get<double>() + p.at("edge_m").get<double>()});
          listed.push_back(p.at("passes_s"));
        }
      }
      bool some_disc_twice = false;
      const auto &ts = clean.column("t"), &xs = clean.column("x"), &ys = clean.column("y");
      for (std::size_t d = 0; d < discs.size(); ++d) {
        std::vector<std::pair<double, double>> expected;
        for (std::size_t k = 0; k < clean.rows(); ++k) {
          if (!(std::hypot(xs[k] - discs[d][0], ys[k] - discs[d][1]) < discs[d][2])) continue;
          if (!expected.empty() && ts[k] - expected.back().second <= 1.0 + 1e-9) expected.back().second = ts[k];
          else expected.push_back({ts[k], ts[k]});
        }
        INFO("seed " << seed << ", " << e.at("name").get<std::string>() << " disc " << d << ": " << listed[d].dump());
        REQUIRE(listed[d].size() == expected.size());
        for (std::size_t i = 0; i < expected.size(); ++i) {
          // a row dropped from the file at a pass's edge moves it by one row
          CHECK(listed[d][i][0].get<double>() == Approx(expected[i].first).margin(0.05));
          CHECK(listed[d][i][1].get<double>() == Approx(expected[i].second).margin(0.05));
        }
        some_disc_twice = some_disc_twice || expected.size() >= 2;
      }
      CHECK(e.at("crossed_once").get<bool>() == !some_disc_twice);
      (some_disc_twice ? crossed_more : crossed_once) += 1;
      const auto& reported = e.at("name") == "bump" ? g.place_passes[1] : g.place_passes[0];
      CHECK(reported.effect == e.at("name").get<std::string>());
      CHECK(reported.crossed_once() == !some_disc_twice);
    }
  }
  CHECK(crossed_once >= 1);  // both kinds occur, so both are checked
  CHECK(crossed_more >= 1);
  std::filesystem::remove_all(dir);
}
