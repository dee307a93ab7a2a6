// arborx_bench's scenes: the reference, procedural, real, scale and extra scenes in table order.
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "arborx_bench.h"

namespace peer {

Scene mesh_scene(const std::string& suite, const std::string& name, const std::string& path, double factor) {
  const ref::Mesh mesh = ref::load_mesh(path);  // .obj, .ply or .off (CGAL's elephant-with-holes)
  return Scene{suite, name, std::filesystem::path(path).filename().string() + ", static", mesh, mesh.xyz, factor,
               float(factor * ref::mean_edge_length(mesh))};
}

std::vector<std::function<Scene()>> scene_list(const Options& opt) {
  std::vector<std::function<Scene()>> list;
  auto wanted = [&](const std::string& name) {
    if (opt.only.empty()) return true;
    for (const auto& x : split(opt.only))
      if (x == name) return true;
    return false;
  };
  auto sheet = [&](const std::string& suite, const std::string& name, double triangles) {
    if (!wanted(name)) return;
    list.push_back([=, &opt] {
      const mb::SceneFrames f = mb::make_scene("twist_target", triangles, 1, opt.data_dir);
      return Scene{suite, name, f.recipe, f.mesh, f.frames[0], 0.25, float(0.25 * f.mean_edge)};
    });
  };
  for (const std::string& suite : opt.suites) {
    if (suite == "reference") {
      sheet(suite, "twisted_sheet_301", 2.0 * 300 * 300);
      std::string elephant = opt.elephant;
      if (elephant.empty() && std::string(ARBORX_BENCH_CGAL_DIR) != "")
        elephant = std::string(ARBORX_BENCH_CGAL_DIR) + "/elephant-with-holes.off";
      if (!wanted("elephant-with-holes")) continue;
      if (elephant.empty() || !std::filesystem::is_regular_file(elephant))
        std::fprintf(stderr, "arborx_bench: skipped elephant-with-holes: %s not found (build.sh fetches it; or --elephant PATH)\n",
                     elephant.empty() ? "no path" : elephant.c_str());
      else
        list.push_back([=] { return mesh_scene("reference", "elephant-with-holes", elephant, 1.0); });
    } else if (suite == "scenes") {
      for (const std::string& name : mb::procedural_scene_names()) {
        if (!wanted(name)) continue;
        list.push_back([=, &opt] {
          // minkq_bench's frames: 4, r = factor x mean edge of frame 0; measured at the last.
          const mb::SceneFrames f = mb::make_scene(name, 0, 4, opt.data_dir);
          return Scene{"scenes", name, "last of 4 frames: " + f.recipe, f.mesh, f.frames.back(), f.radius_factor,
                       float(f.radius_factor * f.mean_edge)};
        });
      }
    } else if (suite == "real") {
      for (const mb::RealMesh& m : mb::available_real_meshes(opt.data_dir)) {
        if (!wanted(m.name)) continue;
        list.push_back([=, &opt] { return mesh_scene("real", m.name, mb::mesh_path(m.path, opt.data_dir), 0.25); });
      }
    } else if (suite == "scale") {
      sheet(suite, "twisted_sheet_1M", 1e6);
    } else {
      throw std::invalid_argument("unknown suite '" + suite + "'");
    }
  }
  for (const auto& [path, factor] : opt.meshes) {
    const std::string name = std::filesystem::path(path).stem().string();
    if (wanted(name)) list.push_back([=] { return mesh_scene("extra", name, path, factor); });
  }
  return list;
}

}  // namespace peer
