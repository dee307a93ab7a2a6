// cloth.cpp: the C++ classes of minkq.hpp (minkq::api) in a small step loop. A cloth, a grid of
// 8 x 8 vertices over the unit square, falls onto a static ground (two triangles at z = 0 whose
// shared edge is the diagonal x = y). The scene holds both as geometries; each step moves the
// cloth alone (geometry_refit) and asks for the vertex-triangle and edge-edge contacts within r.
// Checked: no contact until the cloth comes within r; then every cloth vertex lies over the
// ground, one pair each, and the 8 on the diagonal touch both triangles: 72 VT pairs. A refit
// with a wrong vertex count throws minkq::api::Error with the library's message.
#include <minkq.hpp>

#include <cstdio>
#include <exception>
#include <vector>

namespace api = minkq::api;

namespace {

constexpr int kSide = 8;  // cloth vertices per side

std::vector<float> cloth_at(float z) {
  std::vector<float> xyz;
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) xyz.insert(xyz.end(), {float(i) / (kSide - 1), float(j) / (kSide - 1), z});
  return xyz;
}

std::vector<int32_t> cloth_triangles() {
  std::vector<int32_t> tris;
  for (int j = 0; j + 1 < kSide; ++j)
    for (int i = 0; i + 1 < kSide; ++i) {
      const int32_t a = j * kSide + i, b = a + 1, c = a + kSide, d = c + 1;
      tris.insert(tris.end(), {a, b, d, a, d, c});
    }
  return tris;
}

}  // namespace

int main() {
  try {
    const api::Device device("auto");
    std::printf("device: %s\n", device.name().c_str());
    const std::vector<float> ground_xyz{-1, -1, 0, 2, -1, 0, 2, 2, 0, -1, 2, 0};
    const std::vector<int32_t> ground_tris{0, 1, 2, 0, 2, 3};
    const std::vector<int32_t> tris = cloth_triangles();
    const float r = 0.03f;

    const std::vector<float> start = cloth_at(0.1f);  // read when the scene is created: kept till then
    std::vector<api::GeometryDesc> geometries(2);
    geometries[0].vertices(start).triangles(tris);  // its own pairs too (the default)
    geometries[1].vertices(ground_xyz).triangles(ground_tris).self(false).is_static(true);
    api::Scene scene(device, geometries);
    const api::Range ground = scene.geometry_range(1, MINKQ_ELEMENT_TRIANGLE);
    std::printf("%u geometries; the ground's triangles are %zu and %zu\n", scene.geometry_count(), ground.first,
                ground.first + 1);

    const api::Query vt{MINKQ_QUERY_VT, r, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_CANONICAL};
    const api::Query ee{MINKQ_QUERY_EE, r, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_CANONICAL};
    std::vector<api::Pair> pairs;  // reused from step to step
    bool ok = true;
    for (int step = 0; step < 5; ++step) {
      const float z = 0.1f - 0.02f * float(step);
      scene.geometry_refit(0, cloth_at(z));
      const minkq_query_info info = scene.query(vt, pairs);
      const uint64_t ee_count = scene.count({MINKQ_QUERY_EE, r, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT});
      std::printf("step %d, cloth at z = %.2f: %llu VT and %llu EE contacts\n", step, double(z),
                  static_cast<unsigned long long>(info.count), static_cast<unsigned long long>(ee_count));
      const uint64_t expected = z > r ? 0 : kSide * kSide + kSide;
      if (info.count != expected || ee_count != scene.query(ee).size()) ok = false;
      for (const api::Pair& p : pairs)  // (cloth vertex, ground triangle)
        if (p.first >= kSide * kSide || p.second < int32_t(ground.first)) ok = false;
    }

    try {
      scene.geometry_refit(0, std::vector<float>(3 * 5, 0.0f));
      ok = false;
    } catch (const api::Error& e) {
      std::printf("a refit of 5 vertices is refused: %s\n", e.what());
    }
    std::printf(ok ? "ok\n" : "FAIL: unexpected pairs\n");
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
