#include "sysid/rosbag/bag_messages.hpp"

#include <cstring>

#include "base/error.hpp"

namespace mppi::sysid::bag {

namespace {

// Little-endian reader over a message's bytes; every read is bounds-checked.
class ByteReader {
 public:
  ByteReader(const std::vector<std::uint8_t>& bytes, const std::string& what) : b_(bytes), what_(what) {}
  std::uint32_t u32() {
    need(4, "uint32");
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | b_[pos_ + i];
    pos_ += 4;
    return v;
  }
  bool boolean() {
    need(1, "bool");
    return b_[pos_++] != 0;
  }
  double f64() {
    need(8, "float64");
    std::uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | b_[pos_ + i];
    pos_ += 8;
    double d;
    std::memcpy(&d, &v, sizeof d);
    return d;
  }
  std::string str() {
    const std::uint32_t n = u32();
    need(n, "string");
    std::string s(reinterpret_cast<const char*>(b_.data() + pos_), n);
    pos_ += n;
    return s;
  }
  Header header() {
    Header h;
    h.seq = u32();
    const std::uint32_t sec = u32(), nsec = u32();
    h.stamp_ns = static_cast<std::int64_t>(sec) * 1000000000 + nsec;
    h.frame_id = str();
    return h;
  }
  void skip_f64(std::size_t n) {
    need(8 * n, "float64 array");
    pos_ += 8 * n;
  }
  void finish() const {
    if (pos_ != b_.size())
      throw Error(what_ + ": " + std::to_string(b_.size() - pos_) + " bytes after the end of the message (" +
                  std::to_string(b_.size()) + " bytes, the layout reads " + std::to_string(pos_) + ")");
  }

 private:
  void need(std::size_t n, const char* field) const {
    if (n > b_.size() - pos_)
      throw Error(what_ + ": the message ends at byte " + std::to_string(b_.size()) + " inside a " + std::string(field) +
                  " at byte " + std::to_string(pos_));
  }
  const std::vector<std::uint8_t>& b_;
  const std::string& what_;
  std::size_t pos_ = 0;
};

}  // namespace

Odometry decode_odometry(const std::vector<std::uint8_t>& bytes, const std::string& what) {
  ByteReader r(bytes, what);
  Odometry m;
  m.header = r.header();
  m.child_frame_id = r.str();
  for (double& v : m.position_m) v = r.f64();
  for (double& v : m.orientation_xyzw) v = r.f64();
  r.skip_f64(36);  // pose covariance
  for (double& v : m.linear_mps) v = r.f64();
  for (double& v : m.angular_radps) v = r.f64();
  r.skip_f64(36);  // twist covariance
  r.finish();
  return m;
}

ChassisState decode_chassis_state(const std::vector<std::uint8_t>& bytes, const std::string& what) {
  ByteReader r(bytes, what);
  ChassisState m;
  m.header = r.header();
  m.throttle_relay_enabled = r.boolean();
  m.autonomous_enabled = r.boolean();
  m.runstop_motion_enabled = r.boolean();
  m.steering_commander = r.str();
  m.steering = r.f64();
  m.throttle_commander = r.str();
  m.throttle = r.f64();
  m.front_brake_commander = r.str();
  m.front_brake = r.f64();
  r.finish();
  return m;
}

ChassisCommand decode_chassis_command(const std::vector<std::uint8_t>& bytes, const std::string& what) {
  ByteReader r(bytes, what);
  ChassisCommand m;
  m.header = r.header();
  m.sender = r.str();
  m.throttle = r.f64();
  m.steering = r.f64();
  m.front_brake = r.f64();
  r.finish();
  return m;
}

WheelSpeeds decode_wheel_speeds(const std::vector<std::uint8_t>& bytes, const std::string& what) {
  ByteReader r(bytes, what);
  WheelSpeeds m;
  m.header = r.header();
  m.lf_mps = r.f64();
  m.rf_mps = r.f64();
  m.lb_mps = r.f64();
  m.rb_mps = r.f64();
  r.finish();
  return m;
}

}  // namespace mppi::sysid::bag
