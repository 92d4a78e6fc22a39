// NpzFile: the real AutoRally files, tiny fixtures made by tests/data/npz/make_fixtures.py, and
// damaged copies (truncated, bytes flipped) that must end in mppi::Error naming the file.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "base/npz.hpp"
#include "test_data.hpp"

namespace {

using mppi::NpzFile;
using Shape = std::vector<std::size_t>;

// The fixtures live next to this test's sources (tests/data/npz), not in the project's data/.
std::string fixture(const std::string& name) {
  return (std::filesystem::path(__FILE__).parent_path().parent_path() / "data" / "npz" / name).string();
}

std::vector<char> read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

// A temp file unique to this process, removed when the object dies.
struct TempFile {
  std::string path;
  explicit TempFile(const std::string& tag)
      : path((std::filesystem::temp_directory_path() /
              ("mppi_test_npz_" + std::to_string(::getpid()) + "_" + tag + ".npz"))
                 .string()) {}
  ~TempFile() { std::filesystem::remove(path); }
  void write(const std::vector<char>& bytes, std::size_t n) const {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f.write(bytes.data(), static_cast<std::streamsize>(n));
  }
};

// Loads `path`, expecting mppi::Error whose message starts with the path and contains `needle`.
void require_error(const std::string& path, const std::string& needle) {
  try {
    (void)NpzFile::load(path);
    FAIL("no error loading " << path);
  } catch (const mppi::Error& e) {
    const std::string what = e.what();
    INFO(what);
    CHECK(what.rfind(path, 0) == 0);
    CHECK(what.find(needle) != std::string::npos);
  }
}

}  // namespace

TEST_CASE("npz: the AutoRally network file (stored float64)", "[nn]") {
  const std::string path = mppi::test::data_path("autorally/models/autorally_nnet_09_12_2018.npz");
  const NpzFile npz = NpzFile::load(path);
  CHECK(npz.path() == path);
  CHECK(npz.keys() == std::vector<std::string>{"dynamics_W1", "dynamics_W2", "dynamics_W3",
                                               "dynamics_b1", "dynamics_b2", "dynamics_b3"});
  const auto& w1 = npz.at("dynamics_W1", {32, 6});
  CHECK(w1.dtype == "<f8");
  // Values printed with numpy (np.load(...)['dynamics_W1'][0].tolist() etc.).
  const double w1_row0[6] = {-1.332636747950333, -0.030374861576047248, -0.3691065713018289,
                             0.04483583269392639, 0.23730902295282227, 1.3247400916407308};
  for (int i = 0; i < 6; ++i) CHECK(w1.values[i] == w1_row0[i]);
  CHECK(w1.values[31 * 6 + 5] == 0.8066905243750988);
  CHECK(npz.at("dynamics_b1", {32}).values[0] == -0.25562283134045855);
  CHECK(npz.at("dynamics_W2", {32, 32}).values[5 * 32 + 7] == -0.4756297485095279);
  CHECK(npz.at("dynamics_W3", {4, 32}).values[3 * 32 + 31] == -1.1362168743671444);
  const auto& b3 = npz.at("dynamics_b3", {4});
  CHECK(b3.values == std::vector<double>{0.07772222691295132, -0.935588378919834, -0.3157888249377459,
                                         0.35824130418947847});
}

TEST_CASE("npz: a deflated float32 costmap", "[nn]") {
  const NpzFile npz = NpzFile::load(mppi::test::data_path("autorally/maps/gazebo/gazebo_costmap.npz"));
  CHECK(npz.at("xBounds", {2}).values == std::vector<double>{-25, 10});
  CHECK(npz.at("pixelsPerMeter", {1}).values == std::vector<double>{20});
  const auto& c0 = npz.at("channel0", {490000});
  CHECK(c0.dtype == "<f4");
  double sum = 0;
  for (double v : c0.values) sum += v;
  CHECK(sum == Approx(33227451.769573927).epsilon(1e-12));  // numpy: c0.sum(dtype=np.float64)
  CHECK(c0.values[1234] == 100.0);
}

