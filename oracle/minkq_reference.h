// minkq::reference (target minkq_reference): the independent double-precision oracle of the
// `minkq demo` false-negative check, the tests, the fuzzers and the benchmarks.
//
// It shares no code with the core on purpose: a bug in the core's predicates or traversal must
// not be able to hide itself by also living in the oracle. Distances are evaluated in long
// double on float meshes (whose coordinates are exact in double) or on a mesh's double input
// (Mesh::xyz64, exact in long double), and a pair is a contact when
// its distance is <= r (compared as squared distance <= r^2, both in long double; in scenes of
// many geometries r + t(a) + t(b)). Everything here favours being obviously right over being fast; the
// grid-accelerated queries exist only so that ~300k-triangle scenes can be checked in seconds.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "mesh_io.h"

namespace minkq::reference {

// The mesh type and its loader are the mesh I/O library's (apps/meshio), named here too so
// that the oracle's users read one vocabulary.
using meshio::derive_edges;
using meshio::load_mesh;
using meshio::Mesh;
using meshio::mean_edge_length;
using meshio::set_float64;

// ---- Distances (long double, robust to degenerate input) -----------------------------------
// Each is the minimum over the boundary features (endpoints, edges) plus the interior case,
// taken only when the closest point lies strictly inside; zero-length segments, parallel
// segments and zero-area triangles therefore need no special tolerance.
long double point_segment_distance(const double p[3], const double a[3], const double b[3]);
long double point_triangle_distance(const double p[3], const double a[3], const double b[3], const double c[3]);
long double segment_segment_distance(const double p0[3], const double p1[3], const double q0[3], const double q1[3]);

// ---- Contacts -------------------------------------------------------------------------------
using Pairs = std::vector<std::pair<int32_t, int32_t>>;

// Every (vertex, triangle) with point_triangle_distance <= r, sorted. drop_incident drops the
// triangles that contain the vertex. Grid-accelerated and parallel (TBB).
Pairs vt_contacts(const Mesh& mesh, double r, bool drop_incident);
// Every (e, f), e < f, with segment_segment_distance <= r, sorted. drop_incident drops pairs of
// edges sharing a vertex. Grid-accelerated and parallel (TBB).
Pairs ee_contacts(const Mesh& mesh, double r, bool drop_incident);
// The same sets by testing every pair: O(N * M), for small meshes and for checking the grid.
Pairs vt_contacts_brute(const Mesh& mesh, double r, bool drop_incident);
Pairs ee_contacts_brute(const Mesh& mesh, double r, bool drop_incident);

// ---- Scenes of many geometries ---------------------------------------------------------------
// A scene of several geometries (triangle meshes, rods, particles), as minkq.h's
// minkq_scene_create_geometries describes it, and its contacts in the global numbering. The
// bit values are the C API's (the tests check that they agree), but the oracle does not
// include minkq.h: it is the description of the rules, written again.
enum class Kind { VT, EE, VV, EV };
// Geometry::kinds bits: the kinds of pairs a geometry takes part in (MINKQ_SCENE_VT, ...).
inline constexpr uint32_t kKindVT = 1, kKindEE = 2, kKindVV = 16, kKindEV = 32;
// Geometry::flags bits (minkq_geometry_flags).
inline constexpr uint32_t kSelf = 1, kDropIncident = 2, kFloat64 = 4, kStatic = 8;

struct Geometry {
  // Its vertices (xyz64 when not empty, else xyz), triangles and edges: mesh.edges when not
  // empty (given), else derive_edges(mesh.tris) when it takes part in EE or EV, else none.
  Mesh mesh;
  std::vector<double> thickness;  // one per vertex (>= 0), or empty for none
  uint32_t kinds = kKindVT | kKindEE;
  uint32_t flags = kSelf | kDropIncident;  // kFloat64 and kStatic change no pair
  int32_t world = 0;                       // >= 0, or -1: part of every world
  uint32_t group = 1, mask = ~0u;
};

// The geometry's edges, as above.
std::vector<int32_t> geometry_edges(const Geometry& g);
// The geometries concatenated in order: the global numbering of vertices, triangles and edges
// (geometry_edges of each, offset by the vertices before it). xyz64 holds the positions in
// double (floats widened) when any geometry has double input, else it is empty.
Mesh concatenate(const std::vector<Geometry>& geometries);
// Geometry g's first global id and count of vertices, triangles or edges (k: 0, 1, 2, the
// order of minkq_element).
std::pair<size_t, size_t> geometry_range(const std::vector<Geometry>& geometries, size_t g, int k);

// Of `pairs` (global ids of `kind`: (vertex, triangle), (edge, edge), (vertex, vertex),
// (vertex, edge)), those that are not looked for at all: out of range, EE or VV not (lower,
// higher), or not allowed. Allowed are self pairs within a geometry with kSelf, less incident
// ones under kDropIncident (VT: the vertex is the triangle's, EE: the edges share a vertex, EV:
// the vertex is the edge's), and cross pairs between geometries that both take part in the
// kind, share a world (equal, or either -1) and pass each other's mask.
Pairs not_allowed(const std::vector<Geometry>& geometries, Kind kind, const Pairs& pairs);

// A global pair's distance (long double, on the input as given), its reach r + t(a) + t(b)
// (an element's thickness the largest of its vertices', 0 without) and the operand size S:
// the largest distance between any two of its points. Throws for a pair out of range.
struct PairMeasure {
  long double distance;
  double reach, scale;
};
std::vector<PairMeasure> measure_pairs(const std::vector<Geometry>& geometries, Kind kind, const Pairs& pairs, double r);

// Every allowed pair of `kind` whose distance is <= its reach (squared, in long double),
// sorted, in global ids. Grid-accelerated and parallel; the brute form tests every pair.
// Throws std::invalid_argument for a description minkq_scene_create_geometries refuses
// (bad indices, thickness count or value, world, kinds or flags).
Pairs geometry_contacts(const std::vector<Geometry>& geometries, Kind kind, double r);
Pairs geometry_contacts_brute(const std::vector<Geometry>& geometries, Kind kind, double r);

// ---- Scene generators (deterministic on every platform) -------------------------------------
// n x n vertices on [0,1]^2 at z = 0; vertex (i, j) is index j * n + i at (i, j) / (n - 1).
// Cell (i, j) gives triangles (v00, v10, v11) and (v00, v11, v01). n >= 2.
Mesh grid_sheet(int n);
// grid_sheet(n) twisted about the x axis: (u, v) -> (u, (v - 1/2) cos t, (v - 1/2) sin t) with
// t = turns * 2 pi * u. Three turns on the unit square strain the rows far from the axis, so
// the sheet mixes short and long edges and comes close to itself only near the axis.
Mesh twisted_sheet(int n, double turns);
// `layers` copies of grid_sheet(n), layer k lifted to z = k * gap (aligned vertex over vertex).
Mesh stacked_sheets(int n, int layers, double gap);
// `triangles` independent triangles (3 vertices each, nothing shared): centre uniform in
// [0,1]^3, each vertex the centre plus a uniform offset in [-size/2, size/2]^3. The random
// numbers come from splitmix64(seed), so the soup is the same on every platform.
Mesh random_soup(int triangles, uint64_t seed, double size);

// x -> x * scale + offset on every coordinate, in double, then rounded to float (double input:
// xyz64 transformed, xyz its rounding).
void transform(Mesh& mesh, double scale, double offset);

}  // namespace minkq::reference
