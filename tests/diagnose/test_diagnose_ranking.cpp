// mppi-fit diagnose: the order in which a round's passing candidates are tried. Oracle: the
// ranking rules applied by hand to candidates whose validation gain, BIC and parameter count are
// written here (parsimony share 0.9, strong BIC evidence 6).
#include <catch2/catch.hpp>

#include <vector>

#include "diagnose/ranking.hpp"

using mppi::diagnose::rank_passing_candidates;
using mppi::diagnose::RankedCandidate;

namespace {
std::vector<std::size_t> ranked(const std::vector<RankedCandidate>& c) { return rank_passing_candidates(c, 0.9, 6.0); }
}  // namespace

TEST_CASE("ranking: the largest validation gain leads when the others are not near it", "[diagnose][ranking]") {
  // 0.20 and 0.10 are below 0.9 x 0.40: only the first is near-best.
  CHECK(ranked({{0.10, -50, 1}, {0.40, -20, 2}, {0.20, -90, 1}}) == std::vector<std::size_t>{1, 2, 0});
}

TEST_CASE("ranking: among near-best candidates the one with fewer parameters leads", "[diagnose][ranking]") {
  // A drag c v|v| (1 parameter, +0.37) against F0 + b v (2 parameters, +0.40, BIC only 3 lower).
  CHECK(ranked({{0.40, -103, 2}, {0.37, -100, 1}}) == std::vector<std::size_t>{1, 0});
  // With more parameters and a BIC 16 lower but a smaller validation gain, the simpler one stays first.
  CHECK(ranked({{0.38, -100, 1}, {0.37, -116, 2}}) == std::vector<std::size_t>{0, 1});
}

TEST_CASE("ranking: of as many parameters, a BIC lower by at least 6 takes the lead", "[diagnose][ranking]") {
  // A pure delay and a lag of the same size: 0.5 % apart on validation, 100 apart in BIC.
  CHECK(ranked({{0.500, -100, 1}, {0.495, -200, 1}}) == std::vector<std::size_t>{1, 0});
  // 5 apart in BIC is not strong evidence: the better validation stays first.
  CHECK(ranked({{0.500, -100, 1}, {0.495, -105, 1}}) == std::vector<std::size_t>{0, 1});
}

TEST_CASE("ranking: more parameters lead when better on validation and in BIC by at least 6", "[diagnose][ranking]") {
  // A payload (mass and yaw inertia) against a voltage sag: +31.4 % / BIC -167.0 against +28.7 % / -150.4.
  const std::vector<RankedCandidate> sag_and_payload = {{0.287, -150.4, 1}, {0.314, -167.0, 2}};
  CHECK(ranked(sag_and_payload) == std::vector<std::size_t>{1, 0});
  // Only 5 lower in BIC: parsimony keeps the voltage sag first.
  CHECK(ranked({{0.287, -150.4, 1}, {0.314, -155.4, 2}}) == std::vector<std::size_t>{0, 1});
  // A larger candidate outside the near-best band never takes the lead, whatever its BIC.
  CHECK(ranked({{0.40, -100, 1}, {0.30, -400, 2}}) == std::vector<std::size_t>{0, 1});
}

TEST_CASE("ranking: an empty round stays empty", "[diagnose][ranking]") {
  CHECK(ranked({}).empty());
}
