// The corrected-model file's nominal_params section (dynamics/corrected_model_io.cpp) for every
// model a file can name, read and written through that model's descriptor. Oracles: the
// parameter table itself (every field read back equal to the one written) and the names of
// CorrectedNominalModels in the error for any other name.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "base/type_list.hpp"
#include "dynamics/corrected_model.hpp"
#include "dynamics/with_effects.hpp"

using namespace mppi;

namespace {

bool in_range(const ParamField& f, double v) {
  const bool lo_open = f.bounds == Bounds::kOpen || f.bounds == Bounds::kOpenLow;
  const bool hi_open = f.bounds == Bounds::kOpen || f.bounds == Bounds::kOpenHigh;
  return std::isfinite(v) && (lo_open ? v > f.lo : v >= f.lo) && (hi_open ? v < f.hi : v <= f.hi);
}

// Moves every field of the table off its default by a different small step that stays in its
// range, with digits that only a full-precision writer keeps.
void nudge_every_field(const std::vector<ParamField>& fields) {
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const double v = fields[i].get(), step = 1e-3 * static_cast<double>(i + 1) / 3.0;
    for (const double candidate : {v * (1 + step), v * (1 - step), step, -step}) {
      if (candidate != v && in_range(fields[i], candidate)) {
        fields[i].set(candidate);
        break;
      }
    }
    INFO(fields[i].key);
    CHECK(fields[i].get() != v);  // else the round trip would not show that the key is written
  }
}

void check_same_fields(const std::vector<ParamField>& written, const std::vector<ParamField>& read) {
  REQUIRE(written.size() == read.size());
  for (std::size_t i = 0; i < written.size(); ++i) {
    INFO(written[i].key);
    CHECK(written[i].get() == read[i].get());
  }
}

}  // namespace

TEMPLATE_LIST_TEST_CASE("corrected-model file: each nominal model's parameters round-trip through the file",
                        "[corrected]", CorrectedNominalModels) {
  using D = TestType;
  CorrectedModelFile file;
  file.nominal_model = D::kName;
  file.effects.steer_lag_s = 0.05;
  if constexpr (HasParamTable<D>) {
    typename D::Params& written = nominal_params_of<D>(file);
    nudge_every_field(D::params(written));
    std::string why;
    REQUIRE(written.is_valid(&why));
    const CorrectedModelFile back = corrected_model_from_yaml(corrected_model_to_yaml(file), "round trip");
    CHECK(back.nominal_model == D::kName);
    typename D::Params read = nominal_params_of<D>(back);
    check_same_fields(D::params(written), D::params(read));
    // A four-wheel set's single-track core is also the file's `nominal`.
    if constexpr (requires { single_track_core(read); }) {
      SingleTrackParams core = single_track_core(read), nominal = back.nominal;
      check_same_fields(param_table(core), param_table(nominal));
    }
  } else {
    file.network_npz = "weights/a network: #2.npz";
    const CorrectedModelFile back = corrected_model_from_yaml(corrected_model_to_yaml(file), "round trip");
    CHECK(back.nominal_model == D::kName);
    CHECK(back.network_npz == file.network_npz);
  }
}

TEST_CASE("corrected-model file: a nominal model it cannot name is an error naming it and the valid names",
          "[corrected]") {
  auto check_names_valid = [](const std::string& message) {
    for_each_type(CorrectedNominalModels{},
                  [&]<class D>() { CHECK_THAT(message, Catch::Contains(std::string(D::kName))); });
  };
  for (const std::string name : {"diff-drive", "autorally-bf"}) {
    INFO(name);
    try {
      corrected_model_from_yaml("model: corrected\nnominal: " + name + "\n", "m.yaml");
      FAIL("read a file with nominal " + name);
    } catch (const Error& e) {
      CHECK_THAT(e.what(), Catch::Contains("m.yaml:2:10: nominal must be one of") &&
                               Catch::Contains("got '" + name + "'"));
      check_names_valid(e.what());
    }
    CorrectedModelFile file;
    file.nominal_model = name;
    try {
      corrected_model_to_yaml(file);
      FAIL("wrote a file with nominal " + name);
    } catch (const Error& e) {
      CHECK_THAT(e.what(), Catch::Contains("unknown nominal model '" + name + "' (valid: "));
      check_names_valid(e.what());
    }
  }
}
