// Converters of the shipped real recordings, checked against independent signals in the same
// files (wheel encoder, IMU yaw rate) and the README's stated properties; malformed files give
// errors naming file, line and column.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <functional>
#include <fstream>

#include "base/error.hpp"
#include "sysid/real_data.hpp"
#include "test_data.hpp"

using namespace mppi;
using namespace mppi::sysid;

namespace {
double corr(const std::vector<double>& a, const std::vector<double>& b, const std::vector<bool>& use) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0, n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!use[i] || !std::isfinite(a[i]) || !std::isfinite(b[i])) continue;
    sa += a[i];
    sb += b[i];
    saa += a[i] * a[i];
    sbb += b[i] * b[i];
    sab += a[i] * b[i];
    n += 1;
  }
  return (sab / n - sa / n * sb / n) / std::sqrt((saa / n - sa * sa / n / n) * (sbb / n - sb * sb / n / n));
}
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}
}  // namespace

TEST_CASE("DART Vicon recording converts to body-frame velocities that match the encoder and IMU", "[sysid][real]") {
  const std::string spec =
      test::data_path("real/dart_jetracer.zip") + ":car_1_Datarecording_09_16_2024_10_27_02.csv";
  const sim::Recording rec = convert_real_file(spec);
  REQUIRE(rec.rows() > 10000);
  CHECK(rec.column("t").back() == Approx(104.5).margin(0.2));  // README: 104.5 s
  const auto& vx = rec.column("vx");
  const auto& enc = rec.column("wheel_speed");
  std::vector<bool> moving(rec.rows());
  double diff = 0;
  int n = 0;
  for (std::size_t i = 0; i < rec.rows(); ++i) {
    moving[i] = std::isfinite(enc[i]) && enc[i] > 0.5;
    if (moving[i]) {
      diff += vx[i] - enc[i];
      ++n;
    }
  }
  CHECK(corr(vx, enc, moving) > 0.9);
  CHECK(std::abs(diff / n) < 0.2);  // the encoder reads a little high (wheel slip); same scale
  CHECK(corr(rec.column("yaw_rate"), rec.column("imu_yaw_rate"), moving) > 0.9);
  // Positive steering turns left (README convention check, ISO 8855).
  CHECK(corr(rec.column("steer"), rec.column("yaw_rate"), moving) > 0.8);
  CHECK(rec.metadata.at("vehicle") == "dart_jetracer");
}

TEST_CASE("ETH RC-car recording: world velocities rotated into the body frame, glitches dropped", "[sysid][real]") {
  const sim::Recording rec = convert_real_file(test::data_path("real/eth_lasgroup_rccar.zip") + ":train_1.csv");
  REQUIRE(rec.rows() == 9028);  // README
  const auto& r = rec.column("yaw_rate");
  int missing = 0;
  for (double v : r) missing += std::isnan(v);
  CHECK(missing >= 11);  // README: 11-16 glitch samples with |omega| > 20 rad/s
  CHECK(missing <= 16);
  // The car drives forwards and (about 40% of the time) in reverse: either way the body
  // velocity is mostly along the heading, |vy| small against |vx| (a wrong rotation mixes them).
  const auto& vx = rec.column("vx");
  const auto& vy = rec.column("vy");
  double svx = 0, svy = 0;
  for (std::size_t i = 0; i < rec.rows(); ++i)
    if (std::hypot(vx[i], vy[i]) > 1.0) {
      svx += std::abs(vx[i]);
      svy += std::abs(vy[i]);
    }
  CHECK(svx > 5 * svy);
}

