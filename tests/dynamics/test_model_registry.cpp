// The model registry and the parameter tables: every registered model is complete and loads
// its default data; names are unique and looked up exactly; the tables agree with the ranges
// the models refuse, write YAML that reads back exactly, and keep the messages users know.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "base/param_yaml.hpp"
#include "dynamics/model_registry.hpp"
#include "dynamics/vehicle_params.hpp"
#include "test_data.hpp"

namespace {

std::string default_file_of(const char* relative) {
  const std::string r = relative;
  return r.empty() ? r : std::string(MPPI_TEST_DATA_DIR) + "/" + r;
}

// Fields pushed just outside their range: below lo (or at lo when open), above hi.
template <class P>
void check_table_matches_is_valid(const char* what) {
  P defaults;
  std::string why;
  INFO(what);
  REQUIRE(defaults.is_valid(&why));
  const std::size_t n = mppi::param_table(defaults).size();
  for (std::size_t i = 0; i < n; ++i) {
    for (int side = 0; side < 2; ++side) {
      P p;
      const mppi::ParamField f = mppi::param_table(p)[i];
      const bool lo_open = f.bounds == mppi::Bounds::kOpen || f.bounds == mppi::Bounds::kOpenLow;
      const bool hi_open = f.bounds == mppi::Bounds::kOpen || f.bounds == mppi::Bounds::kOpenHigh;
      double bad;
      if (side == 0) {
        if (std::isinf(f.lo)) continue;
        bad = lo_open ? f.lo : std::nextafter(f.lo, -1e300);
      } else {
        if (std::isinf(f.hi)) continue;
        bad = hi_open ? f.hi : std::nextafter(f.hi, 1e300);
      }
      *f.value = bad;
      INFO(f.key << " = " << bad);
      CHECK_FALSE(p.is_valid(&why));
    }
    // NaN is refused for every field.
    P p;
    *mppi::param_table(p)[i].value = std::nan("");
    INFO(mppi::param_table(p)[i].key << " = NaN");
    CHECK_FALSE(p.is_valid(&why));
  }
}

}  // namespace

TEST_CASE("registry: every model is complete, named once, and loads its default data", "[registry]") {
  std::set<std::string> names;
  int count = 0;
  mppi::for_each_type(mppi::RegisteredModels{}, [&]<class D>() {
    ++count;
    INFO(D::kName);
    CHECK(names.insert(D::kName).second);
    CHECK(D::state_names().size() == static_cast<std::size_t>(D::Model::kNx));
    CHECK(D::state_names()[0] == "x_m");
    const typename D::Model model = D::load(default_file_of(D::kDefaultFile));
    // The model's own state is taken whole.
    std::vector<float> own(D::Model::kNx), read(D::Model::kNx, -99.f);
    for (int i = 0; i < D::Model::kNx; ++i) own[static_cast<std::size_t>(i)] = 0.1f * static_cast<float>(i + 1);
    D::from_plant(model, own.data(), D::Model::kNx, read.data());
    if (std::string(D::kName) != "kinematic") CHECK(read == own);
    // From another plant's state: finite, and the speed is the plant's.
    float plant[20] = {1.f, 2.f, 0.3f, 4.f, 0.5f, 0.6f, 0.07f};
    D::from_plant(model, plant, 20, read.data());
    for (float v : read) CHECK(std::isfinite(v));
    CHECK(read[3] == 4.f);
  });
  CHECK(count >= 5);
  CHECK(names.count("single-track") == 1);
  CHECK(names.count("autorally-nn") == 1);
}

TEST_CASE("registry: the kinematic bicycle reads a plant at its rear axle", "[registry]") {
  const float yaw = 0.7f;
  float plant[7] = {3.f, -2.f, yaw, 5.f, 0.4f, 0.2f, 0.01f};
  float x[7];
  mppi::with_model("kinematic", [&]<class D>() { D::from_plant(D::load(""), plant, 7, x); });
  const double l_r = mppi::SingleTrackParams{}.cg_to_rear_axle_m;  // CG to rear axle
  CHECK(x[0] == Approx(3.0 - l_r * std::cos(0.7)).epsilon(1e-6));
  CHECK(x[1] == Approx(-2.0 - l_r * std::sin(0.7)).epsilon(1e-6));
  CHECK(x[4] == 0.f);  // no lateral velocity at the rear axle
}

