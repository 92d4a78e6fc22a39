// Recordings are screened for values, not just syntax: a clean synthetic recording (truth: aero
// drag) gets one 1e30 row in vx and one NaN row in yaw_rate. Both are flagged with file, row
// and column, listed in report.json and report.md, and kept out of the fit. Oracle: the fit on
// the clean recording with those rows and their neighbours deleted from the file (the
// resulting time gap cuts the pieces there) is the same, to the last bit.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <algorithm>
#include <random>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include <nlohmann/json.hpp>

#include "diagnose/diagnose.hpp"
#include "diagnose/synth.hpp"
#include "sysid/real_data.hpp"

using namespace mppi;
using namespace mppi::diagnose;

namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("mppi_screen_" + std::to_string(::getpid()) + "_" + name)).string();
}

std::vector<double>& column(sim::Recording& rec, const std::string& name) {
  for (std::size_t c = 0; c < rec.columns.size(); ++c)
    if (rec.columns[c] == name) return rec.data[c];
  FAIL("no column " << name);
  return rec.data[0];
}

// The recording without rows [first, last].
sim::Recording without_rows(sim::Recording rec, std::size_t first, std::size_t last) {
  for (auto& col : rec.data) col.erase(col.begin() + static_cast<std::ptrdiff_t>(first),
                                       col.begin() + static_cast<std::ptrdiff_t>(last) + 1);
  return rec;
}

FitResult fit_aero_drag(const PreparedRecording& d, std::size_t* segments) {
  static const auto family = make_model_family("single-track");
  FitProblem p;
  p.data = &d;
  p.family = family.get();
  p.segments = make_segments(d, {}, 25, 25);
  p.scale = channel_scales(d, {});
  *segments = p.segments.size();
  return fit_effect(p, EffectParams{}, effect_spec("aero_drag"));
}

}  // namespace

TEST_CASE("a 1e30 row and a NaN row are flagged, reported and kept out of the fit", "[diagnose][screen]") {
  EffectParams truth;
  parse_effect_assignments("aero_drag_kgpm=0.4", &truth);
  const sim::Recording clean = synthesize_open_loop(truth, 11, 30.0);
  constexpr std::size_t kHugeRow = 400, kNanRow = 900;
  sim::Recording bad = clean;
  column(bad, "vx")[kHugeRow] = 1e30;
  column(bad, "yaw_rate")[kNanRow] = std::numeric_limits<double>::quiet_NaN();
  const std::string clean_csv = temp_path("clean.csv"), bad_csv = temp_path("bad.csv");
  sysid::write_recording(clean, clean_csv);
  sysid::write_recording(bad, bad_csv);

  // Clean noisy data: nothing flagged.
  const PreparedRecording clean_d = load_any(clean_csv);
  CHECK(clean_d.flags.empty());
  CHECK(clean_d.screened_rows == 0);

  const PreparedRecording bad_d = load_any(bad_csv);
  REQUIRE(bad_d.flags.size() == 2);
  CHECK(bad_d.flags[0].file == bad_csv);
  CHECK(bad_d.flags[0].row == kHugeRow);
  CHECK(bad_d.flags[0].column == "vx");
  CHECK(bad_d.flags[0].value == 1e30);
  CHECK(bad_d.flags[0].kind == "impossible");
  CHECK(bad_d.flags[1].file == bad_csv);
  CHECK(bad_d.flags[1].row == kNanRow);
  CHECK(bad_d.flags[1].column == "yaw_rate");
  CHECK(bad_d.flags[1].kind == "non-finite");
  CHECK(bad_d.screened_rows == 6);  // each row and one neighbour on each side

  // The oracle: the rows and their neighbours deleted from the clean file.
  sim::Recording removed = without_rows(clean, kNanRow - 1, kNanRow + 1);
  removed = without_rows(removed, kHugeRow - 1, kHugeRow + 1);
  const std::string removed_csv = temp_path("removed.csv");
  sysid::write_recording(removed, removed_csv);
  const PreparedRecording removed_d = load_any(removed_csv);
  CHECK(removed_d.flags.empty());

  std::size_t bad_segments = 0, removed_segments = 0, clean_segments = 0;
  const FitResult on_bad = fit_aero_drag(bad_d, &bad_segments);
  const FitResult on_removed = fit_aero_drag(removed_d, &removed_segments);
  const FitResult on_clean = fit_aero_drag(clean_d, &clean_segments);
  CHECK(bad_segments == removed_segments);
  CHECK(bad_segments < clean_segments);  // the segments holding the bad rows are gone
  REQUIRE(on_bad.params.size() == on_removed.params.size());
  for (std::size_t i = 0; i < on_bad.params.size(); ++i) {
    INFO(on_bad.params[i].name);
    CHECK(on_bad.params[i].value == on_removed.params[i].value);
    CHECK(on_bad.params[i].stddev == on_removed.params[i].stddev);
  }
  CHECK(on_bad.cost == on_removed.cost);
  CHECK(on_bad.params[0].value == Approx(0.4).margin(0.06));  // and it is still the truth

  for (const auto& p : {clean_csv, bad_csv, removed_csv}) std::filesystem::remove(p);
}

