// minkq: the command-line tool. `demo` measures every query mode on a built-in scene against
// the reference oracle; `query` runs one mode on a mesh file (or, swept, from one frame to the
// next) and prints comparable digests.
#include "minkq.h"
#include "minkq.hpp"
#include "cli_common.h"
#include "cli_output.h"
#include "mesh_io.h"
#include "minkq_reference.h"

#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace meshio = minkq::meshio;
namespace ref = minkq::reference;

namespace {

constexpr int kExitFalseNegatives = 1, kExitUsage = 2, kExitFailure = 3;

const char* const kDemoUsage = R"usage(  demo [--backend B] [--size N] [--radius-factor F]
      Twisted sheet of N x N vertices (default 388: 299,538 triangles), 3 turns, radius
      F x mean edge length (default 0.25). Runs VT and EE queries in every mode, compares them
      with the double-precision reference oracle and prints candidates, true contacts,
      false-positive ratio, false negatives, query time (median of 3) and speedup over box
      (the box query of the same kind).
)usage";

const char* const kQueryUsage = R"usage(  query MESH [--against MESH_B [--self]] [--thickness FILE] [--to MESH1]
        --radius R | --radius-factor F [--kind K] [--mode M] [--leaf-exact] [--backend B]
        [--out PREFIX | --out -] [--format F] [--stats]
      Loads an OBJ, PLY or OFF mesh and runs the queries of each kind K (incident pairs dropped)
      within R (or F x the mesh's mean edge length).
      --kind K: a comma-separated list of vt (vertex, triangle), ee (edge, edge), vv (vertex,
        vertex) and ev (vertex, edge); default vt,ee. Each runs in the order given.
      --mode M: the node test, as the library names it: box (default: r-padded boxes), sphere
        (point queries: vt, vv, ev), capsule_ray (segment slab test; for points the box test)
        or capsule_exact (segment-box distance; for points the sphere test).
      --leaf-exact: the primitive distance at the leaves as well: the contacts (up to the
        slack minkq.h states). Fastest with --mode box.
        Old words, kept for one release with a warning: --mode leaf_exact (= --mode box
        --leaf-exact) and --mode sphere for ee (runs ee as capsule_exact).
      Prints "KIND candidates N digest HEX" per kind (xxHash64 of the canonical pairs) on stdout,
      or on stderr with --out -.
      --out PREFIX writes PREFIX.KIND.EXT per kind; --out - writes the pairs to stdout. Pairs
      are in canonical (sorted) order, in --format F:
        text  "a b" per line, after a line "# KIND: N pairs (...)" (default with --out -)
        csv   a header "kind,first,second", then "KIND,a,b" per line
        npy   a NumPy .npy file of int32, shape (N, 2); to stdout, one kind only
        bin   little-endian int32 (a, b) pairs (default with --out PREFIX); to stdout, one kind
      --stats adds a line of work counts per kind: internal nodes visited, node-shape tests,
      primitive tests and candidates (MINKQ_QUERY_STATS; the same on every backend).
      --against MESH_B: MESH and MESH_B are geometries 0 and 1 of one scene, and only the pairs
      between them are reported: MESH's vertices against MESH_B's triangles and MESH_B's against
      MESH's, and edge pairs across the two (--self adds each mesh's own pairs). Pairs are
      numbered as in the two meshes concatenated: MESH_B's vertices, triangles and edges come
      after MESH's, each mesh's edges numbered as a query of it alone numbers them. F scales
      MESH's mean edge length.
      --thickness FILE: a thickness t >= 0 per vertex, MESH's then MESH_B's, one number per
      line (blank lines and lines starting with # are skipped). An element's thickness is the
      largest of its vertices', and a pair is reported when its distance is <= R + t(a) + t(b).
      A wrong count, or a value that is not a finite number >= 0 (as a float), is an error that
      names the line (exit status 3).
      --to MESH1: swept queries from MESH to MESH1 (same vertices and triangles, read in
      double precision): every pair whose elements come within r while each vertex moves
      linearly from its first to its second position, the candidates of a CCD narrow phase.
      Kinds vt and ee. Modes: box (default), sphere or capsule_exact (VT: the capsule around
      each vertex's path), capsule_ray (VT: its slab test); EE runs box in every mode; no
      --leaf-exact. R = 0 reports elements that touch. Not with --against or --thickness.
      On a terminal, a progress line on stderr names the step under way.
)usage";

const char* const kUsageHead = R"usage(usage: minkq <command> [options]   (minkq <command> --help: that command's usage)

commands:
)usage";

