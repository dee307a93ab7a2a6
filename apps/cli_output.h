// What `minkq query` (minkq_cli.cpp) runs and writes: the kinds of `--kind`, the pair formats of
// `--format` (text, csv, npy, bin) to files or to stdout (`--out -`), and the progress line it
// shows on stderr when stderr is a terminal.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "cli_common.h"
#include "minkq.h"

namespace minkq::cli {

// ---- --kind ----------------------------------------------------------------------------------
struct Kind {
  minkq_query_kind kind;
  const char* name;  // as in --kind and the output: vt, ee, vv, ev
  uint32_t scene_flag;
  const char* pair;  // what its pairs are, for text output
};
inline const std::vector<Kind>& all_kinds() {
  static const std::vector<Kind> kinds{
      {MINKQ_QUERY_VT, "vt", MINKQ_SCENE_VT, "(vertex, triangle)"},
      {MINKQ_QUERY_EE, "ee", MINKQ_SCENE_EE, "(edge, edge), first < second"},
      {MINKQ_QUERY_VV, "vv", MINKQ_SCENE_VV, "(vertex, vertex), first < second"},
      {MINKQ_QUERY_EV, "ev", MINKQ_SCENE_EV, "(vertex, edge)"},
  };
  return kinds;
}

// The kinds of a comma-separated `--kind` list, in the order given; `swept` queries have VT and EE
// only.
inline std::vector<Kind> parse_kinds(const std::string& list, bool swept) {
  std::vector<Kind> kinds;
  for (size_t at = 0; at <= list.size();) {
    const size_t comma = std::min(list.find(',', at), list.size());
    const std::string word = list.substr(at, comma - at);
    at = comma + 1;
    const Kind* found = nullptr;
    for (const Kind& k : all_kinds())
      if (word == k.name) found = &k;
    if (!found) throw UsageError("--kind: unknown kind '" + word + "' (vt, ee, vv, ev, comma-separated)");
    for (const Kind& k : kinds)
      if (k.kind == found->kind) throw UsageError("--kind: '" + word + "' given twice");
    if (swept && found->kind != MINKQ_QUERY_VT && found->kind != MINKQ_QUERY_EE)
      throw UsageError("--kind " + word + ": swept queries (--to) run vt and ee only");
    kinds.push_back(*found);
  }
  return kinds;
}

// ---- --format and --out ----------------------------------------------------------------------
enum class Format { text, csv, npy, bin };

inline Format parse_format(const std::string& word) {
  if (word == "text") return Format::text;
  if (word == "csv") return Format::csv;
  if (word == "npy") return Format::npy;
  if (word == "bin") return Format::bin;
  throw UsageError("--format: unknown format '" + word + "' (text, csv, npy, bin)");
}
inline const char* extension(Format f) {
  return f == Format::text ? "txt" : f == Format::csv ? "csv" : f == Format::npy ? "npy" : "bin";
}
// Binary formats hold one array: to stdout, one kind only.
inline bool one_array_per_stream(Format f) { return f == Format::npy || f == Format::bin; }

// `count` pairs (2 int32 each) in `format`, appended to `bytes`. text: a comment line naming the
// kind, then "a b" per line; csv: "kind,first,second" per line (the header is csv_header());
// npy: a NumPy 1.0 file of an int32 array of shape (count, 2); bin: the raw little-endian pairs.
inline void append_little_endian(std::string& bytes, const int32_t* pairs, uint64_t count) {
  for (uint64_t i = 0; i < 2 * count; ++i)
    for (int b = 0; b < 4; ++b) bytes.push_back(char(uint8_t(uint32_t(pairs[i]) >> (8 * b))));
}
inline const char* csv_header() { return "kind,first,second\n"; }
inline void append_pairs(std::string& bytes, Format format, const Kind& kind, const int32_t* pairs, uint64_t count) {
  switch (format) {
    case Format::text:
      bytes += "# " + std::string(kind.name) + ": " + std::to_string(count) + " pairs " + kind.pair + "\n";
      for (uint64_t i = 0; i < count; ++i)
        bytes += std::to_string(pairs[2 * i]) + " " + std::to_string(pairs[2 * i + 1]) + "\n";
      return;
    case Format::csv:
      for (uint64_t i = 0; i < count; ++i)
        bytes += std::string(kind.name) + "," + std::to_string(pairs[2 * i]) + "," + std::to_string(pairs[2 * i + 1]) + "\n";
      return;
    case Format::npy: {
      // The header's dict, padded with spaces and ended by '\n' so that the data starts at a
      // multiple of 64 bytes (the format's rule for version 1.0).
      std::string dict = "{'descr': '<i4', 'fortran_order': False, 'shape': (" + std::to_string(count) + ", 2), }";
      const size_t unpadded = 10 + dict.size() + 1;
      dict.append((64 - unpadded % 64) % 64, ' ');
      dict += '\n';
      bytes += std::string("\x93NUMPY\x01\x00", 8);
      bytes.push_back(char(dict.size() & 0xff));
      bytes.push_back(char(dict.size() >> 8));
      bytes += dict;
      append_little_endian(bytes, pairs, count);
      return;
    }
    case Format::bin:
      append_little_endian(bytes, pairs, count);
      return;
  }
}

// Writes `bytes` to `path`, or to stdout for "-"; a failed write is an error naming the path.
inline void write_bytes(const std::string& path, const std::string& bytes) {
  if (path == "-") {
    if (std::fwrite(bytes.data(), 1, bytes.size(), stdout) != bytes.size() || std::fflush(stdout) != 0)
      throw std::runtime_error("cannot write the pairs to stdout");
    return;
  }
  std::ofstream f(path, std::ios::binary);
  f.write(bytes.data(), std::streamsize(bytes.size()));
  if (!f) throw std::runtime_error("cannot write " + path);
}

// ---- Progress --------------------------------------------------------------------------------
// One line on stderr naming the step under way, rewritten at each step and erased at the end,
// when stderr is a terminal (nothing otherwise, so that logs and pipes stay clean).
class Progress {
 public:
  Progress() : on_(isatty(STDERR_FILENO) == 1) {}
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  ~Progress() { done(); }
  void step(const std::string& what) {
    if (!on_) return;
    std::fprintf(stderr, "\r\033[Kminkq: %s ...", what.c_str());
    std::fflush(stderr);
    shown_ = true;
  }
  void done() {
    if (!shown_) return;
    std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
    shown_ = false;
  }

 private:
  bool on_;
  bool shown_ = false;
};

}  // namespace minkq::cli
