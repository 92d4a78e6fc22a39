#pragma once
// Reader for NumPy .npz archives (zip of .npy files, stored or deflated), through libzip.
// Supports little-endian float32 / float64 arrays in C order (what AutoRally ships), and for
// convenience int32 / int64 / uint8 / bool (converted to double: int64 beyond 2^53 rounds);
// everything else (big-endian, complex, structured, Fortran order) is rejected with an
// mppi::Error naming the file and the array. Members not named "*.npy" are skipped.
#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace mppi {

struct NpyArray {
  std::vector<std::size_t> shape;  // e.g. {32, 6}; {} for a 0-d scalar
  std::vector<double> values;      // C order, converted to double whatever the stored dtype
  std::string dtype;               // the stored numpy dtype, e.g. "<f8", "<f4"
  std::size_t size() const { return values.size(); }
};

class NpzFile {
 public:
  // Reads every array of the archive. Throws mppi::Error (file name + reason) if the file is
  // missing, not a zip, truncated/corrupt, or holds an array of an unsupported dtype/order.
  static NpzFile load(const std::string& path);

  const std::string& path() const { return path_; }
  bool contains(const std::string& key) const { return arrays_.count(key) != 0; }
  std::vector<std::string> keys() const;
  // Throws mppi::Error "<file>: missing array '<key>' (has: a, b, c)".
  const NpyArray& at(const std::string& key) const;
  // Like at(), and checks the shape: throws "<file>: array '<key>' has shape (3,4), expected (32,6)".
  const NpyArray& at(const std::string& key, const std::vector<std::size_t>& expected_shape) const;

 private:
  std::string path_;
  std::map<std::string, NpyArray> arrays_;  // key without the ".npy" suffix
};

}  // namespace mppi