const char* const kUsageTail = R"usage(  version
      Library, ABI and header versions, and the number of CUDA devices.

options:
  --backend B   cpu, cuda, cuda:N or auto (default: auto, CUDA when a GPU is usable)

exit status: 0 success, 1 false negatives found (demo), 2 bad arguments, 3 failure (file, API)
)usage";

// The usage of one command ("" for all), on stdout.
int print_usage(const std::string& command) {
  if (command == "demo" || command == "query") {
    std::printf("usage: minkq %s\n\n%s\n  --backend B   cpu, cuda, cuda:N or auto (default: auto, CUDA when a GPU is usable)\n",
                command == "demo" ? "demo [options]" : "query MESH [options]", command == "demo" ? kDemoUsage : kQueryUsage);
    return 0;
  }
  std::printf("%s%s%s%s", kUsageHead, kDemoUsage, kQueryUsage, kUsageTail);
  return 0;
}

using namespace minkq::cli;  // Args, UsageError, parse_number, query_radius, query_modes, Kind, Format, Progress

// Owning handles, check(), open_device(), new_result() and new_mesh_scene() (capi/minkq.hpp).
using namespace minkq::cxx;

// A scene of `kinds` (minkq_scene_flags; VT + EE by default) with incident pairs dropped; edges
// are derived by the library.
Scene make_scene(minkq_device* device, const meshio::Mesh& m, uint32_t kinds = MINKQ_SCENE_VT | MINKQ_SCENE_EE) {
  return new_mesh_scene(device, m.xyz.data(), m.vertex_count(), m.tris.data(), m.triangle_count(),
                        kinds | MINKQ_SCENE_DROP_INCIDENT);
}

ref::Pairs result_pairs(const minkq_result* r) {
  const int32_t* p = minkq_result_pairs(r);
  ref::Pairs out(minkq_result_count(r));
  for (size_t i = 0; i < out.size(); ++i) out[i] = {p[2 * i], p[2 * i + 1]};
  return out;
}

double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// ---- demo ----------------------------------------------------------------------------------
struct DemoMode {
  minkq_query_kind kind;
  const char* name;
  minkq_mode mode;
  uint32_t flags;
};

