#pragma once
// The UDP adapter: a stack in any language drives the chassis with the messages of
// udp_protocol.hpp. The vehicle end (UdpChassisServer) drains its socket without blocking on
// each chassis tick, hands well-formed, fresh, valid messages to the arbiter and counts every
// rejected datagram by reason; rejected datagrams never reach the arbiter, so they cannot move
// the car. It answers each client that sent an accepted message in the last second with state
// messages. The stack end is UdpChassisClient. Loopback by default. With a key (udp_auth.hpp)
// every end signs what it sends and drops, and counts, datagrams without the right tag; off
// loopback an end refuses to start without one (the checksum only catches corruption, not
// forgery).
#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <netinet/in.h>

#include "chassis/arbiter.hpp"
#include "chassis/udp_auth.hpp"
#include "chassis/udp_protocol.hpp"

namespace mppi::chassis::udp {

struct Counters {
  long received = 0;
  long commands_accepted = 0;
  long runstops_accepted = 0;
  std::array<long, kRejectCount> rejected{};  // by Reject
  long total_rejected() const;
  // Datagrams dropped for a missing or wrong authentication tag (of those in `rejected`).
  long unauthenticated() const;
};

// The checks: the tag (with a key), decoding, message type, sender, replay, content; then the
// arbiter.
class PacketFilter {
 public:
  explicit PacketFilter(std::size_t max_senders = 64, std::optional<Key> key = {})
      : max_senders_(max_senders), key_(std::move(key)) {}
  // One datagram of `datagram_size` bytes on the wire (bytes may hold fewer if truncated).
  Reject handle(std::span<const std::uint8_t> bytes, std::size_t datagram_size, Arbiter& arbiter,
                Time now);
  const Counters& counters() const { return counters_; }

 private:
  Reject count(Reject r);
  std::size_t max_senders_;
  std::optional<Key> key_;
  std::vector<std::pair<std::string, std::uint64_t>> last_sequence_;
  Counters counters_;
};

// A UDP socket (IPv4), closed on destruction.
class Socket {
 public:
  Socket(const std::string& bind_address, int port);  // port 0 = any free port; throws mppi::Error
  ~Socket();
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;
  int port() const;
  int fd() const { return fd_; }
  // Receives one datagram without blocking; returns its full size on the wire (-1 if none).
  long receive(std::span<std::uint8_t> buffer, sockaddr_in* from);
  // Waits up to timeout_s for a datagram to arrive; true if one is ready.
  bool wait_readable(double timeout_s);
  bool send_to(std::span<const std::uint8_t> bytes, const sockaddr_in& to);

 private:
  int fd_ = -1;
};

struct ServerSettings {
  std::string bind_address = "127.0.0.1";  // loopback only by default
  int port = kDefaultPort;                 // 0 = any free port
  std::size_t max_senders = 64;            // replay table size
  int max_datagrams_per_poll = 256;        // bound on work per chassis tick
  double client_timeout_s = 1.0;           // state goes to clients heard from this recently
  std::optional<Key> key;                  // authenticate every datagram; required off loopback
};

class UdpChassisServer {
 public:
  // Throws mppi::Error if the socket cannot be bound, or is bound off loopback without a key.
  explicit UdpChassisServer(ServerSettings settings = {});
  int port() const { return socket_.port(); }
  // Drains pending datagrams (never blocks) into the arbiter; returns how many were read.
  int poll(Arbiter& arbiter, Time now);
  // Sends a state message to every recent client.
  void send_state(const StateMessage& state, Time now);
  const Counters& counters() const { return filter_.counters(); }

 private:
  struct Client {
    sockaddr_in address;
    Time last_heard;
  };
  ServerSettings settings_;
  Socket socket_;
  PacketFilter filter_;
  std::vector<Client> clients_;
  std::uint64_t state_sequence_;
};

class UdpChassisClient {
 public:
  // `sender` signs every message (controller name in the priorities, or runstop source).
  // The first sequence number defaults to the wall clock in microseconds, so a restarted
  // client continues above its previous numbers. With a key it signs its messages and accepts
  // only state messages signed with it; a chassis off loopback needs one (throws mppi::Error).
  UdpChassisClient(std::string sender, const std::string& host = "127.0.0.1",
                   int port = kDefaultPort, std::optional<std::uint64_t> first_sequence = {},
                   std::optional<Key> key = {});
  void send_command(const Command& command);
  void send_runstop(bool motion_enabled);
  // Sends raw bytes, unsigned (tests of malformed datagrams).
  void send_raw(std::span<const std::uint8_t> bytes);
  // The next valid state message within timeout_s, if any.
  std::optional<StateMessage> receive_state(double timeout_s);
  std::uint64_t next_sequence() const { return sequence_; }
  long rejected_replies() const { return rejected_; }

 private:
  std::string sender_;
  std::optional<Key> key_;
  Socket socket_;
  sockaddr_in server_{};
  std::uint64_t sequence_;
  std::uint64_t last_state_sequence_ = 0;
  bool have_state_ = false;
  long rejected_ = 0;
};

// A parameter change for the stack (e.g. the controller's target speed), as received.
struct ParameterUpdate {
  std::string sender;
  std::string name;
  double value = 0.0;
};

// The stack end of parameter messages (type 4): an operator station or script changes a cost
// parameter of the running controller. Checks like the chassis server's: well-formed, a
// parameter message, sequence rising per sender; the value itself is checked by whoever
// applies it (Controller::set_cost_param names the key and range it refuses). With a key, only
// messages signed with it; off loopback it needs one (throws mppi::Error).
class UdpParameterListener {
 public:
  UdpParameterListener(const std::string& bind_address = "127.0.0.1", int port = kDefaultParameterPort,
                       std::size_t max_senders = 64, std::optional<Key> key = {});
  int port() const { return socket_.port(); }
  // The next accepted parameter message within timeout_s, if any.
  std::optional<ParameterUpdate> receive(double timeout_s);
  long rejected() const { return rejected_; }

 private:
  std::optional<Key> key_;
  Socket socket_;
  std::size_t max_senders_;
  std::vector<std::pair<std::string, std::uint64_t>> last_sequence_;
  long rejected_ = 0;
};

// Sends parameter messages to a stack's UdpParameterListener. The first sequence number is the
// wall clock in microseconds (a restarted sender continues above its previous numbers). With a
// key it signs them; a stack off loopback needs one (throws mppi::Error).
class UdpParameterSender {
 public:
  UdpParameterSender(std::string sender, const std::string& host = "127.0.0.1", int port = kDefaultParameterPort,
                     std::optional<Key> key = {});
  void send(std::string_view name, double value);

 private:
  std::string sender_;
  std::optional<Key> key_;
  Socket socket_;
  sockaddr_in to_{};
  std::uint64_t sequence_;
};

}  // namespace mppi::chassis::udp
