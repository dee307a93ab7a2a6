// minkq_sort_study: the CPU build's key sort (core/src/cpu/radix_sort.cpp's radix_sort_pairs,
// called in libminkq.so) on synthetic 63-bit keys, where the build study's real meshes cannot
// reach: keys in runs of L that share their top 24 bits (L = 1: every key its own cell, as
// Morton codes of a surface give; L = 8 to 1000: clustered points), each run's low 39 bits
// random, at sizes sorted on one thread and in parallel. Run two builds of the library against
// it (LD_LIBRARY_PATH) to compare sorts.
//
//   minkq_sort_study [--threads N] [--repeats N] [--out FILE]   (defaults: 2, 31, stdout only)
#include <tbb/global_control.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "common.h"
#include "cpu/radix_sort.h"

using namespace minkq;
using namespace minkq::bench;

int main(int argc, char** argv) {
  int threads = 2, repeats = 31;
  std::string out;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--threads" && i + 1 < argc) threads = std::atoi(argv[++i]);
    else if (a == "--repeats" && i + 1 < argc) repeats = std::atoi(argv[++i]);
    else if (a == "--out" && i + 1 < argc) out = argv[++i];
    else {
      std::fprintf(stderr, "usage: minkq_sort_study [--threads N] [--repeats N] [--out FILE]\n");
      return 2;
    }
  }
  tbb::global_control control(tbb::global_control::max_allowed_parallelism, size_t(std::max(1, threads)));
  const double load_start = load_average();
  std::ostringstream o;
  o << "# The CPU key sort on clustered keys\n\nWritten by `minkq_sort_study` (bench/sort_study.cpp). Machine: "
    << machine_line("cpu") << "; " << threads << " TBB threads. 63-bit keys in runs of L keys sharing their top 24 "
    << "bits (the runs' cells spread by a multiplicative hash), low 39 bits random; values 0..n-1; ms = median "
    << "(range) of " << repeats << " sorts of a fresh copy, after 2 untimed.\n\n| keys | run length L | ms |\n|---|---|---|\n";
  std::mt19937_64 rng(27);
  for (const int64_t n : {5000, 15000, 100000}) {
    for (const int64_t run : {1, 8, 33, 100, 1000}) {
      HostVector<uint64_t> keys(static_cast<size_t>(n)), sorted_keys;
      HostVector<int32_t> values;
      for (int64_t i = 0; i < n; ++i) {
        const uint64_t cell = (uint64_t(i / run) * 0x9e3779b97f4a7c15ull) >> 40;  // 24 bits
        keys[size_t(i)] = cell << 39 | (rng() & ((uint64_t(1) << 39) - 1));
      }
      RadixScratch scratch;
      const Timing t = measure(
          2, repeats, [&] { radix_sort_pairs(sorted_keys, values, 63, scratch); },
          [&] {
            sorted_keys = keys;
            values.resize(size_t(n));
            for (int64_t i = 0; i < n; ++i) values[size_t(i)] = int32_t(i);
          });
      for (int64_t i = 1; i < n; ++i)
        if (sorted_keys[size_t(i - 1)] > sorted_keys[size_t(i)]) {
          std::fprintf(stderr, "minkq_sort_study: keys out of order at %lld\n", static_cast<long long>(i));
          return 1;
        }
      o << "| " << n << " | " << run << " | " << t.text() << " |\n";
    }
  }
  o << "\nLoad average (1 min) at start " << fmt(load_start, 3) << ", at end " << fmt(load_average(), 3) << ".\n";
  std::fputs(o.str().c_str(), stdout);
  if (!out.empty()) std::ofstream(out) << o.str();
  return 0;
}
