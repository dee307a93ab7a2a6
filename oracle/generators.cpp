// Scene generators and the transform of the reference library.
#include "minkq_reference.h"

#include <cmath>
#include <stdexcept>

namespace minkq::reference {

// ---- Generators ----------------------------------------------------------------------------
Mesh grid_sheet(int n) {
  if (n < 2) throw std::invalid_argument("grid_sheet: n must be >= 2");
  Mesh m;
  m.xyz.reserve(3 * size_t(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) m.xyz.insert(m.xyz.end(), {float(double(i) / (n - 1)), float(double(j) / (n - 1)), 0.0f});
  m.tris.reserve(6 * size_t(n - 1) * (n - 1));
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int32_t v00 = j * n + i, v10 = v00 + 1, v01 = v00 + n, v11 = v01 + 1;
      m.tris.insert(m.tris.end(), {v00, v10, v11, v00, v11, v01});
    }
  m.edges = derive_edges(m.tris);
  return m;
}

Mesh twisted_sheet(int n, double turns) {
  Mesh m = grid_sheet(n);
  const double pi = 3.14159265358979323846;
  for (size_t i = 0; i < m.xyz.size(); i += 3) {
    const double u = m.xyz[i], v = m.xyz[i + 1] - 0.5, t = turns * 2 * pi * u;
    m.xyz[i + 1] = float(v * std::cos(t));
    m.xyz[i + 2] = float(v * std::sin(t));
  }
  return m;
}

Mesh stacked_sheets(int n, int layers, double gap) {
  if (layers < 1) throw std::invalid_argument("stacked_sheets: layers must be >= 1");
  const Mesh sheet = grid_sheet(n);
  const int32_t nv = int32_t(sheet.vertex_count());
  Mesh m;
  for (int k = 0; k < layers; ++k) {
    for (size_t i = 0; i < sheet.xyz.size(); i += 3)
      m.xyz.insert(m.xyz.end(), {sheet.xyz[i], sheet.xyz[i + 1], float(k * gap)});
    for (int32_t v : sheet.tris) m.tris.push_back(v + k * nv);
  }
  m.edges = derive_edges(m.tris);
  return m;
}

Mesh random_soup(int triangles, uint64_t seed, double size) {
  if (triangles < 0) throw std::invalid_argument("random_soup: negative triangle count");
  uint64_t state = seed;
  auto uniform = [&state] {  // splitmix64, then the top 53 bits as a double in [0, 1)
    uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return double((z ^ (z >> 31)) >> 11) * 0x1p-53;
  };
  Mesh m;
  for (int t = 0; t < triangles; ++t) {
    double c[3];
    for (double& x : c) x = uniform();
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) m.xyz.push_back(float(c[a] + (uniform() - 0.5) * size));
    m.tris.insert(m.tris.end(), {3 * t, 3 * t + 1, 3 * t + 2});
  }
  m.edges = derive_edges(m.tris);
  return m;
}

void transform(Mesh& m, double scale, double offset) {
  if (!m.xyz64.empty()) {
    for (double& x : m.xyz64) x = x * scale + offset;
    m.xyz.assign(m.xyz64.begin(), m.xyz64.end());
    return;
  }
  for (float& x : m.xyz) x = float(double(x) * scale + offset);
}

}  // namespace minkq::reference
