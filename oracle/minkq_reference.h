// minkq::reference (target minkq_reference): the independent double-precision oracle of the
// `minkq demo` false-negative check, the tests, the fuzzers and the benchmarks.
//
// It shares no code with the core on purpose: a bug in the core's predicates or traversal must
// not be able to hide itself by also living in the oracle. Distances are evaluated in long
// double on float meshes (whose coordinates are exact in double) or on a mesh's double input
// (Mesh::xyz64, exact in long double), and a pair is a contact when
// its distance is <= r (compared as squared distance <= r^2, both in long double). Everything here favours being obviously right over being fast; the
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
