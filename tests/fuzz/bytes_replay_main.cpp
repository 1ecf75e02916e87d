// Deterministic driver for a byte-input fuzz entry point, so ctest runs it on every build without
// libFuzzer: every file of the corpus folders as it is, then `count` seeded mutations of them
// (bit flips, byte overwrites with interesting values, insertions, deletions, duplicated runs,
// splices of two inputs, truncation), each handed to LLVMFuzzerTestOneInput. A crash, a sanitizer
// report or a hang is the failure; the entry point checks its own invariants.
// Usage: <binary> COUNT DIR...   |   <binary> --seeds DIR (writes the target's own seeds there)
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "fuzz/fuzz_seeds.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

using Input = std::vector<std::uint8_t>;

std::vector<Input> read_corpus(const std::vector<std::string>& folders) {
  std::vector<Input> corpus;
  for (const std::string& folder : folders) {
    if (!std::filesystem::is_directory(folder)) continue;
    std::vector<std::filesystem::path> files;
    for (const auto& entry : std::filesystem::directory_iterator(folder)) {
      if (entry.is_regular_file()) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());  // the same order everywhere, so runs repeat
    for (const auto& file : files) {
      std::ifstream in(file, std::ios::binary);
      corpus.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
  }
  return corpus;
}

class Mutator {
 public:
  explicit Mutator(std::uint64_t seed) : random_(seed) {}

  Input mutate(const std::vector<Input>& corpus) {
    Input input = corpus.empty() ? Input{} : corpus[below(corpus.size())];
    const std::size_t rounds = 1 + below(4);
    for (std::size_t round = 0; round < rounds; ++round) apply(input, corpus);
    return input;
  }

 private:
  std::size_t below(std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(random_() % n); }

  void apply(Input& input, const std::vector<Input>& corpus) {
    static constexpr std::uint8_t kInteresting[] = {0, 1, 0x7f, 0x80, 0xff, '"', '{', '}', '[', ']',
                                                    ',', ':', '-', '.', 'e', '0', '9'};
    switch (below(8)) {
      case 0:  // flip a bit
        if (!input.empty()) input[below(input.size())] ^= static_cast<std::uint8_t>(1u << below(8));
        break;
      case 1:  // overwrite a byte with an interesting one
        if (!input.empty()) input[below(input.size())] = kInteresting[below(std::size(kInteresting))];
        break;
      case 2: {  // insert random bytes
        const std::size_t at = below(input.size() + 1);
        const std::size_t n = 1 + below(8);
        for (std::size_t i = 0; i < n; ++i) {
          input.insert(input.begin() + static_cast<std::ptrdiff_t>(at), static_cast<std::uint8_t>(random_()));
        }
        break;
      }
      case 3:  // delete a run
        if (!input.empty()) {
          const std::size_t at = below(input.size());
          const std::size_t n = 1 + below(std::min<std::size_t>(16, input.size() - at));
          input.erase(input.begin() + static_cast<std::ptrdiff_t>(at),
                      input.begin() + static_cast<std::ptrdiff_t>(at + n));
        }
        break;
      case 4:  // duplicate a run
        if (!input.empty() && input.size() < 1 << 16) {
          const std::size_t at = below(input.size());
          const std::size_t n = 1 + below(std::min<std::size_t>(64, input.size() - at));
          const Input run(input.begin() + static_cast<std::ptrdiff_t>(at),
                          input.begin() + static_cast<std::ptrdiff_t>(at + n));
          input.insert(input.begin() + static_cast<std::ptrdiff_t>(below(input.size() + 1)), run.begin(), run.end());
        }
        break;
      case 5:  // splice: this input's head, another's tail
        if (!corpus.empty()) {
          const Input& other = corpus[below(corpus.size())];
          input.resize(below(input.size() + 1));
          const std::size_t from = below(other.size() + 1);
          input.insert(input.end(), other.begin() + static_cast<std::ptrdiff_t>(from), other.end());
        }
        break;
      case 6:  // truncate
        input.resize(below(input.size() + 1));
        break;
      default:  // a random byte anywhere
        if (!input.empty()) input[below(input.size())] = static_cast<std::uint8_t>(random_());
        break;
    }
  }

  std::mt19937_64 random_;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--seeds") {
    std::filesystem::create_directories(argv[2]);
    int index = 0;
    for (const std::string& seed : haptic::fuzz::seeds()) {
      std::ofstream(std::filesystem::path(argv[2]) / ("seed-" + std::to_string(index++)), std::ios::binary) << seed;
    }
    std::printf("%d seeds written to %s\n", index, argv[2]);
    return 0;
  }
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s COUNT DIR...  |  %s --seeds DIR\n", argv[0], argv[0]);
    return 2;
  }
  const long count = std::stol(argv[1]);
  std::vector<Input> corpus = read_corpus(std::vector<std::string>(argv + 2, argv + argc));
  for (const std::string& seed : haptic::fuzz::seeds()) corpus.emplace_back(seed.begin(), seed.end());
  for (const Input& input : corpus) LLVMFuzzerTestOneInput(input.data(), input.size());
  Mutator mutator(0x6861707469636475ull);
  for (long i = 0; i < count; ++i) {
    const Input input = mutator.mutate(corpus);
    LLVMFuzzerTestOneInput(input.data(), input.size());
  }
  std::printf("%zu corpus inputs and %ld mutations, no crash\n", corpus.size(), count);
  return 0;
}
