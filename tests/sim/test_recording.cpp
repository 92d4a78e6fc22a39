// The CSV recording format: round trip, exact text, and malformed files with file/line/column.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "base/error.hpp"
#include "sim/recording.hpp"

using namespace mppi::sim;
using Catch::Matchers::Contains;

namespace {
// Files of this test run, removed at exit.
struct TempFiles {
  std::vector<std::string> paths;
  ~TempFiles() {
    std::error_code ec;
    for (const auto& p : paths) std::filesystem::remove(p, ec);
  }
} temp_files;

std::string temp_path(const std::string& name) {
  // Per process, so concurrent test runs do not share files.
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("mppi_sim_test_" + std::to_string(::getpid()) + "_" + name)).string();
  temp_files.paths.push_back(path);
  return path;
}
std::string write_text(const std::string& name, const std::string& text) {
  const std::string path = temp_path(name);
  std::ofstream(path) << text;
  return path;
}
std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
const std::string kHeader = "t,x,y,yaw,vx,vy,yaw_rate,steer,throttle\n";
const double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

TEST_CASE("recording: writer output is the documented text", "[sim]") {
  const std::string path = temp_path("text.csv");
  {
    RecordingWriter w(path, {"roll", "wheel_speed"}, {{"vehicle", "autorally"}, {"track", "gazebo"}});
    const double extras[2] = {0.125, kNaN};
    w.write(0.1 + 0.2, {1.5f, -2.25f, 0.1f, 5.0f, 0.0f, -0.5f, 0.0f}, {0.25f, -1.0f}, extras);
  }
  CHECK(slurp(path) ==
        "# vehicle: autorally\n# track: gazebo\n"
        "t,x,y,yaw,vx,vy,yaw_rate,steer,throttle,roll,wheel_speed\n"
        "0.3,1.5,-2.25,0.1,5,0,-0.5,0.25,-1,0.125,\n");
}

TEST_CASE("recording: round trip keeps metadata, columns and values", "[sim]") {
  const std::string path = temp_path("round.csv");
  std::vector<std::vector<double>> rows;
  {
    RecordingWriter w(path, {"roll", "ax", "my_custom"}, {{"source", "unit test: round trip"}}, 3);
    for (int i = 0; i < 50; ++i) {
      const float f = static_cast<float>(i);
      const mppi::VehicleState s{0.1f * f, -0.37f * f, 0.01f * f - 3.0f, 7.3f, 0.2f, -1.1f, 0.0f};
      const mppi::Control u{std::sin(f), -0.5f};
      // Exact floats, a double that is not a float (1/3 + i), and a missing value.
      const double extras[3] = {static_cast<double>(0.001f * f), 1.0 / 3.0 + i, i % 7 == 0 ? kNaN : -f};
      const double t = 0.002 * i;
      w.write(t, s, u, extras);
      rows.push_back({t, s.x_m, s.y_m, s.yaw_rad, s.vx_mps, s.vy_mps, s.yaw_rate_radps, u.steer,
                      u.throttle, extras[0], extras[1], extras[2]});
    }
    CHECK(w.rows_written() == 50);
  }
  const Recording rec = RecordingReader::read(path);
  CHECK(rec.metadata.at("source") == "unit test: round trip");
  REQUIRE(rec.columns == std::vector<std::string>{"t", "x", "y", "yaw", "vx", "vy", "yaw_rate", "steer",
                                                   "throttle", "roll", "ax", "my_custom"});
  REQUIRE(rec.rows() == 50);
  for (std::size_t r = 0; r < rows.size(); ++r)
    for (std::size_t c = 0; c < rows[r].size(); ++c) {
      INFO("row " << r << " column " << rec.columns[c]);
      const double want = rows[r][c], got = rec.data[c][r];
      if (std::isnan(want)) {
        CHECK(std::isnan(got));
      } else if (c == 0) {
        CHECK(got == Approx(want).margin(1e-9));  // t to the nanosecond
      } else if (rec.columns[c] == "ax") {
        CHECK(got == want);  // not a float: written with double precision, exact
      } else {
        // Exact floats are written with the shortest digits that read back to the same float.
        CHECK(static_cast<float>(got) == static_cast<float>(want));
        CHECK(got == Approx(want).epsilon(1e-7));
      }
    }
  CHECK(rec.column("yaw_rate")[3] == -1.1);  // written "-1.1"
  CHECK_THROWS_WITH(rec.column("pitch"), Contains("pitch") && Contains("yaw_rate"));
}

