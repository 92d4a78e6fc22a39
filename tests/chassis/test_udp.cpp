// The UDP adapter: the wire format (CRC-32 check value, byte layout), every kind of bad
// datagram rejected with its counted reason and never moving the car, random corruption never
// accepted, and a loopback round trip through real sockets.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <thread>
#include <vector>

#include "chassis/calibration.hpp"
#include "chassis/udp_adapter.hpp"

using namespace mppi::chassis;
using namespace mppi::chassis::udp;

namespace {
using Bytes = std::vector<std::uint8_t>;
template <std::size_t N>
Bytes vec(const std::array<std::uint8_t, N>& a) { return Bytes(a.begin(), a.end()); }
void reseal(Bytes& b) {  // recompute the trailer after an edit (so only the edit is wrong)
  const std::uint32_t c = crc32(std::span<const std::uint8_t>(b.data(), b.size() - 4));
  for (int i = 0; i < 4; ++i) b[b.size() - 4 + i] = static_cast<std::uint8_t>(c >> (8 * i));
}
// The car moves only with throttle > 0 from a controller while the runstop allows it.
bool moving(const Decision& d) { return d.command.throttle > 0.f; }
}  // namespace

TEST_CASE("CRC-32 and the byte layout follow the documented format", "[chassis][udp]") {
  const std::string check = "123456789";
  CHECK(crc32(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(check.data()),
                                            check.size())) == 0xCBF43926u);  // the standard check value
  const auto m = encode_command("mppi", 0x0102030405060708ull, Command{0.5f, -1.f, 0.25f, 5});
  CHECK(m.size() == 52);
  CHECK(std::memcmp(m.data(), "MPCH", 4) == 0);
  CHECK(m[4] == 1);
  CHECK(m[5] == 1);
  CHECK((m[6] | (m[7] << 8)) == 52);
  CHECK(m[8] == 0x08);   // little-endian sequence
  CHECK(m[15] == 0x01);
  CHECK(std::memcmp(m.data() + 16, "mppi\0\0\0\0\0\0\0\0\0\0\0\0", 16) == 0);
  CHECK(m[32] == 0x00);  // 0.5f = 0x3F000000 little-endian
  CHECK(m[35] == 0x3F);
  CHECK(m[44] == 5);
  const Message d = decode(m, m.size());
  REQUIRE(d.reason == Reject::kNone);
  CHECK(d.command.steering == 0.5f);
  CHECK(d.command.throttle == -1.f);
  CHECK(d.command.front_brake == 0.25f);
  CHECK(d.sequence == 0x0102030405060708ull);
  CHECK(std::string(d.sender) == "mppi");
  StateMessage s;
  s.time_s = 12.5;
  s.state = {1, 2, 3, 4, 5, 6, 7};
  s.pulses_us = {1500, 1600, 1700};
  s.motion_enabled = true;
  s.watchdog_tripped = false;
  const auto e = encode_state("chassis", 9, s);
  const Message ds = decode(e, e.size());
  REQUIRE(ds.reason == Reject::kNone);
  CHECK(ds.state.state[6] == 7.f);
  CHECK(ds.state.pulses_us[2] == 1700);
  CHECK(ds.state.motion_enabled);
  CHECK_FALSE(ds.state.watchdog_tripped);
}

