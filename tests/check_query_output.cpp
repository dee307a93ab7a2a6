// Checks what `minkq query` writes on a real mesh: its leaf_exact pairs (PREFIX.vt.bin,
// PREFIX.ee.bin) contain every VT/EE contact of the independent double-precision oracle, in
// the same numbering, and every extra pair lies within r + 2^-19 * S.
// usage: check_query_output MINKQ_BINARY MESH RADIUS_FACTOR WORK_DIR
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "contact_checks.h"

using minkq::reference::Pairs;
using minkq::test::compare_pairs;
using minkq::test::read_pairs;

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: check_query_output MINKQ_BINARY MESH RADIUS_FACTOR WORK_DIR\n");
    return 2;
  }
  try {
    const std::string binary = argv[1], mesh_path = argv[2], work = argv[4];
    minkq::reference::Mesh mesh = minkq::reference::load_mesh(mesh_path);
    const float r = float(std::atof(argv[3]) * minkq::reference::mean_edge_length(mesh));
    char radius[32];
    std::snprintf(radius, sizeof radius, "%.9g", double(r));  // round-trips the float exactly
    const std::string prefix = work + "/out";
    const std::string command = "\"" + binary + "\" query \"" + mesh_path + "\" --radius " + radius +
                                " --mode box --leaf-exact --backend cpu --out \"" + prefix + "\"";
    std::printf("%s\n", command.c_str());
    std::fflush(stdout);
    if (std::system(command.c_str()) != 0) throw std::runtime_error("minkq query failed");
    const Pairs vt = read_pairs(prefix + ".vt.bin"), ee = read_pairs(prefix + ".ee.bin");
    const auto reach = [r](int32_t, int32_t) { return (long double)r; };
    int failures = compare_pairs(
        "VT", vt, minkq::reference::vt_contacts(mesh, r, true), true,
        [&](int32_t v, int32_t t, double* s) { return minkq::test::vt_distance(mesh, v, t, s); }, reach);
    failures += compare_pairs(
        "EE", ee, minkq::reference::ee_contacts(mesh, r, true), true,
        [&](int32_t e, int32_t f, double* s) { return minkq::test::ee_distance(mesh, mesh.edges, e, f, s); }, reach);
    return failures == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "check_query_output: %s\n", e.what());
    return 3;
  }
}