TEST_CASE("recording: reader accepts reordered columns, CRLF, spaces, comments and NaN", "[sim]") {
  const std::string path = write_text(
      "loose.csv",
      "# vehicle: dart\r\n#plain comment\r\nthrottle,steer,yaw_rate,vy,vx,yaw,y,x,t,voltage\r\n"
      "0.5, -0.25 ,0,0,1,0,2,3,0.0,\r\n\r\n0.5,-0.25,0,0,1,0,2,3,+1e-3,7.4\r\n");
  const Recording rec = RecordingReader::read(path);
  CHECK(rec.metadata.at("vehicle") == "dart");
  CHECK(rec.rows() == 2);
  CHECK(rec.column("t")[1] == 0.001);
  CHECK(rec.column("steer")[0] == -0.25);
  CHECK(std::isnan(rec.column("voltage")[0]));
  CHECK(rec.column("voltage")[1] == 7.4);
}

TEST_CASE("recording: malformed files name file, line and column", "[sim]") {
  SECTION("missing required column") {
    const std::string p = write_text("nocol.csv", "# a: b\nt,x,y,vx,vy,yaw_rate,steer,throttle\n0,0,0,0,0,0,0,0\n");
    CHECK_THROWS_WITH(RecordingReader::read(p),
                      Contains(p) && Contains("missing required column 'yaw'"));
  }
  SECTION("too few fields") {
    const std::string p = write_text("few.csv", "# meta: 1\n" + kHeader + "0,1,2,3,4,5,6,7,8\n0.1,1,2,3,4,5,6,7\n");
    CHECK_THROWS_WITH(RecordingReader::read(p),
                      Contains(p + ":4: column 9 (throttle)") && Contains("8 fields"));
  }
  SECTION("too many fields") {
    const std::string p = write_text("many.csv", kHeader + "0,1,2,3,4,5,6,7,8,9\n");
    CHECK_THROWS_WITH(RecordingReader::read(p), Contains(p + ":2: column 10") && Contains("10 fields"));
  }
  SECTION("non-numeric value") {
    const std::string p = write_text("nan.csv", kHeader + "0,1,2,3,4,5,6,7,8\n0.1,1,abc,3,4,5,6,7,8\n");
    CHECK_THROWS_WITH(RecordingReader::read(p), Contains(p + ":3: column 3 (y)") && Contains("'abc'"));
  }
  SECTION("number with trailing junk") {
    const std::string p = write_text("junk.csv", "\n" + kHeader + "0,1,2,3,4,5,6,7,1.5x\n");
    CHECK_THROWS_WITH(RecordingReader::read(p), Contains(p + ":3: column 9 (throttle)") && Contains("'1.5x'"));
  }
  SECTION("non-increasing t") {
    const std::string p = write_text(
        "time.csv", kHeader + "0,1,2,3,4,5,6,7,8\n0.1,1,2,3,4,5,6,7,8\n# note\n0.1,1,2,3,4,5,6,7,8\n");
    CHECK_THROWS_WITH(RecordingReader::read(p), Contains(p + ":5: column 1 (t)") && Contains("increase"));
  }
  SECTION("missing t") {
    const std::string p = write_text("not.csv", "x,y,yaw,vx,vy,yaw_rate,steer,throttle,t\n1,2,3,4,5,6,7,8,\n");
    CHECK_THROWS_WITH(RecordingReader::read(p), Contains(p + ":2: column 9 (t)") && Contains("missing"));
  }
  SECTION("duplicate column") {
    const std::string p = write_text("dup.csv", "t,x,y,yaw,vx,vy,yaw_rate,steer,throttle,x\n");
    CHECK_THROWS_WITH(RecordingReader::read(p), Contains(p + ":1: column 10") && Contains("twice"));
  }
  SECTION("no file") {
    CHECK_THROWS_WITH(RecordingReader::read(temp_path("does_not_exist.csv")), Contains("does_not_exist.csv"));
  }
}

TEST_CASE("recording: writer rejects bad columns and row sizes", "[sim]") {
  const std::string p = temp_path("bad_writer.csv");
  CHECK_THROWS_WITH((RecordingWriter(p, {"roll", "roll"})), Contains("roll") && Contains("twice"));
  CHECK_THROWS_WITH((RecordingWriter(p, {"x"})), Contains("twice"));
  CHECK_THROWS_WITH((RecordingWriter(p, {"a,b"})), Contains("a,b"));
  CHECK_THROWS_AS((RecordingWriter(p, {}, {{"key", "two\nlines"}})), mppi::Error);
  CHECK_THROWS_WITH(RecordingWriter("/nonexistent-dir/x.csv"), Contains("/nonexistent-dir/x.csv"));
  RecordingWriter w(p, {"roll"});
  CHECK_THROWS_WITH(w.write(0.0, {}, {}), Contains("0 extra values for 1"));
  const double row[3] = {0, 1, 2};
  CHECK_THROWS_AS(w.write_row(row), mppi::Error);
  w.close();
  const double extra[1] = {0.0};
  CHECK_THROWS_AS(w.write(0.0, {}, {}, extra), mppi::Error);
}