TEST_CASE("malformed, truncated, oversized, replayed and invalid datagrams are rejected with "
          "their reason and never move the car", "[chassis][udp]") {
  Arbiter arbiter(Priorities({{"mppi", 1}, {"joystick", 2}}));
  PacketFilter filter;
  FakeClock clock;
  std::array<long, kRejectCount> expected{};
  auto feed = [&](const Bytes& b, Reject want, std::size_t wire = 0) {
    const Reject got = filter.handle(b, wire ? wire : b.size(), arbiter, clock.now());
    ++expected[static_cast<std::size_t>(want)];
    CHECK(got == want);
    CHECK_FALSE(moving(arbiter.decide(clock.now())));
  };
  std::uint64_t seq = 100;
  // The runstop allows motion: only a controller's command could move the car now.
  REQUIRE(filter.handle(vec(encode_runstop("ocs", seq++, true)), kRunstopSize, arbiter, clock.now()) ==
          Reject::kNone);
  const Command go{0.2f, 1.f, 0.f, actuator::kAll};
  const Bytes good = vec(encode_command("mppi", 50, go));  // older than all below

  for (std::size_t n = 0; n < good.size(); ++n)  // every truncation
    feed(Bytes(good.begin(), good.begin() + static_cast<long>(n)),
         n < kHeaderSize + 4 || n >= 8 ? Reject::kTruncated : Reject::kBadMagic);
  {
    Bytes big = good;
    big.push_back(0);
    feed(big, Reject::kOversized);
    feed(Bytes(1000, 0x55), Reject::kOversized);
    feed(Bytes(good.begin(), good.end()), Reject::kOversized, 4096);  // receive buffer cut it
  }
  {
    Bytes b = good;
    b[0] = 'X';
    feed(b, Reject::kBadMagic);
    b = good, b[4] = 2, reseal(b);
    feed(b, Reject::kBadVersion);
    b = good, b[5] = 9, reseal(b);
    feed(b, Reject::kBadType);
    b = good, b[5] = 2, reseal(b);  // says runstop, is command-sized
    feed(b, Reject::kLengthMismatch);
    b = good, b[6] = 40, b.resize(40), reseal(b);  // a command cut to a runstop's length
    feed(b, Reject::kLengthMismatch);
    b = good, b[40] ^= 0x01;  // one flipped bit in the payload
    feed(b, Reject::kBadChecksum);
    b = good, b[16] = 0, reseal(b);  // empty name
    feed(b, Reject::kBadSender);
    b = good, b[18] = ' ', reseal(b);
    feed(b, Reject::kBadSender);
    b = good, b[25] = 'x', reseal(b);  // garbage after the NUL
    feed(b, Reject::kBadSender);
    b = good, b[45] = 1, reseal(b);
    feed(b, Reject::kReservedNotZero);
    feed(vec(encode_state("mppi", seq++, StateMessage{})), Reject::kBadType);  // wrong direction
    feed(vec(encode_command("intruder", seq++, go)), Reject::kUnknownSender);
    Bytes r = vec(encode_runstop("ocs", seq++, true));
    r[32] = 2, reseal(r);
    feed(r, Reject::kBadRunstopValue);
  }
  // Invalid values: well-formed datagrams whose command the chassis rejects.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const Command& bad : {Command{nan, 1.f, 0.f, actuator::kAll}, Command{0.f, 1.5f, 0.f, actuator::kAll},
                             Command{0.f, 1.f, -0.1f, actuator::kAll}, Command{0.f, 1.f, 0.f, 0},
                             Command{0.f, std::numeric_limits<float>::infinity(), 0.f, actuator::kThrottle}})
    feed(vec(encode_command("mppi", seq++, bad)), Reject::kInvalidCommand);

  // Replay: the good datagram is accepted once (the car moves), then rejected, as is any
  // older sequence; and a replayed "allow" runstop does not undo a later stop.
  std::uint64_t cmd_seq = seq++;
  const Bytes fresh = vec(encode_command("mppi", cmd_seq, go));
  REQUIRE(filter.handle(fresh, fresh.size(), arbiter, clock.now()) == Reject::kNone);
  CHECK(moving(arbiter.decide(clock.now())));
  clock.advance(seconds(0.15));  // the watchdog stops the car ...
  CHECK_FALSE(moving(arbiter.decide(clock.now())));
  feed(fresh, Reject::kReplayed);  // ... and replaying the command does not restart it
  feed(vec(encode_command("mppi", cmd_seq - 1, go)), Reject::kReplayed);
  feed(good, Reject::kReplayed);  // sequence 50 < cmd_seq
  const Bytes allow = vec(encode_runstop("ocs", seq++, true));
  REQUIRE(filter.handle(allow, allow.size(), arbiter, clock.now()) == Reject::kNone);
  REQUIRE(filter.handle(vec(encode_runstop("ocs", seq++, false)), kRunstopSize, arbiter, clock.now()) ==
          Reject::kNone);
  feed(allow, Reject::kReplayed);
  const Bytes go_again = vec(encode_command("mppi", seq++, go));
  REQUIRE(filter.handle(go_again, go_again.size(), arbiter, clock.now()) == Reject::kNone);
  CHECK_FALSE(moving(arbiter.decide(clock.now())));  // still runstopped

  // Random corruption of fresh, otherwise valid datagrams is never accepted.
  std::mt19937 rng(3);
  long corrupted = 0;
  for (int i = 0; i < 20000; ++i) {
    Bytes b = vec(encode_command("mppi", seq++, go));
    const int edits = std::uniform_int_distribution<int>(1, 4)(rng);
    for (int e = 0; e < edits; ++e)
      b[std::uniform_int_distribution<std::size_t>(0, b.size() - 1)(rng)] ^=
          static_cast<std::uint8_t>(std::uniform_int_distribution<int>(1, 255)(rng));
    if (std::uniform_int_distribution<int>(0, 3)(rng) == 0)
      b.resize(std::uniform_int_distribution<std::size_t>(0, b.size() - 1)(rng));
    const Reject got = filter.handle(b, b.size(), arbiter, clock.now());
    CHECK(got != Reject::kNone);
    ++corrupted;
    if (got != Reject::kNone) ++expected[static_cast<std::size_t>(got)];
  }
  CHECK(corrupted == 20000);

  const Counters& c = filter.counters();
  for (int r = 1; r < kRejectCount; ++r) {
    INFO(to_string(static_cast<Reject>(r)));
    CHECK(c.rejected[static_cast<std::size_t>(r)] == expected[static_cast<std::size_t>(r)]);
  }
  CHECK(c.commands_accepted == 2);
  CHECK(c.runstops_accepted == 3);
}

