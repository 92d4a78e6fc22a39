// The rosbag import (sysid/rosbag/) against bags written by python3-rosbag (write_test_bags.py): a
// closed-form drive on a circle read back at known values, and the bags it must refuse.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <unistd.h>

#include "error_of.hpp"
#include "sim/recording.hpp"
#include "sysid/rosbag/bag_file.hpp"
#include "sysid/rosbag/bag_recording.hpp"

using mppi::test::error_of;
using namespace mppi::sysid::bag;

namespace {

// The bags, written once per test run into a fresh folder, removed at exit.
struct BagDir {
  std::string path;
  BagDir() {
    const auto d = std::filesystem::temp_directory_path() / ("mppi_rosbag_test_" + std::to_string(::getpid()));
    std::filesystem::remove_all(d);
    std::filesystem::create_directories(d);
    path = d.string();
  }
  ~BagDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
};
const std::string& bag_dir() {
  static const BagDir dir;
  static const bool written = [] {
    const std::string cmd = std::string(MPPI_TEST_PYTHON) + " " + MPPI_TEST_ROSBAG_WRITER + " " + dir.path;
    return std::system(cmd.c_str()) == 0;
  }();
  if (!written) FAIL("the test bags could not be written by " << MPPI_TEST_ROSBAG_WRITER);
  return dir.path;
}
std::string bag(const std::string& name) { return bag_dir() + "/" + name; }

constexpr double kV = 2.0, kR = 4.0, kW = kV / kR;

// The latest message of a 50 Hz stream sent at offset + 0.02 j at or before t (-1: none yet).
long held_index(double t, double offset) { return t + 1e-9 < offset ? -1 : std::lround(std::floor((t - offset + 1e-9) / 0.02)); }

void check_circle(const mppi::sim::Recording& rec, double rate_hz, double pose_tol) {
  const auto& t = rec.column("t");
  REQUIRE(rec.rows() == static_cast<std::size_t>(std::floor(4.0 * rate_hz + 1e-6)) + 1);
  for (std::size_t k = 0; k < rec.rows(); ++k) {
    INFO("row " << k << " t " << t[k]);
    REQUIRE(t[k] == Approx(k / rate_hz).margin(1e-12));
    const double yaw = kW * t[k];
    CHECK(rec.column("x")[k] == Approx(kR * std::sin(yaw)).margin(pose_tol));
    CHECK(rec.column("y")[k] == Approx(kR * (1 - std::cos(yaw))).margin(pose_tol));
    CHECK(rec.column("yaw")[k] == Approx(yaw).margin(1e-9));
    CHECK(rec.column("vx")[k] == Approx(kV).margin(1e-9));
    CHECK(rec.column("vy")[k] == Approx(0).margin(1e-9));
    CHECK(rec.column("yaw_rate")[k] == Approx(kW).margin(1e-12));
    CHECK(rec.column("roll")[k] == Approx(0).margin(1e-12));
  }
}

}  // namespace

TEST_CASE("rosbag import: AutoRally topics of a circle drive read back at the known values", "[rosbag]") {
  const mppi::sim::Recording rec = read_bag_recording(bag("circle.bag"));
  check_circle(rec, 100.0, 1e-9);  // the pose topic's rate: the grid is the pose stamps
  CHECK(rec.metadata.at("source") == "rosbag circle.bag");
  CHECK(rec.metadata.at("controls") == "/chassisState (chassis state)");
  for (std::size_t k = 0; k < rec.rows(); ++k) {
    const double t = rec.column("t")[k];
    INFO("row " << k << " t " << t);
    const long s = held_index(t, 0.007), c = held_index(t, 0.005);
    if (s < 0) {  // before the first chassis state: no command known
      CHECK(std::isnan(rec.column("steer")[k]));
      CHECK(std::isnan(rec.column("throttle")[k]));
    } else {
      CHECK(rec.column("steer")[k] == Approx(0.25).margin(1e-12));  // AutoRally's -0.25 (right) is +0.25 left
      CHECK(rec.column("throttle")[k] == Approx(0.2 + 0.001 * s).margin(1e-12));
      CHECK(rec.column("front_brake")[k] == Approx(0.1).margin(1e-12));
      CHECK(rec.column("runstop_motion_enabled")[k] == (s < 100 ? 1.0 : 0.0));
    }
    if (c >= 0) {
      CHECK(rec.column("command_steer")[k] == Approx(0.3).margin(1e-12));
      CHECK(rec.column("command_throttle")[k] == Approx(0.1 + 0.001 * c).margin(1e-12));
    }
    CHECK(rec.column("wheel_speed")[k] == Approx(2.0).margin(1e-12));
    CHECK(rec.column("wheel_speed_lb")[k] == Approx(1.8).margin(1e-12));
    CHECK(rec.column("wheel_speed_rb")[k] == Approx(2.2).margin(1e-12));
  }
}

