#include "haptic/wire/datagram.hpp"

#include <bit>

#include "haptic/wire/siphash.hpp"

namespace haptic::wire {
namespace {

// Little-endian writer and reader over a fixed buffer, one byte at a time so the result does not
// depend on the host's byte order or on struct padding. Callers check the size before using them.
class Writer {
 public:
  explicit Writer(std::uint8_t* out) : out_(out) {}
  void u16(std::uint16_t v) { put(v, 2); }
  void u32(std::uint32_t v) { put(v, 4); }
  void u64(std::uint64_t v) { put(v, 8); }
  void i64(std::int64_t v) { put(static_cast<std::uint64_t>(v), 8); }
  // The bit pattern, so NaN payloads, infinities and -0.0 cross unchanged.
  void f64(double v) { put(std::bit_cast<std::uint64_t>(v), 8); }
  void vec(const Vec3d& v) {
    f64(v.x);
    f64(v.y);
    f64(v.z);
  }
  std::size_t written() const { return offset_; }

 private:
  void put(std::uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) out_[offset_++] = static_cast<std::uint8_t>(v >> (8 * i));
  }
  std::uint8_t* out_;
  std::size_t offset_ = 0;
};

class Reader {
 public:
  explicit Reader(const std::uint8_t* in) : in_(in) {}
  std::uint16_t u16() { return static_cast<std::uint16_t>(get(2)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(get(4)); }
  std::uint64_t u64() { return get(8); }
  std::int64_t i64() { return static_cast<std::int64_t>(get(8)); }
  double f64() { return std::bit_cast<double>(get(8)); }
  Vec3d vec() {
    Vec3d v;
    v.x = f64();
    v.y = f64();
    v.z = f64();
    return v;
  }

 private:
  std::uint64_t get(int bytes) {
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= static_cast<std::uint64_t>(in_[offset_++]) << (8 * i);
    return v;
  }
  const std::uint8_t* in_;
  std::size_t offset_ = 0;
};

// 0 for a value that is not a DatagramType (the enum has a fixed underlying type, so the cast of
// any u16 is defined).
std::size_t payload_size_of(std::uint16_t type) {
  switch (static_cast<DatagramType>(type)) {
    case DatagramType::kState: return kStatePayloadSize;
    case DatagramType::kStateOriented: return kStateOrientedPayloadSize;
    case DatagramType::kHeartbeat: return kHeartbeatPayloadSize;
    case DatagramType::kPathChallenge:
    case DatagramType::kPathResponse: return kPathPayloadSize;
  }
  return 0;
}

void write_header(Writer& w, const Header& header, std::size_t payload_size) {
  w.u32(kMagic);
  w.u16(kWireVersion);
  w.u16(static_cast<std::uint16_t>(header.type));
  w.u64(header.session_id);
  w.u64(header.sequence);
  w.i64(header.time_ns);
  w.u32(static_cast<std::uint32_t>(payload_size));
  w.u32(0);  // reserved
}

void append_tag(std::span<std::uint8_t> out, std::size_t body_size, const Key& key) {
  const std::uint64_t tag = siphash24(key, out.first(body_size));
  Writer w(out.data() + body_size);
  w.u64(tag);
}

// One XOR of the whole 64-bit tag and one test: no early exit, so the time taken does not tell a
// forger how many leading bytes of a guess were right.
bool tag_matches(std::span<const std::uint8_t> datagram, const Key& key) {
  const std::size_t body = datagram.size() - kTagSize;
  const std::uint64_t expected = siphash24(key, datagram.first(body));
  const std::uint64_t received = Reader(datagram.data() + body).u64();
  return (expected ^ received) == 0;
}

DecodeError check_typed(std::span<const std::uint8_t> datagram, const Key& key, DatagramType type,
                        Header& header) {
  if (const DecodeError e = peek_header(datagram, header); e != DecodeError::kNone) return e;
  if (header.type != type) return DecodeError::kUnknownType;
  if (!tag_matches(datagram, key)) return DecodeError::kBadTag;
  return DecodeError::kNone;
}

/// Writes a datagram of `type`: header, the payload `write` puts, tag. 0 if `out` is too small.
template <typename Write>
std::size_t encode_as(Header header, DatagramType type, std::size_t payload_size, const Key& key,
                      std::span<std::uint8_t> out, Write write) {
  const std::size_t size = kHeaderSize + payload_size + kTagSize;
  if (out.size() < size) return 0;
  header.type = type;
  Writer w(out.data());
  write_header(w, header, payload_size);
  write(w);
  append_tag(out, w.written(), key);
  return size;
}

/// Checks a datagram of `type` (check_typed proves its exact size) and reads its payload with
/// `read`; the outputs are written only on success.
template <typename Payload, typename Read>
DecodeError decode_as(std::span<const std::uint8_t> datagram, const Key& key, DatagramType type,
                      Header& header, Payload& payload, Read read) {
  Header parsed;
  if (const DecodeError e = check_typed(datagram, key, type, parsed); e != DecodeError::kNone) {
    return e;
  }
  Reader r(datagram.data() + kHeaderSize);
  payload = read(r);
  header = parsed;
  return DecodeError::kNone;
}

}  // namespace

const char* to_string(DecodeError error) {
  switch (error) {
    case DecodeError::kNone: return "none";
    case DecodeError::kTooShort: return "too short";
    case DecodeError::kBadMagic: return "bad magic";
    case DecodeError::kBadVersion: return "bad version";
    case DecodeError::kUnknownType: return "unknown type";
    case DecodeError::kBadPayloadSize: return "bad payload size";
    case DecodeError::kBadTag: return "bad tag";
  }
  return "invalid error";
}

DecodeError peek_header(std::span<const std::uint8_t> datagram, Header& header) {
  // From here on the 40 header bytes exist; nothing below reads past them.
  if (datagram.size() < kHeaderSize + kTagSize) return DecodeError::kTooShort;
  Reader r(datagram.data());
  if (r.u32() != kMagic) return DecodeError::kBadMagic;
  if (r.u16() != kWireVersion) return DecodeError::kBadVersion;
  const std::uint16_t type = r.u16();
  const std::size_t expected_payload = payload_size_of(type);
  if (expected_payload == 0) return DecodeError::kUnknownType;
  Header parsed;
  parsed.type = static_cast<DatagramType>(type);
  parsed.session_id = r.u64();
  parsed.sequence = r.u64();
  parsed.time_ns = r.i64();
  const std::uint32_t payload_size = r.u32();
  const std::uint32_t reserved = r.u32();
  // Exact length: trailing bytes would be unauthenticated if the tag were taken from the end, or
  // ignored if it were not; either way the sender and receiver disagree, so drop the datagram.
  if (payload_size != expected_payload || reserved != 0 ||
      datagram.size() != kHeaderSize + expected_payload + kTagSize) {
    return DecodeError::kBadPayloadSize;
  }
  header = parsed;
  return DecodeError::kNone;
}

std::size_t encode_state(Header header, const StatePayload& state, const Key& key,
                         std::span<std::uint8_t> out) {
  const DatagramType type = state.has_orientation ? DatagramType::kStateOriented : DatagramType::kState;
  const std::size_t size = state.has_orientation ? kStateOrientedPayloadSize : kStatePayloadSize;
  return encode_as(header, type, size, key, out, [&](Writer& w) {
    w.u64(state.tick);
    w.vec(state.p_WT);
    w.vec(state.v_WT);
    w.vec(state.F_T_W);
    w.vec(state.p_WP);
    w.u32(state.contact_count);
    w.u32(state.flags);
    w.u32(state.buttons);
    if (state.has_orientation) {
      w.f64(state.R_WT.w);
      w.f64(state.R_WT.x);
      w.f64(state.R_WT.y);
      w.f64(state.R_WT.z);
      w.vec(state.tau_T_W);
    }
  });
}

std::size_t encode_heartbeat(Header header, const HeartbeatPayload& heartbeat, const Key& key,
                             std::span<std::uint8_t> out) {
  return encode_as(header, DatagramType::kHeartbeat, kHeartbeatPayloadSize, key, out, [&](Writer& w) {
    w.i64(heartbeat.client_time_ns);
    w.u64(heartbeat.last_state_sequence);
    w.u64(heartbeat.states_received);
    w.u64(heartbeat.states_lost);
    w.i64(heartbeat.echo_state_time_ns);
    w.i64(heartbeat.echo_hold_ns);
  });
}

std::size_t encode_path_challenge(Header header, const PathChallengePayload& challenge,
                                  const Key& key, std::span<std::uint8_t> out) {
  return encode_as(header, DatagramType::kPathChallenge, kPathPayloadSize, key, out, [&](Writer& w) {
    w.u64(challenge.nonce);
    w.u64(challenge.heartbeat_sequence);
  });
}

std::size_t encode_path_response(Header header, const PathResponsePayload& response,
                                 const Key& key, std::span<std::uint8_t> out) {
  return encode_as(header, DatagramType::kPathResponse, kPathPayloadSize, key, out, [&](Writer& w) {
    w.u64(response.nonce);
    w.i64(response.client_time_ns);
  });
}

DecodeError decode_state(std::span<const std::uint8_t> datagram, const Key& key, Header& header,
                         StatePayload& state) {
  // Either state type: the header says which (and peek_header has checked its exact length).
  Header peeked;
  const DatagramType type =
      peek_header(datagram, peeked) == DecodeError::kNone && peeked.type == DatagramType::kStateOriented
          ? DatagramType::kStateOriented
          : DatagramType::kState;
  return decode_as(datagram, key, type, header, state, [type](Reader& r) {
    StatePayload decoded;
    decoded.tick = r.u64();
    decoded.p_WT = r.vec();
    decoded.v_WT = r.vec();
    decoded.F_T_W = r.vec();
    decoded.p_WP = r.vec();
    decoded.contact_count = r.u32();
    decoded.flags = r.u32();
    decoded.buttons = r.u32();
    if (type == DatagramType::kStateOriented) {
      decoded.has_orientation = true;
      decoded.R_WT.w = r.f64();
      decoded.R_WT.x = r.f64();
      decoded.R_WT.y = r.f64();
      decoded.R_WT.z = r.f64();
      decoded.tau_T_W = r.vec();
    }
    return decoded;
  });
}

DecodeError decode_heartbeat(std::span<const std::uint8_t> datagram, const Key& key,
                             Header& header, HeartbeatPayload& heartbeat) {
  return decode_as(datagram, key, DatagramType::kHeartbeat, header, heartbeat, [](Reader& r) {
    HeartbeatPayload decoded;
    decoded.client_time_ns = r.i64();
    decoded.last_state_sequence = r.u64();
    decoded.states_received = r.u64();
    decoded.states_lost = r.u64();
    decoded.echo_state_time_ns = r.i64();
    decoded.echo_hold_ns = r.i64();
    return decoded;
  });
}

DecodeError decode_path_challenge(std::span<const std::uint8_t> datagram, const Key& key,
                                  Header& header, PathChallengePayload& challenge) {
  return decode_as(datagram, key, DatagramType::kPathChallenge, header, challenge, [](Reader& r) {
    PathChallengePayload decoded;
    decoded.nonce = r.u64();
    decoded.heartbeat_sequence = r.u64();
    return decoded;
  });
}

DecodeError decode_path_response(std::span<const std::uint8_t> datagram, const Key& key,
                                 Header& header, PathResponsePayload& response) {
  return decode_as(datagram, key, DatagramType::kPathResponse, header, response, [](Reader& r) {
    PathResponsePayload decoded;
    decoded.nonce = r.u64();
    decoded.client_time_ns = r.i64();
    return decoded;
  });
}

}  // namespace haptic::wire
