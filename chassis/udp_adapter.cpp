#include "chassis/udp_adapter.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>

#include "base/error.hpp"

namespace mppi::chassis::udp {

long Counters::unauthenticated() const {
  return rejected[static_cast<std::size_t>(Reject::kUnauthenticated)] +
         rejected[static_cast<std::size_t>(Reject::kBadTag)];
}

long Counters::total_rejected() const {
  long n = 0;
  for (std::size_t i = 1; i < rejected.size(); ++i) n += rejected[i];
  return n;
}

Reject PacketFilter::count(Reject r) {
  ++counters_.rejected[static_cast<std::size_t>(r)];
  return r;
}

Reject PacketFilter::handle(std::span<const std::uint8_t> bytes, std::size_t datagram_size,
                            Arbiter& arbiter, Time now) {
  ++counters_.received;
  const Message m = decode_datagram(bytes, datagram_size, key_ ? &*key_ : nullptr);
  if (m.reason != Reject::kNone) return count(m.reason);
  if (m.type == MessageType::kState || m.type == MessageType::kParameter)
    return count(Reject::kBadType);  // vehicle -> stack, operator -> stack only
  int index = -1;
  if (m.type == MessageType::kCommand) {
    index = arbiter.priorities().index_of(m.sender);
    if (index < 0) return count(Reject::kUnknownSender);
  }
  // Replay: the sequence must rise strictly per sender.
  std::pair<std::string, std::uint64_t>* entry = nullptr;
  for (auto& e : last_sequence_)
    if (e.first == m.sender) entry = &e;
  if (entry) {
    if (m.sequence <= entry->second) return count(Reject::kReplayed);
    entry->second = m.sequence;
  } else {
    if (last_sequence_.size() >= max_senders_) return count(Reject::kTooManySenders);
    last_sequence_.emplace_back(m.sender, m.sequence);
  }
  if (m.type == MessageType::kCommand) {
    if (arbiter.submit_command(index, m.command, now) != SubmitStatus::kAccepted)
      return count(Reject::kInvalidCommand);
    ++counters_.commands_accepted;
  } else {
    if (arbiter.submit_runstop(m.sender, m.motion_enabled, now) != SubmitStatus::kAccepted)
      return count(Reject::kRunstopRejected);
    ++counters_.runstops_accepted;
  }
  return Reject::kNone;
}

namespace {
sockaddr_in make_address(const std::string& host, int port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  if (inet_pton(AF_INET, host.c_str(), &a.sin_addr) != 1)
    throw Error("udp: '" + host + "' is not an IPv4 address");
  return a;
}
bool same_address(const sockaddr_in& a, const sockaddr_in& b) {
  return a.sin_addr.s_addr == b.sin_addr.s_addr && a.sin_port == b.sin_port;
}
// The address, once require_key_off_loopback() let it pass (member initialisers: before binding).
const std::string& checked(const std::string& what, const std::string& address, const std::optional<Key>& key) {
  require_key_off_loopback(what, address, key ? &*key : nullptr);
  return address;
}
// A stack end binds to loopback to talk to a chassis there, else to every address (the replies
// come from the chassis' address).
std::string local_address_for(const std::string& host) { return is_loopback_address(host) ? "127.0.0.1" : "0.0.0.0"; }
std::uint64_t wall_clock_us() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}
}  // namespace

Socket::Socket(const std::string& bind_address, int port) {
  if (port < 0 || port > 65535) throw Error("udp: port must be in [0, 65535]");
  const sockaddr_in a = make_address(bind_address, port);
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw Error(std::string("udp: socket(): ") + std::strerror(errno));
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd_);
    throw Error("udp: cannot bind " + bind_address + ":" + std::to_string(port) + ": " + why);
  }
}

Socket::~Socket() {
  if (fd_ >= 0) ::close(fd_);
}

int Socket::port() const {
  sockaddr_in a{};
  socklen_t len = sizeof a;
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
  return ntohs(a.sin_port);
}

long Socket::receive(std::span<std::uint8_t> buffer, sockaddr_in* from) {
  sockaddr_in a{};
  socklen_t len = sizeof a;
  // MSG_TRUNC: the return value is the datagram's real size even if the buffer is smaller.
  const ssize_t n = ::recvfrom(fd_, buffer.data(), buffer.size(), MSG_TRUNC,
                               reinterpret_cast<sockaddr*>(&a), &len);
  if (n < 0) return -1;
  if (from) *from = a;
  return static_cast<long>(n);
}

bool Socket::wait_readable(double timeout_s) {
  pollfd p{fd_, POLLIN, 0};
  const int ms = static_cast<int>(std::ceil(std::max(0.0, timeout_s) * 1000.0));
  return ::poll(&p, 1, ms) > 0 && (p.revents & POLLIN);
}

bool Socket::send_to(std::span<const std::uint8_t> bytes, const sockaddr_in& to) {
  return ::sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to),
                  sizeof to) == static_cast<ssize_t>(bytes.size());
}

UdpChassisServer::UdpChassisServer(ServerSettings settings)
    : settings_(std::move(settings)),
      socket_(checked("the chassis link's vehicle end", settings_.bind_address, settings_.key), settings_.port),
      filter_(settings_.max_senders, settings_.key),
      state_sequence_(static_cast<std::uint64_t>(
          std::chrono::duration_cast<std::chrono::microseconds>(
              std::chrono::system_clock::now().time_since_epoch()).count())) {}

