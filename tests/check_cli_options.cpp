// Checks the options of `minkq query` and the usage of `minkq` as a Unix program, on a real mesh:
//   check_cli_options MINKQ_BINARY MESH WORK_DIR
// - --help for the program and for each command: exit 0, the usage on stdout, nothing on stderr;
//   an unknown option (with or without a value after it, with one dash or two): exit 2 and a
//   message naming it;
// - --format text, csv and npy (to files and to stdout with --out -) hold exactly the pairs of
//   --format bin, for VT and EE; a .npy file's header is NumPy's 1.0 format for int32 (N, 2);
//   with --out - the digest lines go to stderr and stdout holds the pairs only; npy and bin to
//   stdout take one kind;
// - --kind: only the kinds asked for, in that order, each with the digest of the default run;
//   vv and ev give the pairs of the C API's own VV and EV queries of the mesh;
// - the mode words: --mode box --leaf-exact equals the old --mode leaf_exact, --mode
//   capsule_exact the old --mode sphere; the old words warn on stderr and the new ones print
//   nothing there (and no progress line, stderr not being a terminal).
#include <sys/wait.h>

#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "contact_checks.h"
#include "minkq.hpp"
#include "minkq_reference.h"

namespace {

using minkq::reference::Pairs;

std::string quoted(const std::string& s) { return "'" + s + "'"; }

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error("cannot read " + path);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

struct Run {
  int status;  // the exit status
  std::string out, err;
};

int failures = 0;
void expect(bool ok, const std::string& what) {
  if (!ok) {
    std::printf("FAIL: %s\n", what.c_str());
    ++failures;
  }
}

class Cli {
 public:
  Cli(std::string binary, std::string work) : binary_(std::move(binary)), work_(std::move(work)) {}
  Run operator()(const std::string& arguments) const {
    const std::string command = quoted(binary_) + " " + arguments + " >" + quoted(work_ + "/stdout") + " 2>" +
                                quoted(work_ + "/stderr") + " </dev/null";
    const int status = std::system(command.c_str());
    Run r{WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(work_ + "/stdout"), slurp(work_ + "/stderr")};
    std::printf("minkq %s: exit %d\n", arguments.c_str(), r.status);
    return r;
  }

 private:
  std::string binary_, work_;
};

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// The pairs of text output: "a b" lines after a "# KIND: ..." line; `kind` selects a block.
Pairs parse_text(const std::string& text, const std::string& kind) {
  std::istringstream in(text);
  std::string line, current;
  Pairs pairs;
  while (std::getline(in, line)) {
    if (line.rfind("# ", 0) == 0) {
      current = line.substr(2, line.find(':') - 2);
      continue;
    }
    int32_t a, b;
    char rest;
    if (std::sscanf(line.c_str(), "%" SCNd32 " %" SCNd32 " %c", &a, &b, &rest) != 2)
      throw std::runtime_error("text output: bad line '" + line + "'");
    if (current == kind) pairs.emplace_back(a, b);
  }
  return pairs;
}

// The pairs of csv output of one kind; the first line must be the header.
Pairs parse_csv(const std::string& text, const std::string& kind) {
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  if (line != "kind,first,second") throw std::runtime_error("csv output: header '" + line + "'");
  Pairs pairs;
  while (std::getline(in, line)) {
    const size_t c1 = line.find(','), c2 = line.find(',', c1 + 1);
    if (c1 == std::string::npos || c2 == std::string::npos) throw std::runtime_error("csv output: bad line " + line);
    if (line.substr(0, c1) == kind) pairs.emplace_back(std::stoi(line.substr(c1 + 1)), std::stoi(line.substr(c2 + 1)));
  }
  return pairs;
}

// A .npy file's pairs, its header checked against the NumPy format 1.0 for '<i4' (N, 2).
Pairs parse_npy(const std::string& bytes) {
  if (bytes.size() < 10 || bytes.compare(0, 8, std::string("\x93NUMPY\x01\x00", 8)) != 0)
    throw std::runtime_error("npy: bad magic or version");
  const size_t header = uint8_t(bytes[8]) | size_t(uint8_t(bytes[9])) << 8;
  if ((10 + header) % 64 != 0 || bytes.size() < 10 + header || bytes[10 + header - 1] != '\n')
    throw std::runtime_error("npy: the data does not start at a multiple of 64 after a '\\n'");
  const std::string dict = bytes.substr(10, header);
  unsigned long long n = 0;
  if (!contains(dict, "'descr': '<i4'") || !contains(dict, "'fortran_order': False") ||
      std::sscanf(dict.c_str() + dict.find("'shape': (") + 10, "%llu, 2)", &n) != 1)
    throw std::runtime_error("npy: header " + dict);
  if (bytes.size() != 10 + header + 8 * n) throw std::runtime_error("npy: the data is not " + std::to_string(n) + " pairs");
  Pairs pairs(n);
  for (size_t i = 0; i < n; ++i) {
    int32_t ab[2];
    std::memcpy(ab, bytes.data() + 10 + header + 8 * i, 8);  // little-endian int32, as the host
    pairs[i] = {ab[0], ab[1]};
  }
  return pairs;
}

// "KIND candidates N digest HEX" lines, in order.
std::vector<std::string> digest_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line))
    if (contains(line, " candidates ")) lines.push_back(line);
  return lines;
}