int demo(const Args& args) {
  if (!args.positional.empty()) throw UsageError("demo takes no positional arguments");
  const std::string backend = args.get("--backend") ? *args.get("--backend") : "auto";
  const double size = args.get("--size") ? parse_number("--size", *args.get("--size")) : 388;
  const double factor = args.get("--radius-factor") ? parse_number("--radius-factor", *args.get("--radius-factor")) : 0.25;
  if (size < 2 || size > 20000 || size != std::floor(size)) throw UsageError("--size: an integer from 2 to 20000");
  if (factor < 0) throw UsageError("--radius-factor: must be >= 0");

  const int n = int(size);
  const ref::Mesh mesh = ref::twisted_sheet(n, 3.0);
  const double h = meshio::mean_edge_length(mesh);
  // The library takes a float radius; the oracle gets the very same value.
  const float r = float(factor * h);
  if (!std::isfinite(r)) throw UsageError("--radius-factor: radius overflows a float");

  Device device = open_device(backend);
  std::printf("minkq demo: twisted sheet %dx%d, 3 turns: %zu vertices, %zu triangles, %zu edges\n", n, n,
              mesh.vertex_count(), mesh.triangle_count(), mesh.edge_count());
  std::printf("radius %.6g = %g x mean edge length %.6g; device %s\n", double(r), factor, h,
              minkq_device_name(device.get()));

  double t0 = now_ms();
  Scene scene = make_scene(device.get(), mesh);
  std::printf("scene build %.1f ms\n", now_ms() - t0);
  // The oracle numbers edges with derive_edges; the library must number them the same way.
  std::vector<int32_t> edges(2 * minkq_scene_edge_count(scene.get()));
  check(minkq_scene_edges(scene.get(), edges.data(), edges.size() / 2), "minkq_scene_edges");
  if (edges != mesh.edges) throw std::runtime_error("the library's edge numbering differs from derive_edges");

  t0 = now_ms();
  const ref::Pairs true_vt = ref::vt_contacts(mesh, r, true);
  const double vt_ms = now_ms() - t0;
  t0 = now_ms();
  const ref::Pairs true_ee = ref::ee_contacts(mesh, r, true);
  std::printf("reference oracle: %zu VT contacts in %.0f ms, %zu EE contacts in %.0f ms\n\n", true_vt.size(), vt_ms,
              true_ee.size(), now_ms() - t0);

  const DemoMode modes[] = {
      {MINKQ_QUERY_VT, "box", MINKQ_MODE_BOX, 0},
      {MINKQ_QUERY_VT, "sphere", MINKQ_MODE_SPHERE, 0},
      {MINKQ_QUERY_VT, "box+leaf_exact", MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT},
      {MINKQ_QUERY_VT, "sphere+leaf_exact", MINKQ_MODE_SPHERE, MINKQ_QUERY_LEAF_EXACT},
      {MINKQ_QUERY_EE, "box", MINKQ_MODE_BOX, 0},
      {MINKQ_QUERY_EE, "capsule_ray", MINKQ_MODE_CAPSULE_RAY, 0},
      {MINKQ_QUERY_EE, "capsule_exact", MINKQ_MODE_CAPSULE_EXACT, 0},
      {MINKQ_QUERY_EE, "box+leaf_exact", MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT},
      {MINKQ_QUERY_EE, "capsule_exact+leaf_exact", MINKQ_MODE_CAPSULE_EXACT, MINKQ_QUERY_LEAF_EXACT},
  };
  std::printf("%-4s %-26s %12s %12s %9s %10s %10s %8s\n", "kind", "mode", "candidates", "true", "fp ratio",
              "false neg", "query ms", "speedup");
  Result result = new_result();
  uint64_t total_false_negatives = 0;
  double box_ms = 0;
  for (const DemoMode& m : modes) {
    const minkq_query_desc q{m.kind, m.mode, m.flags, r};
    double times[3];
    for (double& t : times) {
      const double start = now_ms();
      check(minkq_scene_query_result(scene.get(), &q, result.get()), "minkq_scene_query_result");
      t = now_ms() - start;
    }
    std::sort(times, times + 3);
    const double ms = times[1];
    if (m.mode == MINKQ_MODE_BOX && m.flags == 0) box_ms = ms;

    ref::Pairs got = result_pairs(result.get());
    std::sort(got.begin(), got.end());
    const ref::Pairs& truth = m.kind == MINKQ_QUERY_VT ? true_vt : true_ee;
    // Sorted merge: true pairs absent from the candidates.
    uint64_t missing = 0;
    for (size_t i = 0, j = 0; i < truth.size(); ++i) {
      while (j < got.size() && got[j] < truth[i]) ++j;
      if (j == got.size() || got[j] != truth[i]) ++missing;
    }
    total_false_negatives += missing;
    const double fp = truth.empty() ? 0.0 : (double(got.size()) - double(truth.size())) / double(truth.size());
    std::printf("%-4s %-26s %12zu %12zu %9.3f %10" PRIu64 " %10.2f %7.2fx\n", m.kind == MINKQ_QUERY_VT ? "VT" : "EE",
                m.name, got.size(), truth.size(), fp, missing, ms, ms > 0 ? box_ms / ms : 0.0);
  }
  if (total_false_negatives) {
    std::printf("\nFAIL: %" PRIu64 " true contacts missing from the candidates\n", total_false_negatives);
    return kExitFalseNegatives;
  }
  std::printf("\nno false negatives\n");
  return 0;
}