int UdpChassisServer::poll(Arbiter& arbiter, Time now) {
  std::array<std::uint8_t, kMaxDatagramSize + 1> buffer;  // +1: a longer datagram shows as oversized
  int read = 0;
  for (; read < settings_.max_datagrams_per_poll; ++read) {
    sockaddr_in from{};
    const long n = socket_.receive(buffer, &from);
    if (n < 0) break;
    const std::size_t kept = std::min<std::size_t>(static_cast<std::size_t>(n), buffer.size());
    const Reject r = filter_.handle(std::span<const std::uint8_t>(buffer.data(), kept),
                                    static_cast<std::size_t>(n), arbiter, now);
    if (r != Reject::kNone) continue;
    bool known = false;
    for (auto& c : clients_)
      if (same_address(c.address, from)) c.last_heard = now, known = true;
    if (!known) {
      if (clients_.size() >= 8) {  // replace the stalest
        auto oldest = clients_.begin();
        for (auto it = clients_.begin(); it != clients_.end(); ++it)
          if (it->last_heard < oldest->last_heard) oldest = it;
        *oldest = {from, now};
      } else {
        clients_.push_back({from, now});
      }
    }
  }
  return read;
}

void UdpChassisServer::send_state(const StateMessage& state, Time now) {
  const Datagram d = seal_datagram(encode_state("chassis", ++state_sequence_, state),
                                   settings_.key ? &*settings_.key : nullptr);
  for (const auto& c : clients_)
    if (now - c.last_heard < seconds(settings_.client_timeout_s)) socket_.send_to(d.span(), c.address);
}

UdpChassisClient::UdpChassisClient(std::string sender, const std::string& host, int port,
                                   std::optional<std::uint64_t> first_sequence, std::optional<Key> key)
    : sender_(std::move(sender)),
      key_(std::move(key)),
      socket_(local_address_for(checked("the chassis link to a vehicle", host, key_)), 0),
      server_(make_address(host, port)),
      sequence_(first_sequence ? *first_sequence : wall_clock_us()) {
  encode_runstop(sender_, 0, false);  // validates the sender name (throws mppi::Error)
}

void UdpChassisClient::send_command(const Command& command) {
  socket_.send_to(seal_datagram(encode_command(sender_, sequence_++, command), key_ ? &*key_ : nullptr).span(),
                  server_);
}

void UdpChassisClient::send_runstop(bool motion_enabled) {
  socket_.send_to(
      seal_datagram(encode_runstop(sender_, sequence_++, motion_enabled), key_ ? &*key_ : nullptr).span(), server_);
}

void UdpChassisClient::send_raw(std::span<const std::uint8_t> bytes) { socket_.send_to(bytes, server_); }

std::optional<StateMessage> UdpChassisClient::receive_state(double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + seconds(timeout_s);
  std::array<std::uint8_t, kMaxDatagramSize + 1> buffer;
  while (true) {
    sockaddr_in from{};
    const long n = socket_.receive(buffer, &from);
    if (n >= 0) {
      const std::size_t kept = std::min<std::size_t>(static_cast<std::size_t>(n), buffer.size());
      const Message m = decode_datagram(std::span<const std::uint8_t>(buffer.data(), kept),
                                        static_cast<std::size_t>(n), key_ ? &*key_ : nullptr);
      if (m.reason == Reject::kNone && m.type == MessageType::kState &&
          (!have_state_ || m.sequence > last_state_sequence_)) {
        have_state_ = true;
        last_state_sequence_ = m.sequence;
        return m.state;
      }
      ++rejected_;
      continue;
    }
    const double left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0 || !socket_.wait_readable(left)) return std::nullopt;
  }
}

UdpParameterListener::UdpParameterListener(const std::string& bind_address, int port, std::size_t max_senders,
                                           std::optional<Key> key)
    : key_(std::move(key)),
      socket_(checked("the parameter listener", bind_address, key_), port),
      max_senders_(max_senders) {}

std::optional<ParameterUpdate> UdpParameterListener::receive(double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + seconds(timeout_s);
  std::array<std::uint8_t, kMaxDatagramSize + 1> buffer;
  while (true) {
    sockaddr_in from{};
    const long n = socket_.receive(buffer, &from);
    if (n >= 0) {
      const std::size_t kept = std::min<std::size_t>(static_cast<std::size_t>(n), buffer.size());
      const Message m = decode_datagram(std::span<const std::uint8_t>(buffer.data(), kept),
                                        static_cast<std::size_t>(n), key_ ? &*key_ : nullptr);
      if (m.reason != Reject::kNone || m.type != MessageType::kParameter) {
        ++rejected_;
        continue;
      }
      std::pair<std::string, std::uint64_t>* entry = nullptr;
      for (auto& e : last_sequence_)
        if (e.first == m.sender) entry = &e;
      if (entry ? m.sequence <= entry->second : last_sequence_.size() >= max_senders_) {
        ++rejected_;  // replayed, or too many senders
        continue;
      }
      if (entry) entry->second = m.sequence;
      else last_sequence_.emplace_back(m.sender, m.sequence);
      return ParameterUpdate{m.sender, m.parameter_name, m.parameter_value};
    }
    const double left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0 || !socket_.wait_readable(left)) return std::nullopt;
  }
}

UdpParameterSender::UdpParameterSender(std::string sender, const std::string& host, int port, std::optional<Key> key)
    : sender_(std::move(sender)),
      key_(std::move(key)),
      socket_(local_address_for(checked("parameter messages to a stack", host, key_)), 0),
      to_(make_address(host, port)),
      sequence_(wall_clock_us()) {
  encode_runstop(sender_, 0, false);  // validates the sender name (throws mppi::Error)
}

void UdpParameterSender::send(std::string_view name, double value) {
  socket_.send_to(seal_datagram(encode_parameter(sender_, sequence_++, name, value), key_ ? &*key_ : nullptr).span(),
                  to_);
}

}  // namespace mppi::chassis::udp