void check_help_and_unknown_options(const Cli& minkq, const std::string& mesh) {
  for (const char* args : {"--help", "query --help", "demo --help", "query -h", "query MESH --radius 1 --help"}) {
    const Run r = minkq(std::string(args) == "query MESH --radius 1 --help" ? "query " + quoted(mesh) + " --radius 1 --help"
                                                                               : args);
    expect(r.status == 0 && contains(r.out, "usage: minkq") && r.err.empty(), std::string(args) + ": usage on stdout, exit 0");
  }
  expect(contains(minkq("query --help").out, "--format F") && !contains(minkq("query --help").out, "demo ["),
         "query --help is the query command's usage");
  expect(contains(minkq("demo --help").out, "--size N"), "demo --help is the demo command's usage");
  for (const char* option : {"--bogus 1", "--bogus", "-x"}) {
    const Run r = minkq("query " + quoted(mesh) + " --radius 1 " + option);
    const std::string name = std::string(option).substr(0, std::string(option).find(' '));
    expect(r.status == 2 && contains(r.err, "unknown option " + name), std::string(option) + ": exit 2 naming the option");
  }
  const Run no_out = minkq("query " + quoted(mesh) + " --radius 1 --format csv");
  expect(no_out.status == 2 && contains(no_out.err, "--format needs --out"), "--format without --out is refused");
  const Run bad_format = minkq("query " + quoted(mesh) + " --radius 1 --out - --format xml");
  expect(bad_format.status == 2 && contains(bad_format.err, "unknown format 'xml'"), "--format xml is refused");
  const Run bad_kind = minkq("query " + quoted(mesh) + " --radius 1 --kind vt,tt");
  expect(bad_kind.status == 2 && contains(bad_kind.err, "unknown kind 'tt'"), "--kind tt is refused");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: check_cli_options MINKQ_BINARY MESH WORK_DIR\n");
    return 2;
  }
  try {
    const Cli minkq(argv[1], argv[3]);
    const std::string mesh = argv[2], work = argv[3];
    const std::string base = "query " + quoted(mesh) + " --radius-factor 1 --backend cpu ";
    check_help_and_unknown_options(minkq, mesh);

    // The reference: bin files of VT and EE in the default mode.
    const Run bin = minkq(base + "--out " + quoted(work + "/bin"));
    expect(bin.status == 0 && bin.err.empty(), "a plain run prints nothing on stderr (no terminal: no progress line)");
    const Pairs vt = minkq::test::read_pairs(work + "/bin.vt.bin"), ee = minkq::test::read_pairs(work + "/bin.ee.bin");
    expect(!vt.empty() && !ee.empty(), "the mesh has VT and EE pairs at this radius");
    const std::vector<std::string> digests = digest_lines(bin.out);
    expect(digests.size() == 2, "two digest lines by default");

    for (const char* format : {"text", "csv", "npy"}) {
      const std::string prefix = work + "/" + format;
      expect(minkq(base + "--out " + quoted(prefix) + " --format " + format).status == 0, std::string(format) + " files");
      const std::string ext = std::string(format) == "text" ? "txt" : format;
      for (const auto& [kind, truth] : {std::pair{"vt", &vt}, std::pair{"ee", &ee}}) {
        const std::string bytes = slurp(prefix + "." + kind + "." + ext);
        const Pairs got = ext == "txt" ? parse_text(bytes, kind) : ext == "csv" ? parse_csv(bytes, kind) : parse_npy(bytes);
        expect(got == *truth, std::string(format) + " " + kind + " file holds the bin file's pairs");
      }
    }
    const Run text = minkq(base + "--out - --format text");
    expect(text.status == 0 && parse_text(text.out, "vt") == vt && parse_text(text.out, "ee") == ee,
           "--out - --format text prints both kinds' pairs");
    expect(digest_lines(text.out).empty() && digest_lines(text.err) == digests, "--out -: digest lines on stderr");
    expect(minkq(base + "--out -").out == text.out, "--out - defaults to text");
    const Run csv = minkq(base + "--out - --format csv --kind ee,vt");
    expect(csv.status == 0 && parse_csv(csv.out, "vt") == vt && parse_csv(csv.out, "ee") == ee,
           "--out - --format csv prints both kinds under one header");
    const Run npy = minkq(base + "--out - --format npy --kind ee");
    expect(npy.status == 0 && parse_npy(npy.out) == ee, "--out - --format npy --kind ee is the EE array");
    const Run two = minkq(base + "--out - --format npy");
    expect(two.status == 2 && contains(two.err, "one kind"), "npy to stdout with two kinds is refused");

    // --kind: the kinds asked for, in that order, with the digests of the default run.
    expect(digest_lines(minkq(base + "--kind vt").out) == std::vector<std::string>{digests[0]}, "--kind vt");
    expect(digest_lines(minkq(base + "--kind ee,vt").out) == std::vector<std::string>{digests[1], digests[0]},
           "--kind ee,vt");
    // vv and ev: the pairs of the C API's VV and EV queries of the mesh (box mode).
    expect(minkq(base + "--kind vv,ev --out " + quoted(work + "/codim")).status == 0, "--kind vv,ev");
    const minkq::reference::Mesh m = minkq::reference::load_mesh(mesh);
    const float r = float(minkq::reference::mean_edge_length(m));
    minkq::cxx::Device device = minkq::cxx::open_device("cpu");
    minkq::cxx::Scene scene = minkq::cxx::new_mesh_scene(
        device.get(), m.xyz.data(), m.vertex_count(), m.tris.data(), m.triangle_count(),
        MINKQ_SCENE_VV | MINKQ_SCENE_EV | MINKQ_SCENE_DROP_INCIDENT);
    minkq::cxx::Result result = minkq::cxx::new_result();
    for (const auto& [kind, name] : {std::pair{MINKQ_QUERY_VV, "vv"}, std::pair{MINKQ_QUERY_EV, "ev"}}) {
      const minkq_query_desc q{kind, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL, r};
      minkq::cxx::check(minkq_scene_query_result(scene.get(), &q, result.get()), "minkq_scene_query_result");
      const int32_t* p = minkq_result_pairs(result.get());
      Pairs want(minkq_result_count(result.get()));
      for (size_t i = 0; i < want.size(); ++i) want[i] = {p[2 * i], p[2 * i + 1]};
      expect(!want.empty() && minkq::test::read_pairs(work + "/codim." + name + ".bin") == want,
             std::string("--kind ") + name + " writes the C API's pairs");
    }

    // Mode words: the new ones equal the old ones, which warn.
    const Run leaf_new = minkq(base + "--mode box --leaf-exact"), leaf_old = minkq(base + "--mode leaf_exact");
    expect(leaf_new.err.empty() && contains(leaf_old.err, "warning: --mode leaf_exact is deprecated"),
           "--mode leaf_exact warns, --leaf-exact does not");
    expect(digest_lines(leaf_new.out) == digest_lines(leaf_old.out) && digest_lines(leaf_new.out) != digests,
           "--mode box --leaf-exact gives the old leaf_exact pairs, fewer than box's");
    const Run exact_new = minkq(base + "--mode capsule_exact"), sphere_old = minkq(base + "--mode sphere");
    expect(exact_new.err.empty() && contains(sphere_old.err, "warning: --mode sphere for EE is deprecated"),
           "--mode sphere with EE warns, capsule_exact does not");
    expect(digest_lines(exact_new.out) == digest_lines(sphere_old.out), "--mode capsule_exact gives the old sphere pairs");
    expect(minkq(base + "--mode sphere --kind vt").err.empty(), "--mode sphere for VT alone is no old word");
    std::printf("%d failures\n", failures);
    return failures == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "check_cli_options: %s\n", e.what());
    return 3;
  }
}
