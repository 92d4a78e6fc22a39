// The evidence sweep's record of each run (diagnose/evidence_sweep.hpp): a run's partial
// correction, ambiguous pairs and unexplained mismatches survive runs.jsonl, and the totals count
// them apart from the named effects.
#include <catch2/catch.hpp>
#include <fstream>

#include "diagnose/evidence_sweep.hpp"
#include "diagnose_fixtures.hpp"

using mppi::diagnose::EvidenceRun;

namespace {
EvidenceRun run_of(std::vector<std::string> effects, std::vector<std::string> named, std::vector<std::string> partial,
                   int unexplained) {
  EvidenceRun r;
  r.c.effects = std::move(effects);
  r.c.size = "large";
  r.c.seed = 1;
  r.track = "marietta";
  r.direction = "ccw";
  r.driver = "pursuit";
  r.named = std::move(named);
  r.partial = std::move(partial);
  r.unexplained = unexplained;
  mppi::diagnose::score_evidence_run({}, &r);
  return r;
}
}  // namespace

TEST_CASE("evidence sweep: partial corrections and unexplained mismatches are kept and counted apart", "[diagnose]") {
  const mppi::test::ScratchDir dir("mppi_sweep_records");
  std::vector<EvidenceRun> runs = {run_of({"payload"}, {}, {"throttle_gain", "throttle_offset"}, 2),
                                   run_of({"steer_delay"}, {"steer_delay"}, {}, 0)};
  runs[0].ambiguous = "throttle_gain or motor_voltage_sag";
  const std::string path = (dir / "runs.jsonl").string();
  {
    std::ofstream out(path);
    for (const auto& r : runs) out << mppi::diagnose::evidence_run_json(r) << "\n";
  }
  const auto back = mppi::diagnose::read_evidence_runs(path);
  REQUIRE(back.size() == 2);
  CHECK(back[0].partial == std::vector<std::string>{"throttle_gain", "throttle_offset"});
  CHECK(back[0].unexplained == 2);
  CHECK(back[0].ambiguous == "throttle_gain or motor_voltage_sag");
  CHECK(back[1].ambiguous.empty());
  CHECK(back[0].named.empty());
  CHECK_FALSE(back[0].wrong);  // a partial correction is not a name
  CHECK_FALSE(back[0].right);
  CHECK(back[1].right);
  const std::string md = mppi::diagnose::evidence_summary_markdown(back);
  CHECK(md.find("| an unexplained mismatch reported (with an effect) | - | 1/2 (50.0 %) |") != std::string::npos);
  CHECK(md.find("| a partial correction (with an effect; its effects are not counted as named) | - | 1/2 (50.0 %) |") !=
        std::string::npos);
  CHECK(md.find("| a named effect and a substitute reported as ambiguous (with an effect) | - | 1/2 (50.0 %) |") !=
        std::string::npos);
  CHECK(md.find("| a wrong effect named | <= 10 % | 0/2 (0.0 %) |") != std::string::npos);
}
