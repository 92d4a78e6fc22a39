#pragma once
// Reader for NumPy .npz archives (zip of .npy files, stored or deflated), through libzip.
// Supports little-endian float32 / float64 arrays in C order (what AutoRally ships);
// everything else is rejected with an mppi::Error naming the file and the array.
#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace mppi {

struct NpyArray {
  std::vector<std::size_t> shape;  // e.g. {32, 6}; {} for a 0-d scalar
  std::vector<double> values;      // C order, converted to double whatever the stored dtype
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