TEST_CASE("rosbag import: compressed chunks (lz4 and bz2) read as the plain bag", "[rosbag]") {
  const mppi::sim::Recording plain = read_bag_recording(bag("circle.bag"));
  for (const char* name : {"circle_lz4.bag", "circle_bz2.bag"}) {
    INFO(name);
    const mppi::sim::Recording rec = read_bag_recording(bag(name));
    REQUIRE(rec.columns == plain.columns);
    for (std::size_t c = 0; c < rec.columns.size(); ++c)
      for (std::size_t k = 0; k < rec.rows(); ++k)
        if (!std::isnan(plain.data[c][k])) CHECK(rec.data[c][k] == plain.data[c][k]);
  }
}

TEST_CASE("rosbag import: resampled to another rate with the controls from the command topic", "[rosbag]") {
  BagTopicMap map;
  map.apply_pairs("rate_hz=30,controls=command");
  const mppi::sim::Recording rec = read_bag_recording(bag("circle.bag"), map);
  check_circle(rec, 30.0, 2e-5);  // chord of 0.01 s on the circle: R (w dt)^2 / 8 = 1.25e-5 m
  CHECK_FALSE(rec.has_column("command_steer"));
  for (std::size_t k = 0; k < rec.rows(); ++k) {
    const long c = held_index(rec.column("t")[k], 0.005);
    if (c < 0) continue;
    CHECK(rec.column("steer")[k] == Approx(0.3).margin(1e-12));
    CHECK(rec.column("throttle")[k] == Approx(0.1 + 0.001 * c).margin(1e-12));
    CHECK(std::isnan(rec.column("front_brake")[k]));  // frontBrake -5: not commanded
  }
}

TEST_CASE("rosbag import: command_lead_s gives row k the command sent just after t_k", "[rosbag]") {
  BagTopicMap map;
  map.apply_pairs("controls=command,command_lead_s=0.01");
  const mppi::sim::Recording rec = read_bag_recording(bag("circle.bag"), map);
  CHECK(rec.metadata.at("rosbag_topics").find("command_lead_s=0.01") != std::string::npos);
  int shifted = 0;
  for (std::size_t k = 0; k < rec.rows(); ++k) {
    const double t = rec.column("t")[k];
    INFO("row " << k << " t " << t);
    const long c = std::min(held_index(t + 0.01, 0.005), 199L);  // commands at 0.005 + 0.02 j, j < 200
    if (c < 0) {
      CHECK(std::isnan(rec.column("throttle")[k]));
      continue;
    }
    CHECK(rec.column("throttle")[k] == Approx(0.1 + 0.001 * c).margin(1e-12));
    if (c != held_index(t, 0.005)) ++shifted;
  }
  CHECK(shifted > 100);  // half the rows take the next command
  CHECK_THROWS_WITH(map.apply_pairs("command_lead_s=1.5"), Catch::Contains("command_lead_s"));
}

TEST_CASE("rosbag import: another stack's topics through a topic map file", "[rosbag]") {
  const std::string map_file = bag_dir() + "/other_stack.yaml";
  std::ofstream(map_file) << "pose: /odom\ncommand: cmd\ntwist_frame: body\n";
  BagTopicMap map;
  map.apply_yaml_file(map_file);
  const mppi::sim::Recording rec = read_bag_recording(bag("other_stack.bag"), map);
  check_circle(rec, 100.0, 1e-9);
  CHECK(rec.metadata.at("controls") == "/cmd (command)");
  CHECK(rec.column("steer").back() == Approx(0.3));
  // The same bag read with the world-frame default rotates the body velocity once more: wrong.
  BagTopicMap world;
  world.apply_pairs("pose=/odom,command=/cmd");
  CHECK(read_bag_recording(bag("other_stack.bag"), world).column("vy")[100] == Approx(-kV * std::sin(kW * 1.0)));
}

