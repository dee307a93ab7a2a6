// Benchmark scenes: procedural reproductions of the eight Newton scenes of the reference study
// (recipes and radii from ../shared/data/README.md), each a short deterministic sequence of
// frames, at reference size or scaled to a target triangle count; the real meshes of
// ../shared/data; and the twisted sheet of ../shared/REFERENCES.md (the H100 target scene).
//
// A frame is a full set of vertex positions over one fixed topology (frame 0 is in
// `mesh.xyz`), so frame k > 0 exercises refit. Every deformation is a closed-form function of
// the phase s = k / (frames - 1) in [0, 1]; nothing is random, so every platform gets the same
// float coordinates (the libm calls used, sin/cos/exp/sqrt of doubles, are correctly rounded
// in practice on glibc; the counts in the result tables are the check).
#pragma once

#include <string>
#include <vector>

#include "minkq_reference.h"

namespace minkq::bench {

struct SceneFrames {
  std::string name;         // e.g. "cloth_twist"
  std::string recipe;       // one line: what it is and how it moves
  reference::Mesh mesh;     // topology, edges derived (the C API's numbering), frame 0 positions
  std::vector<std::vector<float>> frames;  // frames[k]: 3 floats per vertex; frames[0] == mesh.xyz
  double reference_radius;  // the Newton scene's margin at reference size (scene units)
  double radius_factor;     // reference_radius / mean edge at reference size
  double mean_edge;         // mean edge length of frame 0 of this (possibly scaled) instance
  double scale;             // triangles of this instance / triangles at reference size
};

// The eight procedural scenes, in the reference study's order.
const std::vector<std::string>& procedural_scene_names();

// Builds a procedural scene (one of procedural_scene_names(), or "twist_target": the twisted
// unit sheet of REFERENCES.md, 3 turns, radius 0.25 x mean edge). target_triangles <= 0 gives
// the reference size; otherwise resolution (or midpoint subdivision, for the scenes made from
// meshes) is raised to come close to it. curvedSurface and unisex_shirt come from
// mesh_path(…, data_dir). frames >= 1.
SceneFrames make_scene(const std::string& name, double target_triangles, int frames, const std::string& data_dir);

struct RealMesh {
  std::string name;  // short name for tables
  std::string path;  // for mesh_path
};
// Where a mesh (a path such as "newton/bear.obj") lies: the repository's meshes
// (data/meshes.tar.xz, unpacked by CMake into MINKQ_BENCH_MESH_DIR) first, then data_dir (the
// benchmark-only meshes: ../shared/data beside the repository, or --data DIR). find_mesh gives
// "" when it is in neither; mesh_path throws, naming the file and both folders.
std::string find_mesh(const std::string& relative, const std::string& data_dir);
std::string mesh_path(const std::string& relative, const std::string& data_dir);

// The real meshes of the benchmarks (single static frames): those of data/meshes.tar.xz and the
// larger ones of ../shared/data.
const std::vector<RealMesh>& real_meshes();
// The real meshes that find_mesh finds; each missing one is named on stderr, with the reason.
std::vector<RealMesh> available_real_meshes(const std::string& data_dir);
// Loads one real mesh as a one-frame scene with radius_factor 0.25 (the REFERENCES convention).
SceneFrames load_real_scene(const RealMesh& m, const std::string& data_dir);

// Midpoint subdivision: every triangle into four, shared edge midpoints merged. Edges derived.
reference::Mesh subdivide(const reference::Mesh& m);

}  // namespace minkq::bench
