// The authenticated chassis link: HMAC-SHA256 against RFC 4231's vectors and a datagram signed
// by Python's hmac module, tampered and unsigned datagrams dropped and counted without moving
// the car, key files (format, and refused when group or others may read them), no link off
// loopback without a key, and a keyed round trip through real sockets.
#include <catch2/catch.hpp>

#include <sys/stat.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "chassis/udp_adapter.hpp"
#include "chassis/udp_auth.hpp"
#include "error_of.hpp"

using namespace mppi::chassis;
using namespace mppi::chassis::udp;
using mppi::test::error_of;

namespace {
using Bytes = std::vector<std::uint8_t>;

Bytes from_hex(const std::string& hex) {
  Bytes b;
  for (std::size_t i = 0; i + 1 < hex.size(); i += 2) b.push_back(static_cast<std::uint8_t>(std::stoi(hex.substr(i, 2), nullptr, 16)));
  return b;
}
std::string to_hex(std::span<const std::uint8_t> b) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (std::uint8_t v : b) s += digits[v >> 4], s += digits[v & 15];
  return s;
}
Bytes text(const std::string& s) { return Bytes(s.begin(), s.end()); }

// The key 00 01 02 ... 1f.
const std::string kKeyHex = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";

// A runstop message (sender "OCS", sequence 42, motion enabled) and its tag under kKeyHex, made
// once with Python's hmac module (apps/udp_client.py's message() and hmac.new(key, m, sha256)).
const std::string kPythonSignedRunstop =
    "4d504348010228002a000000000000004f43530000000000000000000000000001000000de602b05"
    "0c1abf6c300329d387eb7b1f9b0d8cf073e6646c6f565d561df7cdc82b32a7a8";

bool moving(const Decision& d) { return d.command.throttle > 0.f; }

// A scratch folder, removed with its files at the end of the test.
struct ScratchDir {
  std::string path;
  ScratchDir() {
    char tmpl[] = "/tmp/mppi_key_test_XXXXXX";
    path = ::mkdtemp(tmpl);
  }
  ~ScratchDir() { std::filesystem::remove_all(path); }
  std::string write(const std::string& name, const std::string& content, mode_t mode) const {
    const std::string file = path + "/" + name;
    std::ofstream(file) << content;
    ::chmod(file.c_str(), mode);
    return file;
  }
};
}  // namespace

TEST_CASE("HMAC-SHA256 matches RFC 4231's test vectors", "[chassis][udp][auth]") {
  CHECK(to_hex(hmac_sha256(Bytes(20, 0x0b), text("Hi There"))) ==
        "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7");  // test case 1
  CHECK(to_hex(hmac_sha256(text("Jefe"), text("what do ya want for nothing?"))) ==
        "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");  // test case 2
  CHECK(to_hex(hmac_sha256(Bytes(131, 0xaa), text("Test Using Larger Than Block-Size Key - Hash Key First"))) ==
        "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54");  // test case 6
}

TEST_CASE("a datagram signed by Python's hmac module decodes and ours is byte for byte the same",
          "[chassis][udp][auth]") {
  const Key key = Key::from_hex(kKeyHex);
  const Bytes python = from_hex(kPythonSignedRunstop);
  REQUIRE(python.size() == kRunstopSize + kTagSize);
  const Message m = decode_authenticated(python, python.size(), key);
  REQUIRE(m.reason == Reject::kNone);
  CHECK(m.type == MessageType::kRunstop);
  CHECK(std::string(m.sender) == "OCS");
  CHECK(m.sequence == 42);
  CHECK(m.motion_enabled);
  const Datagram ours = seal_datagram(encode_runstop("OCS", 42, true), &key);
  CHECK(to_hex(ours.span()) == kPythonSignedRunstop);
  // Round trip of every message type.
  StateMessage s;
  s.time_s = 3.5;
  for (const Datagram& d : {seal_datagram(encode_command("mppi", 7, Command{0.1f, 0.2f, 0.f, 7}), &key),
                            seal_datagram(encode_state("chassis", 8, s), &key),
                            seal_datagram(encode_parameter("ocs", 9, "target_speed_mps", 4.0), &key)}) {
    CHECK(decode_authenticated(d.span(), d.size, key).reason == Reject::kNone);
    CHECK(decode_datagram(d.span(), d.size, &key).reason == Reject::kNone);
  }
}

