// NumPy .npz reader (base/npz.cpp, libzip) and the readers of what it holds: the AutoRally
// cost map (costs/cost_map_io.cpp), network weights (dynamics/autorally_nn_load.cpp) and the
// basis-function model (dynamics/autorally_bf.hpp).
#include "base/npz.hpp"
#include "dynamics/autorally_bf.hpp"
#include "dynamics/autorally_nn.hpp"
#include "fuzz/fuzz_input.hpp"
#include "mppi/cost_map.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = mppi::fuzz::write_temp_file(data, size, ".npz");
  bool readable = false;
  mppi::fuzz::expect_value_or_error([&] {
    mppi::NpzFile::load(path);
    readable = true;
  });
  if (!readable) return 0;
  mppi::fuzz::expect_value_or_error([&] { mppi::CostMap::load_npz(path); });
  mppi::fuzz::expect_value_or_error([&] { mppi::AutoRallyNetwork::load(path); });
  mppi::fuzz::expect_value_or_error([&] { mppi::AutoRallyBasisFunctionModel::load(path); });
  return 0;
}
