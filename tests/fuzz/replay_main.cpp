// Deterministic driver for a fuzz entry point: seeded random inputs and mutations of valid
// datagrams (bit flips, truncation, extension, re-signed valid bodies). Usage: <binary> [count].
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "haptic/wire/datagram.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
  using namespace haptic::wire;
  const long count = argc > 1 ? std::strtol(argv[1], nullptr, 10) : 100000;
  std::mt19937_64 random(0x5eed);
  const Key key{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};

  std::vector<std::uint8_t> state(kStateDatagramSize), heartbeat(kHeartbeatDatagramSize);
  Header header;
  header.session_id = 99;
  header.sequence = 1;
  encode_state(header, StatePayload{}, key, state);
  encode_heartbeat(header, HeartbeatPayload{}, key, heartbeat);

  for (long i = 0; i < count; ++i) {
    std::vector<std::uint8_t> input;
    switch (random() % 4) {
      case 0: {  // random bytes of random length
        input.resize(random() % 256);
        for (auto& b : input) b = static_cast<std::uint8_t>(random());
        break;
      }
      case 1:  // bit flips of a valid datagram
        input = (random() & 1) ? state : heartbeat;
        for (int flips = 1 + static_cast<int>(random() % 4); flips > 0; --flips) {
          input[random() % input.size()] ^= static_cast<std::uint8_t>(1u << (random() % 8));
        }
        break;
      case 2:  // truncated or extended
        input = (random() & 1) ? state : heartbeat;
        input.resize(random() % (input.size() * 2));
        break;
      default: {  // valid datagrams with random contents (exercise the round trip)
        StatePayload payload;
        payload.tick = random();
        payload.p_WT = {static_cast<double>(random()), -1.0, 0.5};
        payload.flags = static_cast<std::uint32_t>(random());
        Header h;
        h.session_id = random();
        h.sequence = random();
        h.time_ns = static_cast<std::int64_t>(random());
        input.resize(kStateDatagramSize);
        encode_state(h, payload, key, input);
        break;
      }
    }
    LLVMFuzzerTestOneInput(input.data(), input.size());
  }
  std::printf("datagram fuzz replay: %ld inputs, no failure\n", count);
  return 0;
}