// ---- query ---------------------------------------------------------------------------------
// The scene of `query` for `kinds` (minkq_scene_flags): static on `first` (float, as loaded), or
// swept from `first` to `*to` (float64 input, read in double; the same topology).
Scene query_scene(minkq_device* device, const std::string& first, const std::string* to, uint32_t kinds) {
  if (!to) return make_scene(device, meshio::load_mesh(first), kinds);
  const meshio::Mesh a = meshio::load_mesh(first, true), b = meshio::load_mesh(*to, true);
  if (a.vertex_count() != b.vertex_count() || a.tris != b.tris)
    throw std::runtime_error("--to " + *to + ": not the same mesh as " + first + " (" + std::to_string(b.vertex_count()) +
                             " vertices and " + std::to_string(b.triangle_count()) + " triangles against " +
                             std::to_string(a.vertex_count()) + " and " + std::to_string(a.triangle_count()) +
                             ", or other triangles)");
  minkq_scene_desc desc{};
  desc.flags = kinds | MINKQ_SCENE_DROP_INCIDENT | MINKQ_SCENE_FLOAT64;
  desc.vertices = host_buffer(a.xyz64.data(), a.vertex_count());
  desc.triangles = host_buffer(a.tris.data(), a.triangle_count());
  Scene scene = new_scene(device, desc);
  check(minkq_scene_rebuild_swept(scene.get(), desc.vertices, host_buffer(b.xyz64.data(), b.vertex_count())),
        "minkq_scene_rebuild_swept");
  return scene;
}

// The values of `--thickness FILE`: one per vertex of `meshes` (in order), one number per line;
// blank lines and lines whose first non-blank character is '#' are skipped. Each value must
// be a finite number >= 0 that stays finite as a float (the C API takes floats). Errors name
// the file and line.
std::vector<float> read_thickness(const std::string& path, const std::vector<meshio::Mesh>& meshes,
                                  const std::vector<std::string>& names) {
  size_t needed = 0;
  std::string counts;
  for (size_t i = 0; i < meshes.size(); ++i) {
    needed += meshes[i].vertex_count();
    counts += (i ? ", " : "") + names[i] + " has " + std::to_string(meshes[i].vertex_count());
  }
  std::ifstream f(path);
  if (!f) throw std::runtime_error("--thickness: cannot read " + path);
  std::vector<float> t;
  t.reserve(needed);
  std::string line;
  size_t number = 0;
  const auto fail = [&](const std::string& what) {
    throw std::runtime_error("--thickness " + path + ":" + std::to_string(number) + ": " + what);
  };
  while (std::getline(f, line)) {
    ++number;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::string text = line.substr(first, line.find_last_not_of(" \t\r") + 1 - first);
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0') fail("not a number: '" + text + "'");
    if (!std::isfinite(v)) fail("not a finite number: '" + text + "'");
    if (v < 0) fail("negative thickness: '" + text + "'");
    if (!std::isfinite(float(v))) fail("too large for a float: '" + text + "'");
    if (t.size() == needed)
      fail("one value too many: " + std::to_string(needed) + " expected, one per vertex (" + counts + ")");
    t.push_back(v == 0 ? 0.0f : float(v));  // -0 as +0
  }
  if (f.bad()) throw std::runtime_error("--thickness: cannot read " + path);
  if (t.size() != needed)
    fail("the file ends after " + std::to_string(t.size()) + " values; " + std::to_string(needed) +
         " expected, one per vertex (" + counts + ")");
  return t;
}

