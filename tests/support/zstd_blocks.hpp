#pragma once
// Where each compressed block of a zstd frame ends, for the tests that cut a recording at a
// block's end or inside one (the run recorder's unit test, the cut-short replay test).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace haptic::test {

/// Where each block of the zstd frame in `bytes` ends (RFC 8878: the frame header, then blocks of
/// a 3-byte header and their content; the 4-byte checksum after the last).
inline std::vector<std::size_t> zstd_block_ends(const std::string& bytes) {
  const auto byte = [&](std::size_t at) { return static_cast<unsigned char>(bytes.at(at)); };
  const unsigned descriptor = byte(4);
  const unsigned content_size_flag = descriptor >> 6;
  const bool single_segment = ((descriptor >> 5) & 1) != 0;
  const std::size_t dictionary_bytes[] = {0, 1, 2, 4};
  std::size_t at = 5 + (single_segment ? 0 : 1) + dictionary_bytes[descriptor & 3] +
                   (content_size_flag == 0 ? (single_segment ? 1 : 0) : std::size_t{1} << content_size_flag);
  std::vector<std::size_t> ends;
  while (at + 3 <= bytes.size()) {
    const std::uint32_t header = byte(at) | byte(at + 1) << 8 | byte(at + 2) << 16;
    at += 3 + (((header >> 1) & 3) == 1 ? 1 : header >> 3);  // an RLE block holds one byte
    ends.push_back(at);
    if ((header & 1) != 0) break;  // the last block
  }
  return ends;
}

}  // namespace haptic::test
