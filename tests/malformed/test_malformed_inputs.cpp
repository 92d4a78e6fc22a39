// Inputs that once escaped the parsers' own error reporting (a yaml-cpp conversion exception,
// an out-of-range read), of the kind the fuzz targets in fuzz/ generate: each must now give an
// mppi::Error that names the source and the place.
#include <catch2/catch.hpp>
#include <sstream>
#include <string>

#include "chassis/calibration.hpp"
#include "chassis/priorities.hpp"
#include "sysid/prepared_recording.hpp"
#include "dynamics/corrected_model.hpp"
#include "sim/recording.hpp"
#include "error_of.hpp"

using mppi::test::error_of;

namespace {
bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }
}  // namespace

TEST_CASE("chassis files: a key that is a list or a map is named with its place", "[malformed][chassis]") {
  using mppi::chassis::Calibration;
  using mppi::chassis::Priorities;
  const std::string cal = error_of([] { Calibration::parse_yaml("[steering]: {min: 1000}\n", "cal.yaml"); });
  CHECK(contains(cal, "cal.yaml:1:1: an actuator name must be a plain text value"));
  const std::string key = error_of([] {
    Calibration::parse_yaml("steering: {min: 1000, {a: 1}: 2}\n", "cal.yaml");
  });
  CHECK(contains(key, "cal.yaml:1:"));
  CHECK(contains(key, "a key of actuator 'steering' must be a plain text value"));
  const std::string named = error_of([] { Calibration::parse_yaml("'0': {name: [steering]}\n", "cal.yaml"); });
  CHECK(contains(named, "cal.yaml:1:"));
  CHECK(contains(named, "an actuator name must be a plain text value"));
  const std::string prio = error_of([] { Priorities::parse_yaml("{[a, b]: 1}\n", "prio.yaml"); });
  CHECK(contains(prio, "prio.yaml:1:2: a controller name must be a plain text value"));
}

TEST_CASE("corrected-model files: keys and names that are not text are named with their place",
          "[malformed][diagnose]") {
  using mppi::corrected_model_from_yaml;
  CHECK(contains(error_of([] { corrected_model_from_yaml("[model]: corrected\n", "m.yaml"); }),
                 "m.yaml:1:1: a key must be a plain text value"));
  CHECK(contains(error_of([] { corrected_model_from_yaml("model: {a: 1}\n", "m.yaml"); }),
                 "m.yaml:1:8: model must be a plain text value"));
  CHECK(contains(error_of([] { corrected_model_from_yaml("model: corrected\nnominal:\n", "m.yaml"); }),
                 "m.yaml:3:1: nominal must be a plain text value"));
  CHECK(contains(error_of([] { corrected_model_from_yaml("selected: [a, [b]]\n", "m.yaml"); }),
                 "m.yaml:1:15: an entry of selected must be a plain text value"));
  CHECK(contains(error_of([] {
                   corrected_model_from_yaml("nominal: autorally-nn\nnominal_params: {network_npz: [x]}\n", "m.yaml");
                 }),
                 "m.yaml (nominal_params):2:31: network_npz must be a plain text value"));
}

TEST_CASE("diagnosis preparation of a one-row recording is refused, whatever minimum is asked",
          "[malformed][diagnose]") {
  std::istringstream in("t,x,y,yaw,vx,vy,yaw_rate,steer,throttle\n0,0,0,0,1,0,0,0,0.2\n");
  const mppi::sim::Recording rec = mppi::sim::RecordingReader::read(in, "one_row.csv");
  for (std::size_t min_rows : {0, 1, 2})
    CHECK(contains(error_of([&] { mppi::sysid::prepare(rec, "one_row.csv", min_rows); }),
                   "one_row.csv: too short for diagnosis: 1 rows, need at least 2"));
}