// The scene of `query --against` or `--thickness`: each mesh one geometry (`kinds`, incident
// pairs dropped, edges derived), in order, so that the pairs come in the numbering of the meshes
// concatenated. With one mesh it reports its own pairs; with two only those across them unless
// `self` (MINKQ_GEOMETRY_SELF on both). `thickness`: empty, or one value per vertex of all.
Scene geometry_scene(minkq_device* device, const std::vector<meshio::Mesh>& meshes, const std::vector<float>& thickness,
                     bool self, uint32_t kinds) {
  std::vector<minkq_geometry_desc> descs(meshes.size());
  size_t first_vertex = 0;
  for (size_t g = 0; g < meshes.size(); ++g) {
    const meshio::Mesh& m = meshes[g];
    minkq_geometry_desc& d = descs[g];
    minkq_geometry_desc_init(&d);
    d.kinds = kinds;
    d.flags = MINKQ_GEOMETRY_DROP_INCIDENT | (self || meshes.size() == 1 ? uint32_t(MINKQ_GEOMETRY_SELF) : 0u);
    d.vertices = host_buffer(m.xyz.data(), m.vertex_count(), 3 * sizeof(float));
    d.triangles = host_buffer(m.tris.data(), m.triangle_count(), 3 * sizeof(int32_t));
    if (!thickness.empty()) d.thickness = host_buffer(thickness.data() + first_vertex, m.vertex_count(), sizeof(float));
    first_vertex += m.vertex_count();
  }
  minkq_scene* s = nullptr;
  check(minkq_scene_create_geometries(device, descs.data(), descs.size(), &s), "minkq_scene_create_geometries");
  return Scene(s);
}

// The scene `query` runs on, from its arguments (see the usage text; check_query_options has
// checked them).
Scene scene_for_query(minkq_device* device, const Args& args, uint32_t kinds) {
  const std::string& path = args.positional[0];
  const std::string *to = args.get("--to"), *against = args.get("--against"), *thickness = args.get("--thickness");
  if (!against && !thickness) return query_scene(device, path, to, kinds);
  std::vector<meshio::Mesh> meshes{meshio::load_mesh(path)};
  std::vector<std::string> names{path};
  if (against) meshes.push_back(meshio::load_mesh(*against)), names.push_back(*against);
  const std::vector<float> t = thickness ? read_thickness(*thickness, meshes, names) : std::vector<float>{};
  return geometry_scene(device, meshes, t, args.has("--self"), kinds);
}

// The usage errors of `query`'s options, before any file is read.
void check_query_options(const Args& args) {
  if (args.positional.size() != 1) throw UsageError("query needs exactly one MESH argument");
  if (args.has("--self") && !args.get("--against"))
    throw UsageError("--self needs --against (a single mesh's own pairs are always reported)");
  if (args.get("--to") && (args.get("--against") || args.get("--thickness")))
    throw UsageError("--to: swept queries take no --against or --thickness");
  if (args.get("--format") && !args.get("--out")) throw UsageError("--format needs --out PREFIX or --out -");
}

void warn(const std::string& message) { std::fprintf(stderr, "minkq: warning: %s\n", message.c_str()); }