TEST_CASE("tampered, unsigned and wrongly keyed datagrams are dropped, counted and never move the car",
          "[chassis][udp][auth]") {
  const Key key = Key::from_hex(kKeyHex);
  const Key other = Key::from_hex(std::string(64, 'e'));
  Arbiter arbiter(Priorities({{"mppi", 1}}));
  PacketFilter filter(64, key);
  FakeClock clock;
  auto feed = [&](std::span<const std::uint8_t> b) { return filter.handle(b, b.size(), arbiter, clock.now()); };

  // Unsigned: a well-formed message without a tag.
  CHECK(feed(encode_runstop("OCS", 1, true)) == Reject::kUnauthenticated);
  CHECK(feed(encode_command("mppi", 2, Command{0.f, 1.f, 0.f, 7})) == Reject::kUnauthenticated);
  // Signed with another key.
  CHECK(feed(seal_datagram(encode_runstop("OCS", 3, true), &other).span()) == Reject::kBadTag);
  // Every single-bit change of a signed command, also with its CRC made right again.
  const Datagram good = seal_datagram(encode_command("mppi", 100, Command{0.f, 1.f, 0.f, 7}), &key);
  long tampered = 0;
  for (std::size_t i = 0; i < good.size; ++i) {
    Bytes b(good.bytes.begin(), good.bytes.begin() + static_cast<long>(good.size));
    b[i] ^= 0x10;
    if (i < kCommandSize - 4) {  // fix the CRC: only the tag can tell
      const std::uint32_t c = crc32(std::span<const std::uint8_t>(b.data(), kCommandSize - 4));
      for (int k = 0; k < 4; ++k) b[kCommandSize - 4 + static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(c >> (8 * k));
    }
    const Reject r = feed(b);
    INFO("byte " << i << ": " << to_string(r));
    CHECK((r == Reject::kBadTag || r == Reject::kUnauthenticated));
    ++tampered;
  }
  // A tag cut short, and a tag alone.
  CHECK(feed(good.span().first(good.size - 1)) == Reject::kBadTag);
  CHECK(feed(good.span().last(kTagSize)) == Reject::kTruncated);
  CHECK_FALSE(moving(arbiter.decide(clock.now())));
  CHECK_FALSE(arbiter.decide(clock.now()).motion_enabled);
  const Counters& c = filter.counters();
  CHECK(c.unauthenticated() == 3 + tampered + 1);
  CHECK(c.commands_accepted == 0);
  CHECK(c.runstops_accepted == 0);
  CHECK(c.rejected[static_cast<std::size_t>(Reject::kReplayed)] == 0);  // never reached the replay table

  // The genuine datagrams are accepted, and the sequence check still holds.
  CHECK(feed(seal_datagram(encode_runstop("OCS", 50, true), &key).span()) == Reject::kNone);
  CHECK(feed(good.span()) == Reject::kNone);
  CHECK(moving(arbiter.decide(clock.now())));
  CHECK(feed(good.span()) == Reject::kReplayed);
  CHECK(c.commands_accepted == 1);
  CHECK(c.runstops_accepted == 1);
}

TEST_CASE("key files: 64 hex digits, refused when group or others may read them", "[chassis][udp][auth]") {
  ScratchDir dir;
  const std::string good = dir.write("car.key", kKeyHex + "\n", 0600);
  CHECK(Key::load(good).bytes()[31] == 0x1f);
  const std::string open = dir.write("open.key", kKeyHex + "\n", 0644);
  CHECK(error_of([&] { Key::load(open); }) ==
        "key file " + open + " has mode 0644; it must not be readable or writable by group or others (chmod 600 " +
            open + ")");
  const std::string group = dir.write("group.key", kKeyHex, 0640);
  CHECK(error_of([&] { Key::load(group); }).find("has mode 0640") != std::string::npos);
  const std::string short_key = dir.write("short.key", "abcd", 0600);
  CHECK(error_of([&] { Key::load(short_key); }).find("key file " + short_key + ": expected a key of 64 hex digits") == 0);
  const std::string not_hex = dir.write("nothex.key", std::string(63, 'a') + "g", 0600);
  CHECK(error_of([&] { Key::load(not_hex); }).find("not a hex digit at character 64") != std::string::npos);
  CHECK(error_of([&] { Key::load(dir.path + "/missing.key"); }).find("missing.key") != std::string::npos);
}

TEST_CASE("no end of the link off loopback without a key", "[chassis][udp][auth]") {
  ServerSettings off;
  off.bind_address = "0.0.0.0";
  off.port = 0;
  const std::string why = error_of([&] { UdpChassisServer server(off); });
  CHECK(why.find("0.0.0.0 is off loopback: it needs a key") != std::string::npos);
  CHECK(error_of([&] { UdpParameterListener listener("0.0.0.0", 0); }).find("off loopback") != std::string::npos);
  CHECK(error_of([&] { UdpChassisClient client("mppi", "192.0.2.1", 47800); }).find("off loopback") !=
        std::string::npos);
  CHECK(error_of([&] { UdpParameterSender sender("ocs", "192.0.2.1", 47801); }).find("off loopback") !=
        std::string::npos);
  CHECK(is_loopback_address("127.0.0.1"));
  CHECK(is_loopback_address("127.1.2.3"));
  CHECK_FALSE(is_loopback_address("0.0.0.0"));
  CHECK_FALSE(is_loopback_address("128.0.0.1"));
  CHECK_FALSE(is_loopback_address("localhost"));  // not an address: not trusted
  off.key = Key::from_hex(kKeyHex);
  UdpChassisServer keyed(off);  // with a key it starts
  CHECK(keyed.port() > 0);
}

TEST_CASE("keyed UDP round trip through real sockets: unsigned traffic is counted, not acted on",
          "[chassis][udp][auth]") {
  const Key key = Key::from_hex(kKeyHex);
  ServerSettings settings;
  settings.port = 0;
  settings.key = key;
  UdpChassisServer server(settings);
  Arbiter arbiter(Priorities({{"mppi", 1}}));
  UdpChassisClient intruder("mppi", "127.0.0.1", server.port());  // no key
  intruder.send_runstop(true);
  intruder.send_command(Command{0.f, 1.f, 0.f, actuator::kAll});
  UdpChassisClient controller("mppi", "127.0.0.1", server.port(), {}, key);
  UdpChassisClient operator_station("ocs", "127.0.0.1", server.port(), {}, key);
  operator_station.send_runstop(true);
  controller.send_command(Command{-0.5f, 0.4f, 0.f, actuator::kAll});
  SteadyClock clock;
  for (int i = 0; i < 200 && server.counters().received < 4; ++i) {
    server.poll(arbiter, clock.now());
    if (server.counters().received < 4) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  REQUIRE(server.counters().received == 4);
  CHECK(server.counters().unauthenticated() == 2);
  CHECK(server.counters().commands_accepted == 1);
  const Decision d = arbiter.decide(clock.now());
  CHECK(d.motion_enabled);
  CHECK(d.command.throttle == 0.4f);
  // State goes back signed to the clients heard (not the intruder); an unkeyed client drops it.
  StateMessage s;
  s.time_s = 2.0;
  server.send_state(s, clock.now());
  const auto got = controller.receive_state(2.0);
  REQUIRE(got.has_value());
  CHECK(got->time_s == 2.0);
  CHECK_FALSE(intruder.receive_state(0.2).has_value());

  UdpParameterListener listener("127.0.0.1", 0, 64, key);
  UdpParameterSender unsigned_sender("ocs", "127.0.0.1", listener.port());
  UdpParameterSender signed_sender("ocs2", "127.0.0.1", listener.port(), key);
  unsigned_sender.send("target_speed_mps", 1.0);
  signed_sender.send("target_speed_mps", 9.0);
  const auto p = listener.receive(1.0);
  REQUIRE(p);
  CHECK(p->sender == "ocs2");
  CHECK(p->value == 9.0);
  CHECK(listener.rejected() == 1);
}
