// Deterministic driver for a fuzz entry point, so ctest runs it on every build without libFuzzer:
// seeded random inputs and mutations of valid datagrams (bit flips, byte overwrites, truncation,
// extension, valid datagrams with random field bits, re-signed random payloads).
// Usage: <binary> [count]   |   <binary> --seeds DIR (one valid datagram per type, for libFuzzer)
#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "haptic/wire/datagram.hpp"
#include "haptic/wire/siphash.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

using namespace haptic::wire;

// The key the entry point decodes with.
constexpr Key kKey{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};

class Generator {
 public:
  explicit Generator(std::uint64_t seed) : random_(seed) {}

  std::uint64_t bits() { return random_(); }
  std::size_t below(std::size_t n) { return static_cast<std::size_t>(random_() % n); }
  // Any bit pattern, so NaN payloads, subnormals and infinities all occur.
  double any_double() { return std::bit_cast<double>(random_()); }
  Vec3d any_vec() { return {any_double(), any_double(), any_double()}; }

  Header any_header() {
    Header h;
    h.session_id = bits();
    h.sequence = bits();
    h.time_ns = static_cast<std::int64_t>(bits());
    return h;
  }

  /// oriented: 0 State, 1 StateOriented, -1 either at random.
  std::vector<std::uint8_t> valid_state(int oriented = -1) {
    StatePayload s;
    s.tick = bits();
    s.p_WT = any_vec();
    s.v_WT = any_vec();
    s.F_T_W = any_vec();
    s.p_WP = any_vec();
    s.contact_count = static_cast<std::uint32_t>(bits());
    s.flags = static_cast<std::uint32_t>(bits());
    s.buttons = static_cast<std::uint32_t>(bits());
    s.has_orientation = oriented < 0 ? (bits() & 1) != 0 : oriented == 1;
    if (s.has_orientation) {
      s.R_WT = {any_double(), any_double(), any_double(), any_double()};
      s.tau_T_W = any_vec();
    }
    std::vector<std::uint8_t> out(s.has_orientation ? kStateOrientedDatagramSize : kStateDatagramSize);
    encode_state(any_header(), s, kKey, out);
    return out;
  }

  std::vector<std::uint8_t> valid_heartbeat() {
    HeartbeatPayload hb{static_cast<std::int64_t>(bits()), bits()};
    std::vector<std::uint8_t> out(kHeartbeatDatagramSize);
    encode_heartbeat(any_header(), hb, kKey, out);
    return out;
  }

  std::vector<std::uint8_t> valid_path() {
    std::vector<std::uint8_t> out(kPathDatagramSize);
    if (bits() & 1) {
      encode_path_challenge(any_header(), {bits(), bits()}, kKey, out);
    } else {
      encode_path_response(any_header(), {bits(), static_cast<std::int64_t>(bits())}, kKey, out);
    }
    return out;
  }

  std::vector<std::uint8_t> valid_any() {
    switch (below(3)) {
      case 0: return valid_state();
      case 1: return valid_heartbeat();
      default: return valid_path();
    }
  }

 private:
  std::mt19937_64 random_;
};

void resign(std::vector<std::uint8_t>& bytes) {
  if (bytes.size() < kTagSize) return;
  const std::size_t body = bytes.size() - kTagSize;
  const std::uint64_t tag = siphash24(kKey, std::span(bytes).first(body));
  for (std::size_t i = 0; i < kTagSize; ++i) bytes[body + i] = static_cast<std::uint8_t>(tag >> (8 * i));
}

}  // namespace

/// Writes one valid datagram of each type into `dir` (a seed corpus for the libFuzzer binary).
int write_seeds(const std::string& dir) {
  Generator g(0x5eed);
  const std::pair<const char*, std::vector<std::uint8_t>> seeds[] = {
      {"state", g.valid_state(0)}, {"state_oriented", g.valid_state(1)}, {"heartbeat", g.valid_heartbeat()}, {"path", g.valid_path()},
      {"path2", g.valid_path()}};
  for (const auto& [name, bytes] : seeds) {
    std::FILE* out = std::fopen((dir + "/" + name).c_str(), "wb");
    if (out == nullptr || std::fwrite(bytes.data(), 1, bytes.size(), out) != bytes.size()) {
      std::perror(name);
      return 1;
    }
    std::fclose(out);
  }
  return 0;
}

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--seeds") return write_seeds(argv[2]);
  const long count = argc > 1 ? std::strtol(argv[1], nullptr, 10) : 100000;
  Generator g(0x5eed);
  std::vector<std::uint8_t> input;
  input.reserve(2 * kMaxDatagramSize + 64);

  for (long i = 0; i < count; ++i) {
    switch (g.below(7)) {
      case 0: {  // random bytes of random length
        input.resize(g.below(2 * kMaxDatagramSize));
        for (auto& b : input) b = static_cast<std::uint8_t>(g.bits());
        break;
      }
      case 1:  // bit flips of a valid datagram
        input = g.valid_any();
        for (std::size_t flips = 1 + g.below(4); flips > 0; --flips) {
          input[g.below(input.size())] ^= static_cast<std::uint8_t>(1u << g.below(8));
        }
        break;
      case 2:  // random bytes overwritten in a valid datagram
        input = g.valid_any();
        for (std::size_t n = 1 + g.below(4); n > 0; --n) {
          input[g.below(input.size())] = static_cast<std::uint8_t>(g.bits());
        }
        break;
      case 3:  // truncated
        input = g.valid_any();
        input.resize(g.below(input.size()));
        break;
      case 4: {  // extended with zero or random bytes
        input = g.valid_any();
        const bool zeros = g.bits() & 1;
        for (std::size_t n = 1 + g.below(kMaxDatagramSize); n > 0; --n) {
          input.push_back(zeros ? 0 : static_cast<std::uint8_t>(g.bits()));
        }
        break;
      }
      case 5:  // valid datagrams with random contents (exercise the round trip)
        input = g.valid_any();
        break;
      default:  // random payload or header bytes, then a correct tag: only the fields can fail
        input = g.valid_any();
        for (std::size_t n = 1 + g.below(8); n > 0; --n) {
          input[g.below(input.size() - kTagSize)] = static_cast<std::uint8_t>(g.bits());
        }
        resign(input);
        break;
    }
    LLVMFuzzerTestOneInput(input.data(), input.size());
  }
  std::printf("datagram fuzz replay: %ld inputs, no failure\n", count);
  return 0;
}
