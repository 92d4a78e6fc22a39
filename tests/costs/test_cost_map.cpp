#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <optional>
#include <random>
#include <regex>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "base/npz.hpp"
#include "costs/python_dict_text.hpp"
#include "mppi/cost_map.hpp"
#include "error_of.hpp"
#include "test_data.hpp"

namespace {

// ---- a minimal writer of stored (uncompressed) npz files, to make broken maps on the fly ----
std::uint32_t crc32(const std::string& data) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char ch : data) {
    crc ^= ch;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

void put16(std::string& s, unsigned v) { s += char(v & 0xff); s += char((v >> 8) & 0xff); }
void put32(std::string& s, std::uint32_t v) { put16(s, v & 0xffff); put16(s, v >> 16); }

// .npy v1.0 of a 1-D little-endian float32 array.
std::string npy_f32(const std::vector<float>& v) {
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + std::to_string(v.size()) + ",), }";
  while ((10 + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::string out = "\x93NUMPY";
  out += char(1);
  out += char(0);
  put16(out, static_cast<unsigned>(header.size()));
  out += header;
  out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(float));
  return out;
}

struct Entry {
  std::string name;  // without ".npy"
  std::vector<float> values;
};

std::string write_npz(const std::string& file_name, const std::vector<Entry>& entries) {
  std::string zip, central;
  for (const auto& e : entries) {
    const std::string name = e.name + ".npy";
    const std::string data = npy_f32(e.values);
    const std::uint32_t crc = crc32(data), offset = static_cast<std::uint32_t>(zip.size());
    put32(zip, 0x04034b50); put16(zip, 20); put16(zip, 0); put16(zip, 0); put16(zip, 0); put16(zip, 0x21);
    put32(zip, crc); put32(zip, data.size()); put32(zip, data.size());
    put16(zip, name.size()); put16(zip, 0);
    zip += name;
    zip += data;
    put32(central, 0x02014b50); put16(central, 20); put16(central, 20); put16(central, 0); put16(central, 0);
    put16(central, 0); put16(central, 0x21); put32(central, crc); put32(central, data.size());
    put32(central, data.size()); put16(central, name.size()); put16(central, 0); put16(central, 0);
    put16(central, 0); put16(central, 0); put32(central, 0); put32(central, offset);
    central += name;
  }
  const std::uint32_t cd_offset = static_cast<std::uint32_t>(zip.size());
  zip += central;
  put32(zip, 0x06054b50); put16(zip, 0); put16(zip, 0); put16(zip, entries.size()); put16(zip, entries.size());
  put32(zip, central.size()); put32(zip, cd_offset); put16(zip, 0);
  const auto path = (std::filesystem::temp_directory_path() / file_name).string();
  std::ofstream(path, std::ios::binary).write(zip.data(), static_cast<std::streamsize>(zip.size()));
  return path;
}

// A 12 x 8 map over x [-1, 2), y [0.5, 2.5) at 4 px/m whose value is 100 * row + col, so a
// lookup tells which pixel it hit.
mppi::CostMap index_map() {
  std::vector<float> v(12 * 8);
  for (int r = 0; r < 8; ++r)
    for (int c = 0; c < 12; ++c) v[r * 12 + c] = 100.f * r + c;
  return mppi::CostMap(-1.f, 2.f, 0.5f, 2.5f, 4.f, v);
}

using mppi::test::error_of;

}  // namespace

TEST_CASE("CostMap: AutoRally pixel mapping, floor at corners, clamp outside", "[costs]") {
  const mppi::CostMap m = index_map();
  REQUIRE(m.width() == 12);   // (2 - -1) * 4
  REQUIRE(m.height() == 8);   // (2.5 - 0.5) * 4
  // Pixel centres: x = -1 + (c + 0.5) / 4, y = 0.5 + (r + 0.5) / 4.
  CHECK(m.lookup(-1.f + 0.125f, 0.5f + 0.125f) == 0.f);
  CHECK(m.lookup(-1.f + 5.5f / 4, 0.5f + 3.5f / 4) == 305.f);
  CHECK(m.lookup(-1.f + 11.5f / 4, 0.5f + 7.5f / 4) == 711.f);
  // Pixel corners (exact in float): floor puts a corner in the pixel to its upper right.
  CHECK(m.lookup(0.f, 1.f) == 204.f);   // col (0+1)*4 = 4, row (1-0.5)*4 = 2
  CHECK(m.lookup(-1.f, 0.5f) == 0.f);
  CHECK(m.lookup(1.75f, 2.25f) == 711.f);  // col 11, row 7: the last pixel's corner
  // One float below a corner: the pixel before (x + 1 and y - 0.5 are exact here, Sterbenz).
  CHECK(m.lookup(-0.5f, 1.f) == 202.f);
  CHECK(m.lookup(std::nextafter(-0.5f, -1.f), std::nextafter(1.f, 0.f)) == 101.f);
  // Outside: clamp to the edge pixel (the right edge x = 2 is already outside: col 12 -> 11).
  CHECK(m.lookup(2.f, 1.f) == 211.f);
  CHECK(m.lookup(-50.f, 1.f) == 200.f);
  CHECK(m.lookup(0.f, -50.f) == 4.f);
  CHECK(m.lookup(50.f, 50.f) == 711.f);
  CHECK(m.lookup(-1e30f, 1e30f) == 700.f);
  CHECK(m.lookup(-1.001f, 0.499f) == 0.f);
}

TEST_CASE("CostMap: NaN and inf coordinates give an in-range, finite value", "[costs]") {
  const mppi::CostMap m = index_map();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  CHECK(m.lookup(nan, 1.f) == 200.f);   // NaN x -> col 0 (x_min edge)
  CHECK(m.lookup(0.f, nan) == 4.f);     // NaN y -> row 0 (y_min edge)
  CHECK(m.lookup(nan, nan) == 0.f);
  CHECK(m.lookup(inf, -inf) == 11.f);
  CHECK(m.lookup(-inf, inf) == 700.f);
  const auto v = m.view();
  CHECK(v.col_of(nan) == 0);
  CHECK(v.row_of(inf) == 7);
  CHECK(v.col_of(3e38f) == 11);
}

TEST_CASE("CostMap: npz lookups equal channel0 read directly", "[costs]") {
  const std::string path = mppi::test::data_path("autorally/maps/marietta/marietta_costmap_2017.npz");
  const mppi::CostMap m = mppi::CostMap::load_npz(path);
  const mppi::NpzFile npz = mppi::NpzFile::load(path);
  const auto& c0 = npz.at("channel0").values;
  // x [-20, 15], y [-25, 10], 20 px/m (README and numpy).
  REQUIRE(m.width() == 700);
  REQUIRE(m.height() == 700);
  CHECK(m.x_min_m() == -20.f);
  CHECK(m.y_max_m() == 10.f);
  CHECK(m.pixels_per_meter() == 20.f);
  // Values printed by numpy: channel0.reshape(700, 700)[row, col].
  CHECK(m.lookup(2.825f, -18.825f) == Approx(1.199324369430542).epsilon(1e-7));    // row 123, col 456
  CHECK(m.lookup(-2.475f, -14.975f) == Approx(0.4045645594596863).epsilon(1e-7));  // row 200, col 350
  // Every 7th pixel centre, computed in double from the published mapping.
  int mismatches = 0;
  for (int r = 0; r < 700; r += 7)
    for (int c = 3; c < 700; c += 7) {
      const double x = -20.0 + (c + 0.5) / 20.0, y = -25.0 + (r + 0.5) / 20.0;
      mismatches += m.lookup(static_cast<float>(x), static_cast<float>(y)) != static_cast<float>(c0[r * 700 + c]);
    }
  CHECK(mismatches == 0);
  // Pixel corners at multiples of 0.25 m (exact in float): col = (x + 20) * 20 exactly.
  for (float x = -19.f; x < 15.f; x += 2.25f)
    for (float y = -24.5f; y < 10.f; y += 1.75f) {
      const int c = static_cast<int>((x + 20.f) * 20.f), r = static_cast<int>((y + 25.f) * 20.f);
      CHECK(m.lookup(x, y) == static_cast<float>(c0[r * 700 + c]));
    }
  // Outside: the edge pixel in that row / column.
  CHECK(m.lookup(-100.f, -2.475f + 0.f) == static_cast<float>(c0[450 * 700 + 0]));  // y -> row 450
  CHECK(m.lookup(2.825f, 1e6f) == static_cast<float>(c0[699 * 700 + 456]));
}

TEST_CASE("CostMap: PNG + track cfg reproduce the gazebo npz", "[costs]") {
  const std::string dir = mppi::test::data_path("autorally/maps/gazebo/");
  const mppi::ImageMapSpec spec = mppi::CostMap::read_autorally_track_cfg(dir + "gazebo_track.cfg");
  // gazebo_track.cfg: xBounds [-25, 10], yBounds [-15, 20], pixelsPerMeter [20], rNormalizer 2.55.
  CHECK(spec.x_min_m == -25.f);
  CHECK(spec.x_max_m == 10.f);
  CHECK(spec.y_min_m == -15.f);
  CHECK(spec.y_max_m == 20.f);
  CHECK(spec.pixels_per_meter == 20.f);
  CHECK(spec.channel == mppi::ImageMapSpec::Channel::kRed);
  CHECK(spec.offset == 0.f);
  CHECK(spec.normalizer == 2.55f);
  CHECK_FALSE(spec.row0_is_y_max);

  const mppi::CostMap from_png = mppi::CostMap::load_image(dir + "gazebo_map.png", spec);
  const mppi::CostMap from_npz = mppi::CostMap::load_npz(dir + "gazebo_costmap.npz");
  REQUIRE(from_png.width() == from_npz.width());
  REQUIRE(from_png.height() == from_npz.height());
  double max_diff = 0.0;
  for (std::size_t i = 0; i < from_npz.values().size(); ++i)
    max_diff = std::max(max_diff, std::abs(double(from_png.values()[i]) - from_npz.values()[i]));
  CHECK(max_diff <= 1e-5);
  // Gazebo: R = 255 far outside -> 100; numpy: channel0[405, 584] = 100, [299, 147] = 0.39215687.
  CHECK(from_png.lookup(4.225f, 5.275f) == Approx(100.f));
  CHECK(from_png.lookup(-17.625f, -0.025f) == Approx(0.3921568691730499));

  // Row 0 at y_max flips the map upside down.
  mppi::ImageMapSpec flipped = spec;
  flipped.row0_is_y_max = true;
  const mppi::CostMap up = mppi::CostMap::load_image(dir + "gazebo_map.png", flipped);
  int mismatches = 0;
  for (int r = 0; r < 700; r += 13)
    for (int c = 0; c < 700; c += 11) mismatches += up.at(r, c) != from_png.at(699 - r, c);
  CHECK(mismatches == 0);
  CHECK(up.at(0, 0) == 100.f);  // corners are outside the track in both

  // A spec whose pixel count does not match the image.
  mppi::ImageMapSpec wrong = spec;
  wrong.x_max_m = 11.f;
  const std::string msg = error_of([&] { (void)mppi::CostMap::load_image(dir + "gazebo_map.png", wrong); });
  CHECK_THAT(msg, Catch::Contains("gazebo_map.png") && Catch::Contains("720 x 700"));
}

TEST_CASE("CostMap: bad npz files give errors naming the file and the array", "[costs]") {
  // A network file has no map arrays.
  const std::string nnet = mppi::test::data_path("autorally/models/autorally_nnet_09_12_2018.npz");
  std::string msg = error_of([&] { (void)mppi::CostMap::load_npz(nnet); });
  CHECK_THAT(msg, Catch::Contains("autorally_nnet_09_12_2018.npz") && Catch::Contains("xBounds"));

  // channel0 one value short of 3 x 2 px.
  const std::vector<float> xb{0.f, 1.5f}, yb{0.f, 1.f}, ppm{2.f};
  const std::string short_path = write_npz("mppi_h2_short_channel0.npz",
      {{"xBounds", xb}, {"yBounds", yb}, {"pixelsPerMeter", ppm}, {"channel0", {1, 2, 3, 4, 5}}});
  msg = error_of([&] { (void)mppi::CostMap::load_npz(short_path); });
  CHECK_THAT(msg, Catch::Contains("mppi_h2_short_channel0.npz") && Catch::Contains("channel0") &&
                      Catch::Contains("expected 3 x 2 = 6"));

  // Missing channel0.
  const std::string no_c0 = write_npz("mppi_h2_no_channel0.npz",
      {{"xBounds", xb}, {"yBounds", yb}, {"pixelsPerMeter", ppm}});
  msg = error_of([&] { (void)mppi::CostMap::load_npz(no_c0); });
  CHECK_THAT(msg, Catch::Contains("mppi_h2_no_channel0.npz") && Catch::Contains("channel0"));

  // Bounds that are not a whole number of pixels; xBounds of the wrong shape.
  const std::string frac = write_npz("mppi_h2_fractional.npz",
      {{"xBounds", {0.f, 1.3f}}, {"yBounds", yb}, {"pixelsPerMeter", ppm}, {"channel0", {1, 2}}});
  msg = error_of([&] { (void)mppi::CostMap::load_npz(frac); });
  CHECK_THAT(msg, Catch::Contains("mppi_h2_fractional.npz") && Catch::Contains("whole number"));
  const std::string bad_shape = write_npz("mppi_h2_bad_shape.npz",
      {{"xBounds", {0.f, 1.f, 2.f}}, {"yBounds", yb}, {"pixelsPerMeter", ppm}, {"channel0", {1, 2}}});
  msg = error_of([&] { (void)mppi::CostMap::load_npz(bad_shape); });
  CHECK_THAT(msg, Catch::Contains("mppi_h2_bad_shape.npz") && Catch::Contains("xBounds"));

  // And a good one written the same way loads with its values in place (row 0 at y_min).
  const std::string good = write_npz("mppi_h2_good.npz",
      {{"xBounds", xb}, {"yBounds", yb}, {"pixelsPerMeter", ppm}, {"channel0", {1, 2, 3, 4, 5, 6}}});
  const mppi::CostMap m = mppi::CostMap::load_npz(good);
  CHECK(m.lookup(1.4f, 0.1f) == 3.f);  // col 2, row 0
  CHECK(m.lookup(0.1f, 0.9f) == 4.f);  // col 0, row 1
  for (const auto& p : {short_path, no_c0, frac, bad_shape, good}) std::remove(p.c_str());

  // In-memory construction checks.
  CHECK_THROWS_AS(mppi::CostMap(0.f, 1.f, 0.f, 1.f, 2.f, std::vector<float>(3)), mppi::Error);
  CHECK_THROWS_AS(mppi::CostMap(1.f, 0.f, 0.f, 1.f, 2.f, std::vector<float>(4)), mppi::Error);
  CHECK_THROWS_AS(mppi::CostMap(0.f, 1.f, 0.f, 1.f, 0.f, std::vector<float>{}), mppi::Error);
  std::vector<float> with_nan(4, 0.f);
  with_nan[3] = std::numeric_limits<float>::quiet_NaN();
  msg = error_of([&] { (void)mppi::CostMap(0.f, 1.f, 0.f, 1.f, 2.f, with_nan); });
  CHECK_THAT(msg, Catch::Contains("NaN at row 1, col 1"));
}

namespace {

std::optional<std::string> dict_value(const std::string& text, const std::string& key) {
  const auto v = mppi::python_dict_value(text, key);
  if (!v) return std::nullopt;
  return std::string(*v);
}

// The grammar of python_dict_value as a regular expression (the reader's earlier implementation):
// the reference the scanner is compared with on generated text.
std::optional<std::string> dict_value_by_regex(const std::string& text, const std::string& key) {
  const std::regex re("[\"']" + key + "[\"']\\s*:\\s*(\\[[^\\]]*\\]|[^,}\\s]+)");
  std::smatch m;
  if (!std::regex_search(text, m, re)) return std::nullopt;
  return m[1].str();
}

std::string write_text(const std::string& file_name, const std::string& text) {
  const auto path = (std::filesystem::temp_directory_path() / file_name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

}  // namespace

TEST_CASE("python_dict_value: hand-written cases", "[costs]") {
  const std::optional<std::string> none;
  // A key that is the start of another key: "x" is not found inside "xBounds".
  const std::string bounds = "{\"xBounds\":[-25, 10], \n\"x\": 3}";
  CHECK(dict_value(bounds, "xBounds") == "[-25, 10]");
  CHECK(dict_value(bounds, "x") == "3");
  CHECK(dict_value(bounds, "Bounds") == none);  // not quoted on its left
  CHECK(dict_value("{\"xBounds\":[1, 2]}", "x") == none);
  // Single quotes, double quotes, and one of each (the reader accepts either on each side).
  CHECK(dict_value("{'pixelsPerMeter': [20]}", "pixelsPerMeter") == "[20]");
  CHECK(dict_value("{\"pixelsPerMeter\": [20]}", "pixelsPerMeter") == "[20]");
  CHECK(dict_value("{'rOffset\": 7}", "rOffset") == "7");
  // Whitespace (spaces, tabs, newlines) on both sides of ':'.
  CHECK(dict_value("{\"rOffset\" \t:\n  -255 , }", "rOffset") == "-255");
  CHECK(dict_value("{\"rOffset\"\n:-255}", "rOffset") == "-255");
  // A missing key; empty text.
  CHECK(dict_value("{\"rOffset\": 0}", "rNormalizer") == none);
  CHECK(dict_value("", "rOffset") == none);
  // A list keeps its inner spaces and brackets; it ends at the first ']' (a '}' or a newline
  // inside does not end it).
  CHECK(dict_value("{\"channelMap\":  [ 0, 1 ,2,3 ] ,\"flip\":False}", "channelMap") == "[ 0, 1 ,2,3 ]");
  CHECK(dict_value("{\"a\": [1,\n}2], \"b\": 4}", "a") == "[1,\n}2]");
  // An unclosed list is a bare token: up to the next ',', '}' or whitespace.
  CHECK(dict_value("{\"a\": [1, 2", "a") == "[1");
  // A bare token ends at ',', '}' or whitespace.
  CHECK(dict_value("{\"flip\":False}", "flip") == "False");
  CHECK(dict_value("{\"a\":1.5e-3,\"b\":2}", "a") == "1.5e-3");
  CHECK(dict_value("{\"a\":x y}", "a") == "x");
  // The key written only as another key's value is not a key; a later real place is found.
  CHECK(dict_value("{\"name\": \"x\", \"note\": \"xBounds\"}", "x") == none);
  CHECK(dict_value("{\"name\": \"x\", \"note\": \"xBounds\"}", "xBounds") == none);
  CHECK(dict_value("{\"name\": \"x\", \"x\": 5}", "x") == "5");
  // No value after ':' (',' or '}' or the end): that place does not count.
  CHECK(dict_value("{\"x\": , \"x\": 2}", "x") == "2");
  CHECK(dict_value("{\"x\":}", "x") == none);
  CHECK(dict_value("{\"x\":   ", "x") == none);
  // The first place wins.
  CHECK(dict_value("{'x': 1, 'x': 2}", "x") == "1");
}

TEST_CASE("python_dict_value: same answers as the regular expression on generated text", "[costs]") {
  // Text made of the pieces that matter to the grammar (quotes, keys, ':', brackets, separators,
  // whitespace, quoted keys), so that they meet in every order; short enough to be read.
  const std::vector<std::string> pieces = {"\"", "'", "x", "xB", ":", " ", "\n\t", "[", "]", ",", "}",
                                           "1", "-3.5", "\"x\"", "'x'", "\"xB'", " : ", "[1, 2]"};
  std::mt19937 rng(20261126);
  std::uniform_int_distribution<int> length(0, 12);
  std::uniform_int_distribution<std::size_t> pick(0, pieces.size() - 1);
  int found = 0, mismatches = 0;
  for (int n = 0; n < 20000; ++n) {
    std::string text;
    for (int k = length(rng); k > 0; --k) text += pieces[pick(rng)];
    for (const std::string key : {"x", "xB"}) {
      const auto expected = dict_value_by_regex(text, key);
      found += expected.has_value();
      if (dict_value(text, key) != expected) {
        ++mismatches;
        UNSCOPED_INFO("key " << key << " in [" << text << "]");
      }
    }
  }
  CHECK(mismatches == 0);
  CHECK(found > 1000);  // the generated text does exercise the matches, not only misses
}

TEST_CASE("track cfg: quotes, spacing, key order and decoy keys", "[costs]") {
  // Alpha channel -> channel0 (channelMap[3] = 0), so aOffset and aNormalizer apply.
  const std::string ok = write_text("mppi_track_cfg_ok.cfg",
      "{'flip': False, 'note': 'xBounds',\n"
      " 'channelMap' : [ 3, 1, 2, 0 ], 'aNormalizer': -1.0, \"aOffset\":-255,\n"
      " 'x': [9, 9], 'xBounds' : [ -1.5 , 2.5 ], \"yBounds\":[0,1],\n"
      " 'pixelsPerMeter':[ 4 ], \"imageRotation\"\t:\t0}\n");
  const mppi::ImageMapSpec spec = mppi::CostMap::read_autorally_track_cfg(ok);
  CHECK(spec.x_min_m == -1.5f);
  CHECK(spec.x_max_m == 2.5f);
  CHECK(spec.y_min_m == 0.f);
  CHECK(spec.y_max_m == 1.f);
  CHECK(spec.pixels_per_meter == 4.f);
  CHECK(spec.channel == mppi::ImageMapSpec::Channel::kAlpha);
  CHECK(spec.offset == -255.f);
  CHECK(spec.normalizer == -1.f);

  // pixelsPerMeter only as another key's value: missing, and the message names file and key.
  const std::string missing = write_text("mppi_track_cfg_missing.cfg",
      "{\"xBounds\":[0, 1], \"yBounds\":[0, 1], \"note\": \"pixelsPerMeter\"}");
  std::string msg = error_of([&] { (void)mppi::CostMap::read_autorally_track_cfg(missing); });
  CHECK_THAT(msg, Catch::Contains("mppi_track_cfg_missing.cfg") && Catch::Contains("missing key 'pixelsPerMeter'"));
  // A value that is not a number.
  const std::string bad = write_text("mppi_track_cfg_bad.cfg",
      "{\"xBounds\":[0, one], \"yBounds\":[0, 1], \"pixelsPerMeter\": [2]}");
  msg = error_of([&] { (void)mppi::CostMap::read_autorally_track_cfg(bad); });
  CHECK_THAT(msg, Catch::Contains("mppi_track_cfg_bad.cfg") && Catch::Contains("key 'xBounds'") &&
                      Catch::Contains("'one' is not a finite number"));
  for (const auto& p : {ok, missing, bad}) std::remove(p.c_str());

  // The text entry point reads the same; its errors name the given source.
  const std::string shipped = mppi::test::data_path("autorally/maps/gazebo/gazebo_track.cfg");
  std::ifstream in(shipped);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const mppi::ImageMapSpec from_text = mppi::CostMap::parse_autorally_track_cfg(text, "in memory");
  const mppi::ImageMapSpec from_file = mppi::CostMap::read_autorally_track_cfg(shipped);
  CHECK(from_text.x_min_m == from_file.x_min_m);
  CHECK(from_text.x_max_m == from_file.x_max_m);
  CHECK(from_text.y_min_m == from_file.y_min_m);
  CHECK(from_text.y_max_m == from_file.y_max_m);
  CHECK(from_text.pixels_per_meter == from_file.pixels_per_meter);
  CHECK(from_text.channel == from_file.channel);
  CHECK(from_text.offset == from_file.offset);
  CHECK(from_text.normalizer == from_file.normalizer);
  msg = error_of([&] { (void)mppi::CostMap::parse_autorally_track_cfg("{\"xBounds\": [0, 1]}", "in memory"); });
  CHECK_THAT(msg, Catch::Contains("in memory: missing key 'yBounds'"));
}

TEST_CASE("CostMap: image bytes in memory decode as the file does, bad bytes name the source", "[costs]") {
  const std::string dir = mppi::test::data_path("autorally/maps/gazebo/");
  const mppi::ImageMapSpec spec = mppi::CostMap::read_autorally_track_cfg(dir + "gazebo_track.cfg");
  std::ifstream in(dir + "gazebo_map.png", std::ios::binary);
  const std::vector<std::uint8_t> png((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  REQUIRE(png.size() > 8);
  const mppi::CostMap from_file = mppi::CostMap::load_image(dir + "gazebo_map.png", spec);
  const mppi::CostMap from_bytes = mppi::CostMap::decode_image(png.data(), png.size(), "in-memory png", spec);
  CHECK(from_bytes.width() == from_file.width());
  CHECK(from_bytes.height() == from_file.height());
  CHECK(from_bytes.values() == from_file.values());

  std::string msg = error_of([&] { (void)mppi::CostMap::decode_image(png.data(), 0, "empty bytes", spec); });
  CHECK_THAT(msg, Catch::Contains("empty bytes") && Catch::Contains("no image data"));
  const std::string junk = "not an image at all";
  msg = error_of([&] {
    (void)mppi::CostMap::decode_image(reinterpret_cast<const std::uint8_t*>(junk.data()), junk.size(), "junk", spec);
  });
  CHECK_THAT(msg, Catch::Contains("junk: cannot decode image"));
  // A truncated PNG (its header, no pixels).
  msg = error_of([&] { (void)mppi::CostMap::decode_image(png.data(), 40, "cut.png", spec); });
  CHECK_THAT(msg, Catch::Contains("cut.png: cannot decode image"));
  // A header asking for more columns than OpenCV allows: OpenCV's own exception becomes an
  // mppi::Error naming the source.
  const std::string wide = "P5\n2000000 1\n255\n" + std::string(64, '\0');
  msg = error_of([&] {
    (void)mppi::CostMap::decode_image(reinterpret_cast<const std::uint8_t*>(wide.data()), wide.size(), "wide.pgm", spec);
  });
  CHECK_THAT(msg, Catch::Contains("wide.pgm: cannot decode image"));
  // Float formats that OpenCV decodes only through a temporary file are refused before decoding.
  const std::string hdr = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 16 +X 16\n" + std::string(64, '\x01');
  msg = error_of([&] {
    (void)mppi::CostMap::decode_image(reinterpret_cast<const std::uint8_t*>(hdr.data()), hdr.size(), "map.hdr", spec);
  });
  CHECK_THAT(msg, Catch::Contains("map.hdr: Radiance HDR images are not supported"));
  const std::string exr = std::string("\x76\x2f\x31\x01", 4) + std::string(64, '\0');
  msg = error_of([&] {
    (void)mppi::CostMap::decode_image(reinterpret_cast<const std::uint8_t*>(exr.data()), exr.size(), "map.exr", spec);
  });
  CHECK_THAT(msg, Catch::Contains("map.exr: OpenEXR images are not supported"));
  // A file that is not there.
  msg = error_of([&] { (void)mppi::CostMap::load_image(dir + "no_such_map.png", spec); });
  CHECK_THAT(msg, Catch::Contains("no_such_map.png: cannot open image file"));
}
