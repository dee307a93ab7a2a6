// minkq::meshio: the triangle mesh that the programs (apps/), the oracle (oracle/), the tests,
// fuzzers and benchmarks read files into, and its one OBJ / PLY / OFF loader.
//
// It depends on neither the library nor the oracle: it is the file side of every tool, so that
// a mesh means the same vertices, triangles and edges wherever it is loaded.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace minkq::meshio {

// A triangle mesh with optional explicit edges. load_mesh (and the oracle's scene generators)
// fill `edges` with derive_edges(tris); the oracle's contact queries derive them too when
// `edges` is empty, as the C API does for a scene created with no edges.
struct Mesh {
  std::vector<float> xyz;      // 3 per vertex
  std::vector<int32_t> tris;   // 3 vertex indices per triangle
  std::vector<int32_t> edges;  // 2 vertex indices per edge
  // Double-precision input, when not empty: 3 per vertex, the positions the contact queries
  // use; xyz then holds them rounded to nearest float (set_float64 keeps the two in step).
  std::vector<double> xyz64;
  size_t vertex_count() const { return xyz.size() / 3; }
  size_t triangle_count() const { return tris.size() / 3; }
  size_t edge_count() const { return edges.size() / 2; }
};

// Every distinct undirected triangle edge as (min vertex, max vertex), sorted lexicographically:
// the numbering the C API uses. A triangle with a repeated vertex v contributes (v, v).
std::vector<int32_t> derive_edges(const std::vector<int32_t>& tris);

// Mean length of the edges (mesh.edges, or derive_edges(tris) when empty); 0 for no edges.
double mean_edge_length(const Mesh& mesh);

// Makes `xyz64` the mesh's positions (3 per vertex) and xyz their rounding to nearest float.
// Throws std::invalid_argument when its size is not a multiple of 3.
void set_float64(Mesh& mesh, std::vector<double> xyz64);

// Loads an OBJ (tinyobjloader: polygons triangulated, all shapes merged into one mesh), a PLY
// (ascii, binary_little_endian or binary_big_endian; vertex x, y, z of any scalar type, faces
// as a list, polygons fan-triangulated) or an OFF (.off; polygons fan-triangulated). Fills
// edges with derive_edges. Throws std::runtime_error naming the file and the problem. With
// float64, xyz64 holds the file's coordinates in double (OBJ and OFF text parsed as doubles, PLY
// values as stored) and xyz their rounding to nearest float.
Mesh load_mesh(const std::string& path, bool float64 = false);

}  // namespace minkq::meshio