TEST_CASE("registry: lookups are exact and a bad name lists the valid ones", "[registry]") {
  CHECK(mppi::is_registered_model("double-track"));
  CHECK_FALSE(mppi::is_registered_model("Double-Track"));
  CHECK_FALSE(mppi::is_registered_model("double-track "));
  CHECK_FALSE(mppi::is_registered_model(""));
  const int nx = mppi::with_model("full-vehicle", []<class D>() { return D::Model::kNx; });
  CHECK(nx == 16);
  try {
    mppi::with_model("bicycle", []<class D>() { return 0; }, "plant");
    FAIL("no error");
  } catch (const mppi::Error& e) {
    const std::string msg = e.what();
    CHECK_THAT(msg, Catch::Contains("unknown plant 'bicycle'"));
    mppi::for_each_type(mppi::RegisteredModels{}, [&]<class D>() { CHECK_THAT(msg, Catch::Contains(D::kName)); });
  }
}

TEST_CASE("parameter tables: is_valid refuses exactly what the table's ranges exclude", "[registry][params]") {
  check_table_matches_is_valid<mppi::KinematicBicycleParams>("kinematic");
  check_table_matches_is_valid<mppi::SingleTrackParams>("single-track");
  check_table_matches_is_valid<mppi::DoubleTrackParams>("double-track");
  check_table_matches_is_valid<mppi::FullVehicleParams>("full-vehicle");
}

TEST_CASE("parameter tables: the messages name the key and its range", "[registry][params]") {
  std::string why;
  mppi::SingleTrackParams p;
  p.mass_kg = 0;
  CHECK_FALSE(p.is_valid(&why));
  CHECK(why == "mass_kg must be > 0");
  p = {};
  p.max_steer_rad = 2.0;
  CHECK_FALSE(p.is_valid(&why));
  CHECK(why == "max_steer_rad must be in (0, 1.5)");
  p = {};
  p.stall_torque_Nm = -1;
  CHECK_FALSE(p.is_valid(&why));
  CHECK(why == "stall_torque_Nm must be >= 0");
  mppi::DoubleTrackParams d;
  d.front_roll_share = 1.5;
  CHECK_FALSE(d.is_valid(&why));
  CHECK(why == "front_roll_share must be in [0, 1]");
}

TEST_CASE("parameter tables: YAML written from a table reads back exactly", "[registry][params]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> scale(0.9, 1.0);  // stays inside closed upper bounds
  mppi::DoubleTrackParams written;
  // Every value moved down by up to 10 %, staying valid.
  for (const mppi::ParamField& f : mppi::param_table(written))
    if (*f.value != 0) *f.value *= scale(rng);
  std::string why;
  REQUIRE(written.is_valid(&why));
  const std::string yaml = mppi::write_param_yaml(mppi::param_table(written));
  CHECK_THAT(yaml, Catch::Contains("tyre:\n  B: "));
  const mppi::DoubleTrackParams read = mppi::double_track_params_from_yaml(yaml, "round-trip");
  mppi::DoubleTrackParams a = written, b = read;
  const auto ta = mppi::param_table(a), tb = mppi::param_table(b);
  REQUIRE(ta.size() == tb.size());
  for (std::size_t i = 0; i < ta.size(); ++i) {
    INFO(ta[i].key);
    CHECK(*ta[i].value == *tb[i].value);
  }
}

TEST_CASE("parameter tables: a value out of range is refused where it is written", "[registry][params]") {
  try {
    mppi::single_track_params_from_yaml("mass_kg: 20\ntyre:\n  C: 2.5\n", "car.yaml");
    FAIL("no error");
  } catch (const mppi::Error& e) {
    CHECK_THAT(e.what(), Catch::Contains("car.yaml:3") && Catch::Contains("'C'") &&
                             Catch::Contains("in (0, 2)"));
  }
}

TEST_CASE("registry: the help text lists every model and its parameters with units", "[registry]") {
  const std::string help = mppi::models_help();
  mppi::for_each_type(mppi::RegisteredModels{}, [&]<class D>() { CHECK_THAT(help, Catch::Contains(std::string(D::kName) + ": ")); });
  CHECK_THAT(help, Catch::Contains("    mass_kg = 21.88 [kg], > 0: total mass m"));
  CHECK_THAT(help, Catch::Contains("    tyre.C = "));
  CHECK_THAT(help, Catch::Contains("data/config/autorally_double_track.yaml"));
}
