// Cost-map loaders: AutoRally npz, images through OpenCV, AutoRally's track .cfg.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

// OpenCV 4's headers mix enum types, which C++20 deprecates; not our code.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include "base/error.hpp"
#include "base/npz.hpp"
#include "costs/python_dict_text.hpp"
#include "mppi/cost_map.hpp"

namespace mppi {

namespace {

float single_value(const NpzFile& npz, const std::string& key) {
  const NpyArray& a = npz.at(key);
  if (a.size() != 1)
    throw Error(npz.path() + ": array '" + key + "' has " + std::to_string(a.size()) +
                " values, expected 1");
  return static_cast<float>(a.values[0]);
}

// The formats whose signature OpenCV 4's imdecode would hand to a decoder that reads only
// from a file (it writes the bytes to a temporary file first); their name, or nullptr.
// Signatures as OpenCV's decoders check them (grfmt_hdr, grfmt_exr, grfmt_gdcm).
const char* needs_temporary_file(const std::uint8_t* bytes, std::size_t size) {
  const auto starts_with = [&](std::size_t at, const char* magic, std::size_t n) {
    return size >= at + n && std::memcmp(bytes + at, magic, n) == 0;
  };
  if (starts_with(0, "#?RGBE", 6) || starts_with(0, "#?RADIANCE", 10)) return "Radiance HDR";
  if (starts_with(0, "\x76\x2f\x31\x01", 4)) return "OpenEXR";
  if (starts_with(128, "DICM", 4)) return "DICOM";
  return nullptr;
}

}  // namespace

CostMap CostMap::load_npz(const std::string& path) {
  const NpzFile npz = NpzFile::load(path);
  const NpyArray& xb = npz.at("xBounds", {2});
  const NpyArray& yb = npz.at("yBounds", {2});
  const float ppm = single_value(npz, "pixelsPerMeter");
  const float x_min = static_cast<float>(xb.values[0]), x_max = static_cast<float>(xb.values[1]);
  const float y_min = static_cast<float>(yb.values[0]), y_max = static_cast<float>(yb.values[1]);
  int width = 0, height = 0;
  try {
    width = pixel_count(x_min, x_max, ppm, "x");
    height = pixel_count(y_min, y_max, ppm, "y");
  } catch (const Error& e) {
    throw Error(path + ": arrays 'xBounds', 'yBounds', 'pixelsPerMeter': " + e.what());
  }
  const NpyArray& c0 = npz.at("channel0");
  const std::size_t expected = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (c0.size() != expected)
    throw Error(path + ": array 'channel0' has " + std::to_string(c0.size()) + " values, expected " +
                std::to_string(width) + " x " + std::to_string(height) + " = " +
                std::to_string(expected) + " (from xBounds, yBounds, pixelsPerMeter)");
  std::vector<float> values(c0.values.begin(), c0.values.end());
  // NaN is refused by CostMap itself; an infinite cell (or a double beyond the float range) too,
  // here: it would make every rollout through it unusable.
  for (std::size_t i = 0; i < values.size(); ++i)
    if (std::isinf(values[i]))
      throw Error(path + ": array 'channel0': value " + (values[i] > 0 ? "inf" : "-inf") + " at row " +
                  std::to_string(i / static_cast<std::size_t>(width)) + ", col " +
                  std::to_string(i % static_cast<std::size_t>(width)) + " (as float)");
  try {
    return CostMap(x_min, x_max, y_min, y_max, ppm, std::move(values));
  } catch (const Error& e) {
    throw Error(path + ": array 'channel0': " + e.what());
  }
}

CostMap CostMap::load_image(const std::string& path, const ImageMapSpec& spec) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open image file");
  std::vector<std::uint8_t> bytes;
  char chunk[1 << 16];
  while (in.read(chunk, sizeof chunk) || in.gcount() > 0)
    bytes.insert(bytes.end(), chunk, chunk + in.gcount());
  if (in.bad()) throw Error(path + ": cannot read image file");
  return decode_image(bytes.data(), bytes.size(), path, spec);
}