TEST_CASE("malformed raw and project recordings name file, line and column", "[sysid][real]") {
  const std::string raw = "step,t_nominal_s,x_m,y_m,theta_rad,vx_world_mps,vy_world_mps,omega_radps,steer_cmd,throttle_cmd\n"
                          "0,0.0,1,2,0,0,0,0,0,0\n"
                          "1,0.033,1,2,0,0,abc,0,0,0\n";
  CHECK(error_of([&] { convert_real_recording(raw, "bad.csv"); }) ==
        "bad.csv:3: column 7 (vy_world_mps): not a number: 'abc'");
  const std::string short_row = "step,t_nominal_s,x_m,y_m,theta_rad,vx_world_mps,vy_world_mps,omega_radps,steer_cmd,throttle_cmd\n"
                                "0,0.0,1,2\n";
  CHECK(error_of([&] { convert_real_recording(short_row, "short.csv"); }).find("short.csv:2: column 5") == 0);
  CHECK(error_of([&] { convert_real_recording("a,b\n1,2\n", "other.csv"); }).find("other.csv:1: header is neither") == 0);
  // Project format through load_any_recording (the path mppi-fit estimate reads).
  const std::string path = "test_sysid_malformed_recording.csv";
  {
    std::ofstream f(path);
    f << "# vehicle: test\nt,x,y,yaw,vx,vy,yaw_rate,steer,throttle\n0,0,0,0,1,0,0,0,0\n0.02,0,0,0,1,0,0,0,0\n"
         "0.04,0,0,0,1,0,0,x1,0\n";
  }
  CHECK(error_of([&] { load_any_recording(path); }) == path + ":5: column 8 (steer): not a number: 'x1'");
  {
    std::ofstream f(path);
    f << "t,x,y,yaw,vx,vy,yaw_rate,steer,throttle\n0,0,0,0,1,0,0,0,0\n0,0,0,0,1,0,0,0,0\n";
  }
  CHECK(error_of([&] { load_any_recording(path); }).find(path + ":3: column 1 (t)") == 0);
  std::remove(path.c_str());
  CHECK(error_of([&] { read_text_or_zip_member(test::data_path("real/dart_jetracer.zip") + ":nope.csv"); })
            .find("no member 'nope.csv'") != std::string::npos);
}

TEST_CASE("a converted recording round-trips through the project's writer and reader", "[sysid][real]") {
  const sim::Recording rec = convert_real_file(test::data_path("real/eth_lasgroup_rccar.zip") + ":train_2.csv");
  const std::string path = "test_sysid_roundtrip.csv";
  write_recording(slice_recording(rec, 100, 400), path);
  const sim::Recording back = load_any_recording(path);
  std::remove(path.c_str());
  REQUIRE(back.rows() == 300);
  for (const char* c : {"t", "x", "yaw", "vx", "vy", "yaw_rate", "steer", "throttle"})
    for (std::size_t i = 0; i < 300; i += 37) {
      const double a = rec.column(c)[100 + i], b = back.column(c)[i];
      if (std::isnan(a)) CHECK(std::isnan(b));
      else CHECK(b == Approx(a).epsilon(1e-7).margin(1e-9));
    }
  CHECK(back.metadata.at("vehicle") == "eth_lasgroup_rccar");
}

TEST_CASE("a registered reader reads its files, and a rosbag without one is refused saying so", "[sysid][real]") {
  // Nothing in this program registers a ".bag" reader (mppi-fit does, where librosbag is built).
  CHECK(error_of([] { load_any_recording("run.bag"); }) ==
        "run.bag: a rosbag, and this build reads no rosbags (configure with librosbag-dev installed and "
        "MPPI_WITH_ROSBAG=ON; docs/ROSBAG.md)");
  std::string seen;
  register_recording_reader(".testrec", [&seen](const std::string& path) {
    seen = path;
    sim::Recording r;
    r.metadata["source"] = "test reader";
    return r;
  });
  CHECK(load_any_recording("a/b.testrec").metadata.at("source") == "test reader");
  CHECK(seen == "a/b.testrec");
  register_recording_reader(".testrec", [](const std::string& path) -> sim::Recording {
    throw Error(path + ": the second reader");
  });  // replaces the first
  CHECK(error_of([] { load_any_recording("c.testrec"); }) == "c.testrec: the second reader");
  CHECK(error_of([] { register_recording_reader("", {}); }) ==
        "register_recording_reader: an extension and a reader are needed");
}
