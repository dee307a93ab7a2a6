// fuzz_campaign: the differential fuzzer's checks (fuzz_differential.cpp) as a fixed-size
// campaign, without libFuzzer: for the GPU machine, which has no clang, and where the CUDA
// backend is built in, so every scene is also run on each CUDA device and checked equal to
// the CPU's sets (scene_checks.h). Runs LLVMFuzzerInitialize, then every file of the corpus
// folders given, then --inputs random byte strings (lengths 1 to --max-len, from --seed);
// a mismatch prints the scene as C++ and aborts (status 134), as under libFuzzer.
//
//   fuzz_campaign [--inputs N] [--seed S] [--max-len L] [CORPUS_DIR ...]
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv);
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int main(int argc, char** argv) {
  uint64_t inputs = 1000, seed = std::random_device{}();
  size_t max_len = 4096;
  std::vector<std::string> corpora;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "fuzz_campaign: %s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--inputs") inputs = std::strtoull(value(), nullptr, 10);
    else if (arg == "--seed") seed = std::strtoull(value(), nullptr, 10);
    else if (arg == "--max-len") max_len = std::strtoull(value(), nullptr, 10);
    else if (!arg.empty() && arg[0] == '-') {
      std::fprintf(stderr, "usage: fuzz_campaign [--inputs N] [--seed S] [--max-len L] [CORPUS_DIR ...]\n");
      return 2;
    } else corpora.push_back(arg);
  }
  if (max_len == 0) max_len = 1;
  LLVMFuzzerInitialize(&argc, &argv);
  uint64_t replayed = 0;
  for (const std::string& dir : corpora) {
    if (!std::filesystem::is_directory(dir)) {
      std::fprintf(stderr, "fuzz_campaign: %s is not a folder\n", dir.c_str());
      return 2;
    }
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      if (!entry.is_regular_file()) continue;
      std::ifstream file(entry.path(), std::ios::binary);
      const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
      LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
      ++replayed;
    }
  }
  std::fprintf(stderr, "fuzz_campaign: %llu corpus inputs replayed; %llu random inputs from seed %llu\n",
               (unsigned long long)replayed, (unsigned long long)inputs, (unsigned long long)seed);
  std::mt19937_64 random(seed);
  std::vector<uint8_t> bytes;
  for (uint64_t n = 0; n < inputs; ++n) {
    bytes.resize(1 + size_t(random() % max_len));
    for (uint8_t& b : bytes) b = uint8_t(random());
    LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
  }
  return 0;  // the harness prints its totals at exit
}