int query(const Args& args) {
  check_query_options(args);
  const std::string* to = args.get("--to");
  const std::vector<Kind> kinds = parse_kinds(args.get("--kind") ? *args.get("--kind") : "vt,ee", to != nullptr);
  uint32_t scene_kinds = 0;
  bool has_ee = false;
  for (const Kind& k : kinds) scene_kinds |= k.scene_flag, has_ee |= k.kind == MINKQ_QUERY_EE;
  const QueryModes modes =
      query_modes(args.get("--mode") ? *args.get("--mode") : "box", args.has("--leaf-exact"), to != nullptr, has_ee, warn);
  const std::string* out = args.get("--out");
  const bool to_stdout = out && *out == "-";
  const Format format =
      args.get("--format") ? parse_format(*args.get("--format")) : to_stdout ? Format::text : Format::bin;
  if (to_stdout && one_array_per_stream(format) && kinds.size() > 1)
    throw UsageError("--out - --format " + std::string(extension(format)) +
                     ": stdout holds one array, so one kind (--kind vt, ee, vv or ev)");
  Progress progress;
  progress.step("reading " + args.positional[0]);
  const float radius = query_radius(args, [&] { return meshio::mean_edge_length(meshio::load_mesh(args.positional[0])); });
  const std::string backend = args.get("--backend") ? *args.get("--backend") : "auto";
  const uint32_t flags = modes.flags | MINKQ_QUERY_DIGEST | (args.has("--stats") ? uint32_t(MINKQ_QUERY_STATS) : 0u);

  Device device = open_device(backend);
  progress.step("building the scene");
  Scene scene = scene_for_query(device.get(), args, scene_kinds);
  Result result = new_result();
  // The summary lines go to stderr when stdout carries the pairs.
  FILE* summary = to_stdout ? stderr : stdout;
  for (const Kind& k : kinds) {
    progress.step(std::string(k.name) + " query");
    const minkq_query_desc q{k.kind, modes.of(k.kind), flags, radius};
    check(minkq_scene_query_result(scene.get(), &q, result.get()), "minkq_scene_query_result");
    progress.done();
    std::fprintf(summary, "%s candidates %" PRIu64 " digest %016" PRIx64 "\n", k.name, minkq_result_count(result.get()),
                 minkq_result_digest(result.get()));
    if (flags & MINKQ_QUERY_STATS) {
      const minkq_query_stats w = minkq_result_stats(result.get());
      std::fprintf(summary, "%s work nodes_visited %" PRIu64 " node_tests %" PRIu64 " primitive_tests %" PRIu64
                   " candidates %" PRIu64 "\n", k.name, w.nodes_visited, w.node_tests, w.primitive_tests, w.candidates);
    }
    std::fflush(summary);
    if (!out) continue;
    // A file per kind, each csv file with its header; on stdout one header before the first kind.
    if (!to_stdout) progress.step(std::string("writing ") + k.name + " pairs");  // not amid the pairs on a terminal
    std::string bytes = format == Format::csv && (!to_stdout || &k == &kinds.front()) ? csv_header() : "";
    append_pairs(bytes, format, k, minkq_result_pairs(result.get()), minkq_result_count(result.get()));
    write_bytes(to_stdout ? "-" : *out + "." + k.name + "." + extension(format), bytes);
    progress.done();
  }
  return 0;
}

int version() {
  const uint32_t v = minkq_version();
  std::printf("minkq %u.%u.%u (ABI %u; built against header %d.%d.%d, ABI %d)\n", v / 10000, v / 100 % 100, v % 100,
              minkq_abi_version(), MINKQ_VERSION_MAJOR, MINKQ_VERSION_MINOR, MINKQ_VERSION_PATCH, MINKQ_ABI_VERSION);
  std::printf("CUDA devices: %d\n", minkq_cuda_device_count());
  return minkq_abi_version() == MINKQ_ABI_VERSION ? 0 : kExitFailure;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string command = argc > 1 ? argv[1] : "";
  try {
    if (command == "--help" || command == "-h" || command == "help") return print_usage("");
    if ((command == "demo" || command == "query") && wants_help(argc, argv, 2)) return print_usage(command);
    if (command == "version" || command == "--version") {
      if (argc > 2 && !wants_help(argc, argv, 2)) throw UsageError(std::string("version: unknown argument ") + argv[2]);
      return argc > 2 ? print_usage("") : version();
    }
    if (command == "demo") return demo(Args(argc, argv, 2, {"--backend", "--size", "--radius-factor"}));
    if (command == "query")
      return query(Args(argc, argv, 2,
                        {"--radius", "--radius-factor", "--kind", "--mode", "--backend", "--out", "--format", "--to",
                         "--against", "--thickness"},
                        {"--stats", "--self", "--leaf-exact"}));
    throw UsageError(command.empty() ? "no command given" : "unknown command '" + command + "'");
  } catch (const UsageError& e) {
    std::fprintf(stderr, "minkq: %s\n(run 'minkq %s--help' for usage)\n", e.what(),
                 command == "demo" || command == "query" ? (command + " ").c_str() : "");
    return kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "minkq: %s\n", e.what());
    return kExitFailure;
  }
}