TEST_CASE("the diagnose report lists the screened values", "[diagnose][screen]") {
  sim::Recording rec = synthesize_open_loop(EffectParams{}, 5, 20.0);
  column(rec, "vx")[300] = 1e30;
  column(rec, "vy")[500] += 3.0;  // a plausible magnitude, but a single-row spike
  const std::string csv = temp_path("report.csv"), out = temp_path("report");
  sysid::write_recording(rec, csv);
  const PreparedRecording d = load_any(csv);
  REQUIRE(d.flags.size() == 2);
  CHECK(d.flags[1].row == 500);
  CHECK(d.flags[1].column == "vy");
  CHECK(d.flags[1].kind == "spike");
  DiagnoseOptions o;
  o.out_dir = out;
  o.plots = false;
  o.selection.candidates = {"aero_drag"};
  o.selection.stability_resamples = 0;
  run_diagnosis(d, *make_model_family("single-track"), o);
  std::ifstream f(out + "/report.json");
  const auto j = nlohmann::json::parse(f);
  const auto& s = j.at("screening");
  CHECK(s.at("flagged") == 2);
  CHECK(s.at("rows_dropped") == 6);
  REQUIRE(s.at("flags").size() == 2);
  CHECK(s.at("flags")[0].at("row") == 300);
  CHECK(s.at("flags")[0].at("column") == "vx");
  CHECK(s.at("flags")[0].at("file") == csv);
  CHECK(s.at("flags")[0].at("value") == "1e+30");
  CHECK(s.at("flags")[1].at("row") == 500);
  std::ifstream md_file(out + "/report.md");
  const std::string md((std::istreambuf_iterator<char>(md_file)), {});
  CHECK_THAT(md, Catch::Contains("Screened values") && Catch::Contains("| 300 |") && Catch::Contains("| vy |"));
  std::filesystem::remove(csv);
  std::filesystem::remove_all(out);
}

namespace {
// A car driving straight along x at 5 m/s, sampled at 20 Hz; from row `respawn` on it stands
// still 1 m to the side and 0.3 m back (a marshal put it back on the track). Position noise of
// sigma `position_noise_m` on x and y (a GPS-like fix) when given; velocities exact.
sim::Recording straight_drive(std::size_t rows, std::size_t respawn, double position_noise_m, unsigned seed) {
  sim::Recording rec;
  rec.columns = {"t", "x", "y", "yaw", "vx", "vy", "yaw_rate", "steer", "throttle"};
  rec.data.assign(rec.columns.size(), std::vector<double>(rows, 0.0));
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, position_noise_m);
  const double dt = 0.05, v = 5.0;
  double x_at_respawn = 0.0;
  for (std::size_t k = 0; k < rows; ++k) {
    const bool moving = k < respawn;
    if (k == respawn) x_at_respawn = v * dt * static_cast<double>(k - 1) - 0.3;
    rec.data[0][k] = dt * static_cast<double>(k);
    rec.data[1][k] = (moving ? v * dt * static_cast<double>(k) : x_at_respawn) + (position_noise_m > 0 ? noise(rng) : 0.0);
    rec.data[2][k] = (moving ? 0.0 : 1.0) + (position_noise_m > 0 ? noise(rng) : 0.0);
    rec.data[4][k] = moving ? v : 0.0;
    rec.data[8][k] = moving ? 0.3 : 0.0;
  }
  return rec;
}

int pieces(const PreparedRecording& d) { return *std::max_element(d.piece.begin(), d.piece.end()) + 1; }
}  // namespace

TEST_CASE("a respawn is cut out at a low sample rate, where its jump is within a row's travel",
          "[diagnose][screen]") {
  // At 20 Hz the 1.04 m jump is less than the 1.25 m that "3 (v + 2) dt + 0.2" allows for any
  // displacement, but not in the direction or at the speed the velocities say.
  const PreparedRecording d = prepare(straight_drive(400, 200, 0.0, 1), "respawn", 100);
  CHECK(pieces(d) == 2);
  CHECK(d.piece[199] == 0);
  CHECK(d.piece[200] == 1);
  CHECK(d.screened_rows == 0);  // a respawn is cut, not reported as a sensor fault
}

TEST_CASE("noisy positions (a GPS fix) are not cut into pieces", "[diagnose][screen]") {
  // 0.2 m of noise per axis: the displacements disagree with the velocities by about 0.3 m
  // every row, which sets the recording's own scale; no row of 2000 is a respawn.
  const PreparedRecording d = prepare(straight_drive(2000, 2000, 0.2, 7), "gps", 100);
  CHECK(pieces(d) == 1);
  // The same noise with a respawn of 4 m: cut there.
  sim::Recording rec = straight_drive(2000, 1000, 0.2, 7);
  for (std::size_t k = 1000; k < 2000; ++k) rec.data[2][k] += 3.0;
  const PreparedRecording r = prepare(rec, "gps respawn", 100);
  CHECK(pieces(r) == 2);
  CHECK(r.piece[999] != r.piece[1000]);
}