CostMap CostMap::decode_image(const std::uint8_t* bytes, std::size_t size, const std::string& source,
                              const ImageMapSpec& spec) {
  int width = 0, height = 0;
  try {
    width = pixel_count(spec.x_min_m, spec.x_max_m, spec.pixels_per_meter, "x");
    height = pixel_count(spec.y_min_m, spec.y_max_m, spec.pixels_per_meter, "y");
  } catch (const Error& e) {
    throw Error(source + ": bad ImageMapSpec: " + e.what());
  }
  if (!std::isfinite(spec.offset) || !std::isfinite(spec.normalizer) || spec.normalizer == 0.f)
    throw Error(source + ": bad ImageMapSpec: offset must be finite and normalizer finite and non-zero");
  const int channel = static_cast<int>(spec.channel);
  if (channel < 0 || channel > 3) throw Error(source + ": bad ImageMapSpec: channel must be R, G, B or A");

  if (size == 0) throw Error(source + ": no image data (empty file)");
  if (const char* format = needs_temporary_file(bytes, size))
    throw Error(source + ": " + format + " images are not supported (need 8 or 16 bits per channel, " +
                "decoded in memory: PNG, TIFF, BMP, ...)");
  if (size > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw Error(source + ": image file too large (" + std::to_string(size) + " bytes)");
  cv::Mat img;
  try {
    // A 1 x size view of the bytes, no copy; IMREAD_UNCHANGED as imread had: no EXIF rotation.
    const cv::Mat encoded(1, static_cast<int>(size), CV_8U, const_cast<std::uint8_t*>(bytes));
    img = cv::imdecode(encoded, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {  // e.g. a header whose size is beyond OpenCV's limits
    throw Error(source + ": cannot decode image: " + e.err);
  }
  if (img.empty()) throw Error(source + ": cannot decode image (unsupported format or corrupt data)");
  if (img.depth() != CV_8U && img.depth() != CV_16U)
    throw Error(source + ": unsupported image depth (need 8 or 16 bits per channel)");
  const int n_channels = img.channels();
  if (n_channels < 1 || n_channels > 4)
    throw Error(source + ": unsupported number of channels " + std::to_string(n_channels));
  if (img.cols != width || img.rows != height)
    throw Error(source + ": image is " + std::to_string(img.cols) + " x " + std::to_string(img.rows) +
                " pixels, the spec's bounds and pixels_per_meter need " + std::to_string(width) +
                " x " + std::to_string(height));

  // OpenCV stores colour as BGR(A). cell_channel: where the spec's channel lies within a pixel;
  // -1: absent (the alpha of an opaque image).
  int cell_channel = -1;
  if (n_channels >= 3) {
    const int bgra[4] = {2, 1, 0, 3};  // index of R, G, B, A
    cell_channel = bgra[channel];
    if (cell_channel >= n_channels) cell_channel = -1;
  } else {  // gray (+ alpha): gray counts as R = G = B
    cell_channel = (channel == 3) ? (n_channels == 2 ? 1 : -1) : 0;
  }
  const bool is16 = img.depth() == CV_16U;
  const float opaque = is16 ? 65535.f : 255.f;

  std::vector<float> values(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int r = 0; r < height; ++r) {
    const int map_row = spec.row0_is_y_max ? height - 1 - r : r;
    float* out = values.data() + static_cast<std::size_t>(map_row) * width;
    for (int c = 0; c < width; ++c) {
      float raw = opaque;
      if (cell_channel >= 0) {
        const std::size_t k = static_cast<std::size_t>(c) * n_channels + cell_channel;
        raw = is16 ? static_cast<float>(img.ptr<std::uint16_t>(r)[k])
                   : static_cast<float>(img.ptr<std::uint8_t>(r)[k]);
      }
      out[c] = (raw + spec.offset) / spec.normalizer;  // float, as numpy float32 in track_generator.py
    }
  }
  try {
    return CostMap(spec.x_min_m, spec.x_max_m, spec.y_min_m, spec.y_max_m, spec.pixels_per_meter,
                   std::move(values));
  } catch (const Error& e) {
    throw Error(source + ": " + e.what());
  }
}

namespace {

// The raw text of `"key": value` in a Python-dict file: a [list] or a bare token.
std::optional<std::string> dict_value(const std::string& text, const std::string& key) {
  const auto value = python_dict_value(text, key);
  if (!value) return std::nullopt;
  return std::string(*value);
}

std::vector<double> dict_numbers(const std::string& path, const std::string& key, const std::string& raw) {
  std::string body = raw;
  if (!body.empty() && body.front() == '[') body = body.substr(1, body.size() - 2);
  std::vector<double> out;
  std::stringstream ss(body);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto first = item.find_first_not_of(" \t\r\n");
    if (first == std::string::npos) continue;  // trailing comma
    const auto last = item.find_last_not_of(" \t\r\n");
    const std::string token = item.substr(first, last - first + 1);
    std::size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != token.size() || !std::isfinite(v))
      throw Error(path + ": key '" + key + "': '" + token + "' is not a finite number");
    out.push_back(v);
  }
  return out;
}

std::vector<double> required(const std::string& path, const std::string& text, const std::string& key,
                             std::size_t count) {
  const auto raw = dict_value(text, key);
  if (!raw) throw Error(path + ": missing key '" + key + "'");
  auto v = dict_numbers(path, key, *raw);
  if (v.size() != count)
    throw Error(path + ": key '" + key + "' has " + std::to_string(v.size()) + " numbers, expected " +
                std::to_string(count));
  return v;
}

double optional_number(const std::string& path, const std::string& text, const std::string& key,
                       double fallback) {
  const auto raw = dict_value(text, key);
  if (!raw) return fallback;
  auto v = dict_numbers(path, key, *raw);
  if (v.size() != 1) throw Error(path + ": key '" + key + "' must be one number");
  return v[0];
}

}  // namespace

ImageMapSpec CostMap::read_autorally_track_cfg(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open track config");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse_autorally_track_cfg(buffer.str(), path);
}

ImageMapSpec CostMap::parse_autorally_track_cfg(const std::string& text, const std::string& path) {
  ImageMapSpec spec;
  const auto xb = required(path, text, "xBounds", 2);
  const auto yb = required(path, text, "yBounds", 2);
  const auto ppm = required(path, text, "pixelsPerMeter", 1);
  spec.x_min_m = static_cast<float>(xb[0]);
  spec.x_max_m = static_cast<float>(xb[1]);
  spec.y_min_m = static_cast<float>(yb[0]);
  spec.y_max_m = static_cast<float>(yb[1]);
  spec.pixels_per_meter = static_cast<float>(ppm[0]);

  if (optional_number(path, text, "imageRotation", 0.0) != 0.0)
    throw Error(path + ": key 'imageRotation': only 0 is supported");

  // channelMap[i] = the costmap channel that image channel i (R, G, B, A) becomes.
  int source = 0;
  if (const auto raw = dict_value(text, "channelMap")) {
    const auto map = dict_numbers(path, "channelMap", *raw);
    if (map.size() != 4) throw Error(path + ": key 'channelMap' must have 4 entries");
    source = -1;
    for (int i = 0; i < 4; ++i)
      if (map[i] == 0.0) source = i;  // the last one wins, as in the script's copy loop
    if (source < 0) throw Error(path + ": key 'channelMap' sends no image channel to channel0");
  }
  static const char* const kPrefix[4] = {"r", "g", "b", "a"};
  spec.channel = static_cast<ImageMapSpec::Channel>(source);
  spec.offset = static_cast<float>(optional_number(path, text, std::string(kPrefix[source]) + "Offset", 0.0));
  spec.normalizer =
      static_cast<float>(optional_number(path, text, std::string(kPrefix[source]) + "Normalizer", 1.0));
  if (spec.normalizer == 0.f)
    throw Error(path + ": key '" + std::string(kPrefix[source]) + "Normalizer' must not be 0");
  spec.row0_is_y_max = false;  // track_generator.py never flips (its "flip" key is unused)
  return spec;
}

}  // namespace mppi