TEST_CASE("UDP loopback round trip through real sockets", "[chassis][udp]") {
  ServerSettings settings;
  settings.port = 0;  // any free port
  UdpChassisServer server(settings);
  Arbiter arbiter(Priorities({{"mppi", 1}}));
  const Calibration cal;
  UdpChassisClient controller("mppi", "127.0.0.1", server.port());
  UdpChassisClient operator_station("ocs", "127.0.0.1", server.port());
  operator_station.send_runstop(true);
  controller.send_command(Command{-0.5f, 0.4f, 0.f, actuator::kAll});
  std::vector<std::uint8_t> huge(3000, 0xAB);
  controller.send_raw(huge);  // oversized on the wire: counted, not accepted

  SteadyClock clock;
  Decision d;
  for (int i = 0; i < 200 && server.counters().received < 3; ++i) {
    server.poll(arbiter, clock.now());
    if (server.counters().received < 3) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  d = arbiter.decide(clock.now());
  REQUIRE(server.counters().received == 3);
  CHECK(server.counters().rejected[static_cast<std::size_t>(Reject::kOversized)] == 1);
  CHECK(d.motion_enabled);
  CHECK(d.command.steering == -0.5f);
  CHECK(d.command.throttle == 0.4f);

  StateMessage s;
  s.time_s = 1.25;
  s.state = {3.f, 4.f, 0.5f, 2.f, 0.f, 0.1f, 0.f};
  const PulseWidths p = cal.pulses(d.command).rounded();
  s.pulses_us = {static_cast<std::uint16_t>(p.steering_us), static_cast<std::uint16_t>(p.throttle_us),
                 static_cast<std::uint16_t>(p.front_brake_us)};
  s.applied = {d.command.steering, d.command.throttle, d.command.front_brake};
  s.motion_enabled = d.motion_enabled;
  s.watchdog_tripped = d.watchdog_tripped;
  server.send_state(s, clock.now());
  const auto got = controller.receive_state(2.0);
  REQUIRE(got.has_value());
  CHECK(got->time_s == 1.25);
  CHECK(got->pulses_us[0] == 1250);  // -0.5 on 1000/1500/2000
  CHECK(got->pulses_us[1] == 1700);
  CHECK(got->applied[1] == 0.4f);
  CHECK(got->motion_enabled);
  const auto other = operator_station.receive_state(2.0);  // every recent client gets it
  REQUIRE(other.has_value());
  CHECK(other->state[0] == 3.f);
}

TEST_CASE("parameter messages: documented layout, malformed names refused, never accepted by the chassis",
          "[chassis][udp]") {
  const auto m = encode_parameter("ocs", 7, "target_speed_mps", 8.5);
  CHECK(m.size() == 76);
  CHECK(m[5] == 4);
  CHECK((m[6] | (m[7] << 8)) == 76);
  CHECK(std::memcmp(m.data() + 32, "target_speed_mps", 16) == 0);
  for (int i = 32 + 16; i < 64; ++i) CHECK(m[static_cast<std::size_t>(i)] == 0);
  double value = 0;
  std::memcpy(&value, m.data() + 64, 8);  // little-endian host (x86-64, aarch64)
  CHECK(value == 8.5);
  const Message d = decode(m, m.size());
  REQUIRE(d.reason == Reject::kNone);
  CHECK(d.type == MessageType::kParameter);
  CHECK(std::string(d.parameter_name) == "target_speed_mps");
  CHECK(d.parameter_value == 8.5);
  // A name with a space, one not NUL-padded, an empty one.
  Bytes spaced = vec(m);
  spaced[32 + 6] = ' ';
  reseal(spaced);
  CHECK(decode(spaced, spaced.size()).reason == Reject::kBadParameterName);
  Bytes unpadded = vec(m);
  unpadded[32 + 20] = 'x';
  reseal(unpadded);
  CHECK(decode(unpadded, unpadded.size()).reason == Reject::kBadParameterName);
  Bytes empty = vec(m);
  std::memset(empty.data() + 32, 0, 32);
  reseal(empty);
  CHECK(decode(empty, empty.size()).reason == Reject::kBadParameterName);
  CHECK_THROWS(encode_parameter("ocs", 1, "", 1.0));
  CHECK_THROWS(encode_parameter("ocs", 1, std::string(32, 'a'), 1.0));
  // The chassis refuses it as a message it does not take: it cannot move the car.
  Arbiter arbiter(Priorities({{"mppi", 1}}));
  PacketFilter filter;
  CHECK(filter.handle(m, m.size(), arbiter, Time{0}) == Reject::kBadType);
}

TEST_CASE("parameter messages reach the stack through real sockets, replays refused", "[chassis][udp]") {
  UdpParameterListener listener("127.0.0.1", 0);
  UdpParameterSender sender("ocs", "127.0.0.1", listener.port());
  sender.send("target_speed_mps", 9.0);
  sender.send("speed_weight", 3.5);
  auto a = listener.receive(1.0);
  auto b = listener.receive(1.0);
  REQUIRE(a);
  REQUIRE(b);
  CHECK(a->sender == "ocs");
  CHECK(a->name == "target_speed_mps");
  CHECK(a->value == 9.0);
  CHECK(b->name == "speed_weight");
  // The same datagram again is a replay; a command is not a parameter message.
  UdpChassisClient raw("ocs", "127.0.0.1", listener.port(), 1);
  raw.send_raw(encode_parameter("ocs", 1, "target_speed_mps", 1.0));  // sequence 1 is far below
  raw.send_raw(encode_command("mppi", 5, Command{}));
  CHECK_FALSE(listener.receive(0.3));
  CHECK(listener.rejected() == 2);
}
