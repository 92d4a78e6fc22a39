#pragma once
// The chassis UDP message format, version 1 (docs/CHASSIS.md has the byte tables). Every
// datagram is one message: a 32-byte header, a fixed-size body per type, a CRC-32 trailer.
// All integers and floats little-endian (IEEE 754 floats).
//   header:  magic "MPCH" | u8 version = 1 | u8 type | u16 total length | u64 sequence |
//            char[16] sender (printable ASCII, NUL-padded, non-empty)
//   command (type 1, 52 bytes):  f32 steering, f32 throttle, f32 front_brake, u8 actuators,
//                                u8[3] zero
//   runstop (type 2, 40 bytes):  u8 motion_enabled (0 or 1), u8[3] zero
//   state   (type 3, 92 bytes, vehicle -> stack): f64 time_s, f32[7] x, y, yaw, vx, vy,
//            yaw_rate, roll, f32[3] applied steering, throttle, front_brake, u16[3] pulse widths
//            [us] steering, throttle, front_brake, u8 flags (1 motion enabled, 2 watchdog
//            tripped), u8 zero
//   parameter (type 4, 76 bytes, operator -> stack): char[32] name (1-31 printable ASCII, NUL-
//            padded; a cost parameter key, e.g. target_speed_mps), f64 value
//   trailer: u32 CRC-32 (IEEE 802.3, as zlib's crc32) of every byte before it.
// The sequence number must increase strictly per sender name (across message types); a
// datagram whose sequence is not above the last accepted one from that sender is a replay.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "chassis/command.hpp"

namespace mppi::chassis::udp {

inline constexpr std::uint8_t kMagic[4] = {'M', 'P', 'C', 'H'};
inline constexpr std::uint8_t kVersion = 1;
inline constexpr std::size_t kHeaderSize = 32;
inline constexpr std::size_t kSenderSize = 16;  // including the NUL padding: names <= 15 chars
inline constexpr std::size_t kCommandSize = 52;
inline constexpr std::size_t kRunstopSize = 40;
inline constexpr std::size_t kStateSize = 92;
inline constexpr std::size_t kParameterSize = 76;
inline constexpr std::size_t kParameterNameSize = 32;  // including the NUL padding: names <= 31 chars
inline constexpr std::size_t kMaxMessageSize = kStateSize;
inline constexpr int kDefaultPort = 47800;
inline constexpr int kDefaultParameterPort = 47801;  // the stack's port for parameter messages

enum class MessageType : std::uint8_t { kCommand = 1, kRunstop = 2, kState = 3, kParameter = 4 };

// Why a datagram was rejected (counted per reason by the server).
enum class Reject : std::uint8_t {
  kNone = 0,
  kTruncated,        // shorter than header + trailer, or than its declared length
  kOversized,        // longer than the largest message, or than its declared length
  kBadMagic,
  kBadVersion,
  kBadType,          // unknown type, or a type this end does not accept
  kLengthMismatch,   // declared length is not the length of its type
  kBadChecksum,
  kBadSender,        // empty, not NUL-padded, or not printable ASCII
  kReservedNotZero,
  kBadRunstopValue,  // motion_enabled other than 0 or 1
  kReplayed,         // sequence not above the sender's last accepted one
  kUnknownSender,    // a command from a controller not in the priority list
  kInvalidCommand,   // NaN, out of range, negative front brake, bad actuator mask
  kTooManySenders,   // the sender table (replay state) is full
  kRunstopRejected,  // the arbiter refused the runstop source (too many sources)
  kBadParameterName, // empty, not NUL-padded, or not printable ASCII
  kUnauthenticated,  // a message without an authentication tag, to an end with a key (udp_auth.hpp)
  kBadTag,           // an authentication tag that is not the message's under this end's key
};
inline constexpr int kRejectCount = 19;
const char* to_string(Reject reason);

struct StateMessage {
  double time_s = 0.0;
  std::array<float, 7> state{};          // x, y, yaw, vx, vy, yaw_rate, roll (mppi::state order)
  std::array<float, 3> applied{};        // steering, throttle, front_brake actually applied
  std::array<std::uint16_t, 3> pulses_us{};
  bool motion_enabled = false;
  bool watchdog_tripped = true;
};

// A decoded message; `reason` kNone when the bytes are a well-formed message.
struct Message {
  Reject reason = Reject::kNone;
  MessageType type = MessageType::kCommand;
  std::uint64_t sequence = 0;
  char sender[kSenderSize + 1] = {};    // NUL-terminated
  Command command;                       // type kCommand (not validated here)
  bool motion_enabled = false;           // type kRunstop
  StateMessage state;                    // type kState
  char parameter_name[kParameterNameSize + 1] = {};  // type kParameter, NUL-terminated
  double parameter_value = 0.0;          // type kParameter (not validated here)
};

// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320, init and final xor 0xFFFFFFFF).
std::uint32_t crc32(std::span<const std::uint8_t> bytes);

// Encoders; the sender name must be 1-15 printable ASCII characters (throws mppi::Error).
std::array<std::uint8_t, kCommandSize> encode_command(std::string_view sender, std::uint64_t sequence,
                                                      const Command& command);
std::array<std::uint8_t, kRunstopSize> encode_runstop(std::string_view sender, std::uint64_t sequence,
                                                      bool motion_enabled);
std::array<std::uint8_t, kStateSize> encode_state(std::string_view sender, std::uint64_t sequence,
                                                  const StateMessage& state);

std::array<std::uint8_t, kParameterSize> encode_parameter(std::string_view sender, std::uint64_t sequence,
                                                          std::string_view name, double value);

// Checks and decodes one datagram. `datagram_size` is its size on the wire (may exceed
// bytes.size() when the receive buffer truncated it). Does not check replay or content.
Message decode(std::span<const std::uint8_t> bytes, std::size_t datagram_size);

}  // namespace mppi::chassis::udp
