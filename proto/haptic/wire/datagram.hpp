#pragma once
// The UDP data plane: fixed-layout, little-endian datagrams (docs/protocol.md).
//
// Every datagram is   header (40 bytes) | payload (fixed size per type) | tag (8 bytes).
// The tag is SipHash-2-4 over header and payload, keyed with the session's 16-byte key from
// OpenSession. Fields are written byte by byte in little-endian order; no struct is ever cast onto
// the buffer, so the layout is the same on every compiler and host.
//
// Header (offsets in bytes):
//   0  u32 magic          kMagic ("HPTC" read as little-endian bytes 'H','P','T','C')
//   4  u16 version        kWireVersion
//   6  u16 type           DatagramType
//   8  u64 session_id
//  16  u64 sequence       per sender, per session, starts at 1, +1 per datagram
//  24  i64 time_ns        sender's clock: server time for State and PathChallenge, client time
//                         for Heartbeat and PathResponse
//  32  u32 payload_size   must equal the type's fixed payload size
//  36  u32 reserved       zero

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace haptic::wire {

inline constexpr std::uint32_t kMagic = 0x43545048u;  // bytes "HPTC"
// 2: path validation (PathChallenge/Response); 3: buttons in State, StateOriented; 4: the
// client's receive report and the round-trip echo in Heartbeat; 5: the torque on the tool,
// tau_T_W, in StateOriented.
inline constexpr std::uint16_t kWireVersion = 5;
inline constexpr std::size_t kHeaderSize = 40;
inline constexpr std::size_t kTagSize = 8;

enum class DatagramType : std::uint16_t {
  kState = 1,      // server -> client, one tick's sample
  kHeartbeat = 2,  // client -> server, keeps the lease and tells the server where to send state
  // server -> the address a heartbeat came from, before any state goes there: prove you receive
  // here by echoing the nonce (so a client cannot aim the stream at a bystander by spoofing).
  kPathChallenge = 3,
  kPathResponse = 4,  // client -> server, from the challenged address: the nonce echoed
  // server -> client, one tick's sample of a device that reports the tool's orientation: State,
  // then the orientation and the torque on the tool (a device without one sends State, 56 bytes
  // shorter).
  kStateOriented = 5,
};

/// A 128-bit SipHash key.
using Key = std::array<std::uint8_t, 16>;

struct Header {
  DatagramType type = DatagramType::kState;
  std::uint64_t session_id = 0;
  std::uint64_t sequence = 0;
  std::int64_t time_ns = 0;
};

struct Vec3d {
  double x = 0.0, y = 0.0, z = 0.0;
  friend bool operator==(const Vec3d&, const Vec3d&) = default;
};

/// A unit quaternion (w, x, y, z).
struct Quatd {
  double w = 1.0, x = 0.0, y = 0.0, z = 0.0;
  friend bool operator==(const Quatd&, const Quatd&) = default;
};

/// One tick's sample of the device and the scene. Frames: W (world), T (tool point).
struct StatePayload {
  std::uint64_t tick = 0;      // Loop tick index.
  Vec3d p_WT;                  // Tool position. Unit: m.
  Vec3d v_WT;                  // Tool velocity. Unit: m/s.
  Vec3d F_T_W;                 // Commanded force on the tool, after safety. Unit: N.
  Vec3d p_WP;                  // Proxy (contact) point; equals p_WT when not in contact. Unit: m.
  std::uint32_t contact_count = 0;  // Objects in contact this tick.
  std::uint32_t flags = 0;          // StateFlags bits.
  std::uint32_t buttons = 0;        // The device's buttons, bit i for button i.
  /// Sent as kStateOriented when true: the tool's orientation R_WT and the torque tau_T_W; else
  /// kState, R_WT is identity and tau_T_W zero.
  bool has_orientation = false;
  Quatd R_WT;
  /// Commanded torque on the tool, after safety, expressed in W (zero for a device that takes no
  /// torque). Only in kStateOriented: a device without orientation takes no torque. Unit: N·m.
  Vec3d tau_T_W;
  friend bool operator==(const StatePayload&, const StatePayload&) = default;
};

enum StateFlags : std::uint32_t {
  kFlagForceSaturated = 1u << 0,
  kFlagForceFault = 1u << 1,    // a non-finite force was replaced by zero
  kFlagRampingOut = 1u << 2,    // some force is ramping to zero (removed objects, shutdown)
  kFlagDeviceFault = 1u << 3,   // the device's reading failed or was not finite: zero commanded,
                                // the last good state shown
};

/// The client's heartbeat: it keeps the lease, and reports how the stream arrives (what the server
/// cannot see: datagrams lost on the way, and how long the way is, from the echo).
struct HeartbeatPayload {
  std::int64_t client_time_ns = 0;     // Client clock when sent.
  std::uint64_t last_state_sequence = 0;  // Highest state sequence received, 0 if none.
  std::uint64_t states_received = 0;   // State datagrams accepted in this session so far.
  std::uint64_t states_lost = 0;       // Sequence gaps in this session so far, net of late arrivals.
  /// The round-trip echo, when last_state_sequence > 0: the time_ns (server time) of the newest
  /// State received, and how long ago it arrived when this heartbeat left (ns, client clock). The
  /// server's time at receipt − echo − hold is the round trip from that tick's stamp.
  std::int64_t echo_state_time_ns = 0;
  std::int64_t echo_hold_ns = 0;
  friend bool operator==(const HeartbeatPayload&, const HeartbeatPayload&) = default;
};

struct PathChallengePayload {
  std::uint64_t nonce = 0;              // Random, fresh for each challenged address.
  std::uint64_t heartbeat_sequence = 0; // The heartbeat this answers.
  friend bool operator==(const PathChallengePayload&, const PathChallengePayload&) = default;
};

struct PathResponsePayload {
  std::uint64_t nonce = 0;           // The challenge's, echoed.
  std::int64_t client_time_ns = 0;   // Client clock when sent.
  friend bool operator==(const PathResponsePayload&, const PathResponsePayload&) = default;
};

inline constexpr std::size_t kStatePayloadSize = 8 + 4 * 24 + 4 + 4 + 4;  // 116
// R_WT (4 f64), then tau_T_W (3 f64).
inline constexpr std::size_t kStateOrientedPayloadSize = kStatePayloadSize + 32 + 24;  // 172
inline constexpr std::size_t kHeartbeatPayloadSize = 48;
inline constexpr std::size_t kPathPayloadSize = 16;  // challenge and response alike
inline constexpr std::size_t kStateDatagramSize = kHeaderSize + kStatePayloadSize + kTagSize;
inline constexpr std::size_t kStateOrientedDatagramSize =
    kHeaderSize + kStateOrientedPayloadSize + kTagSize;
inline constexpr std::size_t kHeartbeatDatagramSize = kHeaderSize + kHeartbeatPayloadSize + kTagSize;
/// A challenge is shorter than the heartbeat that draws it: no amplification.
inline constexpr std::size_t kPathDatagramSize = kHeaderSize + kPathPayloadSize + kTagSize;
inline constexpr std::size_t kMaxDatagramSize = kStateOrientedDatagramSize;

/// Why a datagram was rejected. Every rejection is counted by the receiver, never thrown.
/// Checks run in the order listed; the first that fails is reported.
enum class DecodeError : std::uint8_t {
  kNone = 0,
  kTooShort,         // shorter than header + tag
  kBadMagic,
  kBadVersion,
  kUnknownType,      // not a DatagramType, or not the type the decoder expects
  kBadPayloadSize,   // payload_size does not match the type, the length disagrees, or reserved != 0
  kBadTag,           // authentication failed
};

/// A short, static, human-readable name ("bad tag"); never null.
const char* to_string(DecodeError error);

/// Reads the header without checking the tag (to find the session, and so the key).
/// Fails on short, wrong-magic, wrong-version, unknown-type, wrong-length or nonzero-reserved
/// datagrams. `header` is written only on success.
DecodeError peek_header(std::span<const std::uint8_t> datagram, Header& header);

/// Encoders write exactly their type's datagram size (kStateDatagramSize, kHeartbeatDatagramSize,
/// kPathDatagramSize) into `out` and return it, or 0 (writing nothing) when `out` is too small.
/// header.type is set by the encoder.
std::size_t encode_state(Header header, const StatePayload& state, const Key& key,
                         std::span<std::uint8_t> out);
std::size_t encode_heartbeat(Header header, const HeartbeatPayload& heartbeat, const Key& key,
                             std::span<std::uint8_t> out);
std::size_t encode_path_challenge(Header header, const PathChallengePayload& challenge,
                                  const Key& key, std::span<std::uint8_t> out);
std::size_t encode_path_response(Header header, const PathResponsePayload& response,
                                 const Key& key, std::span<std::uint8_t> out);

/// Decoders check everything peek_header checks, the type, and the tag (compared in constant
/// time). `header` and the payload are written only on success. Sequence numbers are not checked
/// here: replay protection belongs to the receiver, which knows the last accepted sequence.
DecodeError decode_state(std::span<const std::uint8_t> datagram, const Key& key, Header& header,
                         StatePayload& state);
DecodeError decode_heartbeat(std::span<const std::uint8_t> datagram, const Key& key,
                             Header& header, HeartbeatPayload& heartbeat);
DecodeError decode_path_challenge(std::span<const std::uint8_t> datagram, const Key& key,
                                  Header& header, PathChallengePayload& challenge);
DecodeError decode_path_response(std::span<const std::uint8_t> datagram, const Key& key,
                                 Header& header, PathResponsePayload& response);

}  // namespace haptic::wire