TEST_CASE("rosbag import: a namespaced topic is found by its last name", "[rosbag]") {
  const mppi::sim::Recording rec = read_bag_recording(bag("namespaced.bag"));
  CHECK(rec.metadata.at("controls") == "/autorally_platform/chassisState (chassis state)");
  CHECK(rec.column("steer").back() == Approx(0.25));
  CHECK(rec.column("wheel_speed").back() == Approx(2.0));
  const BagFile file(bag("namespaced.bag"));
  CHECK(file.resolve("chassisState") == "/autorally_platform/chassisState");
  CHECK(file.resolve("/pose_estimate") == "/pose_estimate");
  CHECK(file.resolve("pose_estimate") == "/pose_estimate");
  CHECK(file.resolve("/chassisCommand").empty());
}

TEST_CASE("rosbag import: a topic map with an unknown key or a bad value is refused by name", "[rosbag]") {
  BagTopicMap map;
  CHECK(error_of([&] { map.apply_pairs("pose=/odom,speed=/v"); }).find("--topic: unknown topic map key 'speed'") == 0);
  CHECK(error_of([&] { map.apply_pairs("controls=both"); }) ==
        "--topic: topic map key 'controls': expected auto, state or command, got 'both'");
  CHECK(error_of([&] { map.apply_pairs("pose"); }) == "--topic: expected KEY=VALUE, got 'pose'");
  const std::string bad = bag_dir() + "/bad_map.yaml";
  std::ofstream(bad) << "pose: /odom\nrate_hz: fast\n";
  CHECK(error_of([&] { map.apply_yaml_file(bad); }) == bad + ":2: topic map key 'rate_hz': not a number: 'fast'");
}

TEST_CASE("rosbag import: a bag without the needed topics is refused naming them and listing its topics",
          "[rosbag]") {
  const std::string no_controls = bag("no_controls.bag");
  CHECK(error_of([&] { read_bag_recording(no_controls); }) ==
        no_controls +
            ": no control topic: neither chassis_state '/chassisState' (autorally_msgs/chassisState) nor command "
            "'/chassisCommand' (autorally_msgs/chassisCommand); the bag has /pose_estimate (nav_msgs/Odometry), "
            "/wheelSpeeds (autorally_msgs/wheelSpeeds) (other names: --topic chassis_state=/TOPIC or command=/TOPIC)");
  const std::string no_pose = bag("no_pose.bag");
  CHECK(error_of([&] { read_bag_recording(no_pose); }) ==
        no_pose +
            ": no pose topic '/pose_estimate' (nav_msgs/Odometry); the bag has /chassisCommand "
            "(autorally_msgs/chassisCommand), /chassisState (autorally_msgs/chassisState) (another name: --topic "
            "pose=/TOPIC)");
  BagTopicMap state_only;
  state_only.controls = "state";
  const std::string other = bag("other_stack.bag");
  CHECK(error_of([&] { read_bag_recording(other, state_only); })
            .find(other + ": no pose topic '/pose_estimate'") == 0);
}

TEST_CASE("rosbag import: a topic of the wrong type or another message definition is refused", "[rosbag]") {
  const std::string wrong = bag("wrong_type.bag");
  CHECK(error_of([&] { read_bag_recording(wrong); }) ==
        wrong + ": topic '/pose_estimate' is geometry_msgs/PoseStamped, expected nav_msgs/Odometry");
  const std::string old = bag("old_state.bag");
  CHECK(error_of([&] { read_bag_recording(old); })
            .find(old + ": topic '/chassisState' is autorally_msgs/chassisState with md5sum ") == 0);
  CHECK(error_of([&] { read_bag_recording(old); })
            .find("expected autorally_msgs/chassisState with md5sum cbd23a33a5ec266cc70ab1630ddbccef") !=
        std::string::npos);
}

