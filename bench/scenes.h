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
// meshes) is raised to come close to it. data_dir is ../shared/data (curvedSurface and
// unisex_shirt are loaded from it). frames >= 1.
SceneFrames make_scene(const std::string& name, double target_triangles, int frames, const std::string& data_dir);

struct RealMesh {
  std::string name;  // short name for tables
  std::string path;  // relative to data_dir
};
// The real meshes of ../shared/data (single static frames).
const std::vector<RealMesh>& real_meshes();
// Loads one real mesh as a one-frame scene with radius_factor 0.25 (the REFERENCES convention).
SceneFrames load_real_scene(const RealMesh& m, const std::string& data_dir);

// Midpoint subdivision: every triangle into four, shared edge midpoints merged. Edges derived.
reference::Mesh subdivide(const reference::Mesh& m);

}  // namespace minkq::bench