TEST_CASE("npz: fixtures - deflated float32, stored float64 and ints, npy v2/v3", "[nn]") {
  const NpzFile f32 = NpzFile::load(fixture("f32_deflated.npz"));
  const auto& m = f32.at("m", {2, 3});  // m[i][j] = 10 i + j - 0.5
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 3; ++j) CHECK(m.values[i * 3 + j] == 10 * i + j - 0.5);
  CHECK(f32.at("scalar", {}).values == std::vector<double>{2.5});  // 0-d array
  const auto& v = f32.at("v", {5});
  for (int i = 0; i < 5; ++i) CHECK(v.values[i] == static_cast<double>(static_cast<float>(0.1 * i)));
  CHECK(f32.at("empty", {0}).size() == 0);

  const NpzFile f64 = NpzFile::load(fixture("f64_stored.npz"));
  const auto& d = f64.at("d", {3, 2});  // d[i][j] = 1 / (1 + i + 2 j)
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 2; ++j) CHECK(d.values[i * 2 + j] == 1.0 / (1.0 + i + 2 * j));
  CHECK(f64.at("i4", {3}).values == std::vector<double>{-2, 0, 7});
  CHECK(f64.at("i8", {2}).values == std::vector<double>{-1099511627776.0, 5});
  CHECK(f64.at("u1", {3}).values == std::vector<double>{0, 200, 255});
  CHECK(f64.at("b1", {2}).values == std::vector<double>{1, 0});

  const NpzFile ver = NpzFile::load(fixture("npy_versions.npz"));
  CHECK(ver.at("w2", {2}).values == std::vector<double>{1.5, -3.25});
  CHECK(ver.at("w3", {2}).values == std::vector<double>{1.5, -3.25});
}

TEST_CASE("npz: missing key and wrong shape name the file, key and shapes", "[nn]") {
  const std::string path = fixture("f64_stored.npz");
  const NpzFile npz = NpzFile::load(path);
  CHECK_FALSE(npz.contains("nope"));
  CHECK(npz.contains("d"));
  CHECK_THROWS_WITH(npz.at("nope"), path + ": missing array 'nope' (has: b1, d, i4, i8, u1)");
  CHECK_THROWS_WITH(npz.at("d", {2, 3}), path + ": array 'd' has shape (3,2), expected (2,3)");
  CHECK_THROWS_WITH(npz.at("d", {6}), path + ": array 'd' has shape (3,2), expected (6)");
}

TEST_CASE("npz: unsupported arrays are rejected with the reason", "[nn]") {
  require_error(fixture("fortran.npz"), "array 'bad': Fortran-order");
  require_error(fixture("complex.npz"), "array 'bad': unsupported dtype '<c16'");
  require_error(fixture("bigendian.npz"), "array 'bad': unsupported dtype '>f8'");
  require_error(fixture("bad_magic.npz"), "array 'bad': not a .npy array (bad magic)");
  require_error(fixture("short_data.npz"), "array 'bad': data holds 24 bytes but shape (4) of '<f8' needs 32");
}

TEST_CASE("npz: missing, non-zip, truncated and corrupted files throw mppi::Error", "[nn]") {
  require_error(fixture("does_not_exist.npz"), "No such file");
  const std::string model = mppi::test::data_path("autorally/models/autorally_nnet_09_12_2018.npz");
  const std::vector<char> bytes = read_bytes(model);
  REQUIRE(bytes.size() == 12722);

  SECTION("not a zip") {
    const TempFile tmp("text");
    const std::string text = "just some text, not an archive\n";
    tmp.write(std::vector<char>(text.begin(), text.end()), text.size());
    require_error(tmp.path, "Not a zip archive");
  }
  SECTION("every truncation is an error") {
    const TempFile tmp("trunc");
    for (std::size_t n = 0; n < bytes.size(); n += 101) {
      tmp.write(bytes, n);
      require_error(tmp.path, "");
    }
    tmp.write(bytes, bytes.size() - 1);
    require_error(tmp.path, "");
  }
  SECTION("a flipped byte inside W2's data fails the CRC check") {
    // dynamics_W2.npy starts at offset 2260 (local header 30 + name 15, npy header 128).
    std::vector<char> bad = bytes;
    bad[2260 + 45 + 128 + 1000] ^= 0x10;
    const TempFile tmp("crc");
    tmp.write(bad, bad.size());
    require_error(tmp.path, "array 'dynamics_W2': CRC error");
  }
  SECTION("a flipped byte anywhere: an error naming the file or a clean load, never a crash") {
    const TempFile tmp("flip");
    int errors = 0, loads = 0;
    for (std::size_t pos = 0; pos < bytes.size(); pos += 7) {
      std::vector<char> bad = bytes;
      bad[pos] ^= static_cast<char>(0xA5);
      tmp.write(bad, bad.size());
      try {
        (void)NpzFile::load(tmp.path);
        ++loads;  // e.g. a flipped timestamp byte
      } catch (const mppi::Error& e) {
        ++errors;
        const std::string what = e.what();
        INFO("byte " << pos << ": " << what);
        REQUIRE(what.rfind(tmp.path, 0) == 0);
      }
    }
    CHECK(errors > 9 * (errors + loads) / 10);  // nearly every byte is data, header or CRC
  }
  SECTION("a flipped byte in a deflated file") {
    const std::string gz = mppi::test::data_path("autorally/maps/gazebo/gazebo_costmap.npz");
    std::vector<char> bad = read_bytes(gz);
    bad[bad.size() / 2] ^= static_cast<char>(0xFF);
    const TempFile tmp("deflate");
    tmp.write(bad, bad.size());
    require_error(tmp.path, "array '");
  }
}