TEST_CASE("rosbag import: a truncated or damaged or foreign file is refused naming it and never crashes", "[rosbag]") {
  std::ifstream in(bag("circle.bag"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  REQUIRE(bytes.size() > 100000);
  for (const std::size_t keep : {std::size_t{0}, std::size_t{13}, std::size_t{100}, std::size_t{4200},
                                 bytes.size() / 3, bytes.size() / 2, bytes.size() - 5000, bytes.size() - 1}) {
    const std::string cut = bag_dir() + "/cut_" + std::to_string(keep) + ".bag";
    std::ofstream(cut, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(keep));
    INFO("kept " << keep << " of " << bytes.size() << " bytes");
    const std::string e = error_of([&] { read_bag_recording(cut); });
    CHECK(e.find(cut + ": ") == 0);
    CHECK(e.find("rosbag") != std::string::npos);
  }
  // A message record inside a chunk whose header length points past the chunk (librosbag alone
  // would read past its buffer).
  std::string damaged = bytes;
  const std::size_t op = damaged.find(std::string("op=\x02", 4), 4096);
  REQUIRE(op != std::string::npos);
  for (int i = 0; i < 4; ++i) damaged[op - 8 + i] = static_cast<char>(i == 3 ? 0x7f : 0xff);
  const std::string hurt = bag_dir() + "/damaged.bag";
  std::ofstream(hurt, std::ios::binary).write(damaged.data(), static_cast<std::streamsize>(damaged.size()));
  CHECK(error_of([&] { read_bag_recording(hurt); }).find(hurt + ": damaged rosbag: a record header inside a chunk runs past the chunk") == 0);
  // A bag whose recording did not end cleanly has no index (index_pos 0).
  std::string unindexed = bytes;
  const std::size_t index_pos = unindexed.find("index_pos=");
  REQUIRE(index_pos != std::string::npos);
  for (int i = 0; i < 8; ++i) unindexed[index_pos + 10 + i] = 0;
  const std::string active = bag_dir() + "/unindexed.bag";
  std::ofstream(active, std::ios::binary).write(unindexed.data(), static_cast<std::streamsize>(unindexed.size()));
  CHECK(error_of([&] { read_bag_recording(active); }).find(active + ": damaged rosbag: the bag is not indexed") == 0);
  const std::string csv = bag_dir() + "/not_a_bag.bag";
  std::ofstream(csv) << "t,x,y\n0,1,2\n";
  CHECK(error_of([&] { read_bag_recording(csv); }) ==
        csv + ": not a rosbag (format 2.0 starts with '#ROSBAG V2.0')");
  CHECK(error_of([&] { read_bag_recording(bag_dir() + "/absent.bag"); }) ==
        bag_dir() + "/absent.bag: cannot open the file");
}

TEST_CASE("rosbag import: bytes changed anywhere give a recording or an error naming the file", "[rosbag]") {
  // Damage as a disk or a cut transfer leaves it: 1 to 20 random bytes changed, 60 times per bag.
  for (const char* name : {"circle.bag", "circle_lz4.bag", "circle_bz2.bag"}) {
    std::ifstream in(bag(name), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::mt19937 rng(7);
    const std::string hurt = bag_dir() + "/hurt_" + name;
    int refused = 0;
    for (int trial = 0; trial < 60; ++trial) {
      std::string b = bytes;
      const int changes = std::uniform_int_distribution<int>(1, 20)(rng);
      for (int c = 0; c < changes; ++c)
        b[std::uniform_int_distribution<std::size_t>(13, b.size() - 1)(rng)] =
            static_cast<char>(std::uniform_int_distribution<int>(0, 255)(rng));
      std::ofstream(hurt, std::ios::binary).write(b.data(), static_cast<std::streamsize>(b.size()));
      INFO(name << " trial " << trial);
      const std::string e = error_of([&] { read_bag_recording(hurt); });
      if (e != "(no mppi::Error thrown)") {
        CHECK(e.find(hurt + ": ") == 0);
        ++refused;
      }
    }
    CHECK(refused > 0);
  }
}

TEST_CASE("rosbag import: a message shorter or longer than its layout is refused naming topic and message",
          "[rosbag]") {
  std::vector<std::uint8_t> bytes(20, 0);  // seq, stamp, frame_id (empty), sender (empty), then no throttle
  CHECK(error_of([&] { decode_chassis_command(bytes, "run.bag: topic '/cmd' message 3"); }) ==
        "run.bag: topic '/cmd' message 3: the message ends at byte 20 inside a float64 at byte 20");
  bytes[12] = 100;  // frame_id of 100 bytes
  CHECK(error_of([&] { decode_chassis_command(bytes, "m"); }) == "m: the message ends at byte 20 inside a string at byte 16");
  bytes.assign(16 + 4 + 3 * 8 + 2, 0);
  CHECK(error_of([&] { decode_chassis_command(bytes, "m"); }) ==
        "m: 2 bytes after the end of the message (46 bytes, the layout reads 44)");
}
