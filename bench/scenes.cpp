// Procedural scenes and real-mesh loading for the benchmarks; see scenes.h and the scene table
// in bench/README.md for each recipe.
#include "scenes.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <stdexcept>

namespace minkq::bench {

namespace ref = minkq::reference;

std::string find_mesh(const std::string& relative, const std::string& data_dir) {
  for (const std::string& dir : {std::string(MINKQ_BENCH_MESH_DIR), data_dir})
    if (!dir.empty() && std::filesystem::is_regular_file(dir + "/" + relative)) return dir + "/" + relative;
  return "";
}

std::string mesh_path(const std::string& relative, const std::string& data_dir) {
  const std::string path = find_mesh(relative, data_dir);
  if (path.empty())
    throw std::runtime_error("bench: mesh " + relative + " is in neither " + MINKQ_BENCH_MESH_DIR + " (data/meshes.tar.xz) nor " +
                             data_dir + " (--data DIR)");
  return path;
}

namespace {

constexpr double kPi = 3.14159265358979323846;

struct P3 {
  double x, y, z;
};

// Grid topology: nu x nv vertices, vertex (i, j) = base + j * nu + i; cell (i, j) gives
// (v00, v10, v11) and (v00, v11, v01) as grid_sheet does. periodic_u closes the grid in u
// (the last column connects back to column 0).
int32_t add_grid(ref::Mesh& m, int nu, int nv, bool periodic_u) {
  const int32_t base = int32_t(m.vertex_count());
  m.xyz.resize(m.xyz.size() + 3 * size_t(nu) * nv, 0.0f);
  const int cells_u = periodic_u ? nu : nu - 1;
  for (int j = 0; j + 1 < nv; ++j)
    for (int i = 0; i < cells_u; ++i) {
      const int i1 = (i + 1) % nu;
      const int32_t v00 = base + j * nu + i, v10 = base + j * nu + i1, v01 = v00 + nu, v11 = base + (j + 1) * nu + i1;
      m.tris.insert(m.tris.end(), {v00, v10, v11, v00, v11, v01});
    }
  return base;
}

// Block of nx x ny x nz cells: every lattice vertex (interior ones too, as a tet mesh has them)
// and the surface triangles only. Vertex (i, j, k) = base + (k * (ny + 1) + j) * (nx + 1) + i.
int32_t add_block(ref::Mesh& m, int nx, int ny, int nz) {
  const int32_t base = int32_t(m.vertex_count());
  m.xyz.resize(m.xyz.size() + 3 * size_t(nx + 1) * (ny + 1) * (nz + 1), 0.0f);
  auto id = [&](int i, int j, int k) { return base + int32_t((k * (ny + 1) + j) * (nx + 1) + i); };
  // A quad a-b-c-d (counter-clockwise seen from outside) as two triangles.
  auto quad = [&](int32_t a, int32_t b, int32_t c, int32_t d) { m.tris.insert(m.tris.end(), {a, b, c, a, c, d}); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      quad(id(i, j, 0), id(i, j + 1, 0), id(i + 1, j + 1, 0), id(i + 1, j, 0));      // bottom
      quad(id(i, j, nz), id(i + 1, j, nz), id(i + 1, j + 1, nz), id(i, j + 1, nz));  // top
    }
  for (int k = 0; k < nz; ++k) {
    for (int i = 0; i < nx; ++i) {
      quad(id(i, 0, k), id(i + 1, 0, k), id(i + 1, 0, k + 1), id(i, 0, k + 1));        // y = 0
      quad(id(i, ny, k), id(i, ny, k + 1), id(i + 1, ny, k + 1), id(i + 1, ny, k));    // y = ny
    }
    for (int j = 0; j < ny; ++j) {
      quad(id(0, j, k), id(0, j, k + 1), id(0, j + 1, k + 1), id(0, j + 1, k));        // x = 0
      quad(id(nx, j, k), id(nx, j + 1, k), id(nx, j + 1, k + 1), id(nx, j, k + 1));    // x = nx
    }
  }
  return base;
}

void set(std::vector<float>& xyz, int32_t v, P3 p) {
  xyz[3 * size_t(v)] = float(p.x);
  xyz[3 * size_t(v) + 1] = float(p.y);
  xyz[3 * size_t(v) + 2] = float(p.z);
}

int at_least(double x, int lo) { return std::max(lo, int(std::lround(x))); }

// Isometric fold of a sheet coordinate w (the fold line at w0, bend radius rho): w <= w0 stays
// flat at height 0; the next pi * rho wraps a half cylinder; the rest returns flat at height
// 2 rho, running back. Returns (along, height).
std::pair<double, double> fold(double w, double w0, double rho) {
  if (w <= w0) return {w, 0.0};
  const double arc = w - w0;
  if (arc <= kPi * rho) {
    const double phi = arc / rho;
    return {w0 + rho * std::sin(phi), rho * (1 - std::cos(phi))};
  }
  return {w0 - (arc - kPi * rho), 2 * rho};
}

// Gap schedule shared by the scenes that close a gap: 4 r at s = 0 down to r / 2 at s = 1.
double closing_gap(double r, double s) { return r * (4.0 - 3.5 * s); }

struct Recipe {
  double reference_triangles;
  double margin;  // the Newton scene's query radius (particle_self_contact_margin)
  std::string text;
  // Builds the topology into mesh for resolution multiplier mult (1 = reference) and returns
  // the positions function of the phase s.
  std::function<std::function<std::vector<float>(double)>(ref::Mesh&, double mult, const std::string& data)> build;
};

std::vector<float> deform(const ref::Mesh& m, const std::function<P3(P3)>& f) {
  std::vector<float> out(m.xyz.size());
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const P3 p = f({m.xyz[3 * v], m.xyz[3 * v + 1], m.xyz[3 * v + 2]});
    set(out, int32_t(v), p);
  }
  return out;
}

// mult is a per-axis resolution factor: each midpoint subdivision doubles it.
int subdivision_levels(double mult) { return std::max(0, int(std::lround(std::log2(std::max(mult, 1.0))))); }
double subdivision_factor(double mult) { return std::ldexp(1.0, subdivision_levels(mult)); }

ref::Mesh load_subdivided(const std::string& path, double mult) {
  ref::Mesh m = ref::load_mesh(path);
  for (int l = 0, levels = subdivision_levels(mult); l < levels; ++l) m = subdivide(m);
  return m;
}

const std::map<std::string, Recipe>& recipes() {
  static const std::map<std::string, Recipe> table = {
      {"cloth_bending",
       {12, 0.35,
        "Newton's curvedSurface (12 triangles; midpoint-subdivided to scale); the part at x > 0 hinges about the "
        "y axis by 150 deg x s x min(x, 1), folding one arm onto the other",
        [](ref::Mesh& m, double mult, const std::string& data) {
          const ref::Mesh base = load_subdivided(mesh_path("newton/curvedSurface.obj", data), mult);
          m.xyz = base.xyz;
          m.tris = base.tris;
          const ref::Mesh rest = m;
          return std::function<std::vector<float>(double)>([rest](double s) {
            return deform(rest, [s](P3 p) {
              const double phi = s * (150.0 * kPi / 180.0) * std::clamp(p.x, 0.0, 1.0);
              return P3{p.x * std::cos(phi) - p.z * std::sin(phi), p.y, p.x * std::sin(phi) + p.z * std::cos(phi)};
            });
          });
        }}},
      {"cloth_hanging",
       {4096, 0.03,
        "64 x 32 grid of 0.1 cells hanging in the x-y plane; its lower half folded up behind it (isometric fold, "
        "layer gap 4r -> r/2 over the frames) and both layers waved along x (amplitude 0.15 s, wavelength 1.6)",
        [](ref::Mesh& m, double mult, const std::string&) {
          const int nu = at_least(64 * mult, 2), nv = at_least(32 * mult, 2);
          add_grid(m, nu + 1, nv + 1, false);
          const double r = 0.03 / mult;  // this instance's radius (the margin scales with the mean edge)
          return std::function<std::vector<float>(double)>([nu, nv, r](double s) {
            std::vector<float> xyz(3 * size_t(nu + 1) * (nv + 1));
            const double gap = closing_gap(r, s);
            for (int j = 0; j <= nv; ++j)
              for (int i = 0; i <= nu; ++i) {
                const double u = 6.4 * i / nu, w = 3.2 * j / nv;
                const auto [along, height] = fold(w, 1.6, gap / 2);
                const double wave = 0.15 * s * std::sin(2 * kPi * u / 1.6);
                set(xyz, j * (nu + 1) + i, {u, -along, height + wave});
              }
            return xyz;
          });
        }}},
      {"cloth_poker_cards",
       {2496, 0.0015,
        "52 cards (0.0635 x 0.0889, 4 x 6 cells) stacked 1 mm apart; card k fans out about its corner by "
        "20 deg x s x k/51 and every card bends alike (z += 0.01 s (x/0.0635)^2), so the 1 mm gaps stay",
        [](ref::Mesh& m, double mult, const std::string&) {
          const int nu = at_least(4 * mult, 1), nv = at_least(6 * mult, 1);
          for (int k = 0; k < 52; ++k) add_grid(m, nu + 1, nv + 1, false);
          return std::function<std::vector<float>(double)>([nu, nv](double s) {
            std::vector<float> xyz(3 * size_t(52) * (nu + 1) * (nv + 1));
            for (int k = 0; k < 52; ++k) {
              const double a = s * (20.0 * kPi / 180.0) * k / 51.0;
              for (int j = 0; j <= nv; ++j)
                for (int i = 0; i <= nu; ++i) {
                  const double x = 0.0635 * i / nu, y = 0.0889 * j / nv;
                  const double z = 0.001 * k + 0.01 * s * (x / 0.0635) * (x / 0.0635);
                  set(xyz, (k * (nv + 1) + j) * (nu + 1) + i, {x * std::cos(a) - y * std::sin(a), x * std::sin(a) + y * std::cos(a), z});
                }
            }
            return xyz;
          });
        }}},
      {"cloth_twist",
       {4802, 0.0035,
        "the square_cloth sheet (1.5 x 1.0 after x0.01, 49 x 49 cells) wrung: its width rolled isometrically into "
        "an Archimedean spiral about the long axis (inner radius 0.08, layer gap 4r -> r/2) and twisted about that "
        "axis by 0 -> 3 turns over the frames",
        [](ref::Mesh& m, double mult, const std::string&) {
          const int n = at_least(49 * mult, 1);
          add_grid(m, n + 1, n + 1, false);
          const double r = 0.0035 / mult;  // this instance's radius (the margin scales with the mean edge)
          return std::function<std::vector<float>(double)>([n, r](double s) {
            std::vector<float> xyz(3 * size_t(n + 1) * (n + 1));
            const double turns = 3.0 * s, r0 = 0.08, b = closing_gap(r, s) / (2 * kPi);
            for (int j = 0; j <= n; ++j) {
              const double l = 1.0 * j / n;  // arc length across the width
              const double phi = (-r0 + std::sqrt(r0 * r0 + 2 * b * l)) / b, rad = r0 + b * phi;
              for (int i = 0; i <= n; ++i) {
                const double u = 1.5 * i / n, t = phi + turns * 2 * kPi * u / 1.5;
                set(xyz, j * (n + 1) + i, {u, rad * std::cos(t), rad * std::sin(t)});
              }
            }
            return xyz;
          });
        }}},
      {"cloth_rollers",
       {9444, 0.6,
        "a strip of 320 x 15 vertices wound in a spiral of 12.7 turns (layer pitch 0.4, inner radius 1.5, "
        "uniform arc length, rows 1.0 apart along z) between two open 128-segment cylinders (radius 1); over the "
        "frames the pitch closes to 0.36, the spiral turns by 60 deg and the rollers follow the outer layer",
        [](ref::Mesh& m, double mult, const std::string&) {
          const int nu = at_least(320 * mult, 2), nv = at_least(15 * mult, 2);
          const int segs = at_least(128 * mult, 3), rings = at_least(mult, 1) + 1;
          const int32_t strip = add_grid(m, nu, nv, false);
          const int32_t cyl0 = add_grid(m, segs, rings, true);
          const int32_t cyl1 = add_grid(m, segs, rings, true);
          return std::function<std::vector<float>(double)>([=](double s) {
            std::vector<float> xyz(3 * size_t(nu * nv + 2 * segs * rings));
            const double pitch = 0.4 * (1 - 0.1 * s), r0 = 1.5, b = pitch / (2 * kPi), turns = 12.7;
            const double phi_max = turns * 2 * kPi, length = r0 * phi_max + b * phi_max * phi_max / 2;
            const double spin = s * kPi / 3, width = 14.0;
            for (int i = 0; i < nu; ++i) {
              const double l = length * i / (nu - 1);
              const double phi = (-r0 + std::sqrt(r0 * r0 + 2 * b * l)) / b, rad = r0 + b * phi;
              for (int j = 0; j < nv; ++j)
                set(xyz, strip + j * nu + i, {rad * std::cos(phi + spin), rad * std::sin(phi + spin), width * j / (nv - 1)});
            }
            const double outer = r0 + b * phi_max, gap = 0.6 * (1.5 - s);  // roller clearance 0.9 -> 0.3
            for (int c = 0; c < 2; ++c) {
              const double cx = (c == 0 ? 1 : -1) * (outer + 1.0 + gap);
              for (int k = 0; k < rings; ++k)
                for (int i = 0; i < segs; ++i) {
                  const double a = 2 * kPi * i / segs;
                  set(xyz, (c == 0 ? cyl0 : cyl1) + k * segs + i, {cx + std::cos(a), std::sin(a), width * k / (rings - 1)});
                }
            }
            return xyz;
          });
        }}},
      {"softbody_dropping_to_cloth",
       {3488, 0.02,
        "40 x 40 cloth of 0.05 cells at z = 0 and a 6 x 6 x 3 block of 0.1 cells (all lattice vertices, surface "
        "triangles) settling onto it: the cloth dents under the block (depth 0.2 s, flat under the footprint, "
        "Gaussian rim of width 0.3) and the block's bottom closes to a gap of 4r -> r/2",
        [](ref::Mesh& m, double mult, const std::string&) {
          const int n = at_least(40 * mult, 2), bx = at_least(6 * mult, 1), bz = at_least(3 * mult, 1);
          const int32_t cloth = add_grid(m, n + 1, n + 1, false);
          const int32_t block = add_block(m, bx, bx, bz);
          const double r = 0.02 / mult;
          return std::function<std::vector<float>(double)>([=](double s) {
            std::vector<float> xyz(3 * (size_t(n + 1) * (n + 1) + size_t(bx + 1) * (bx + 1) * (bz + 1)));
            const double depth = 0.2 * s, half = 0.3;
            for (int j = 0; j <= n; ++j)
              for (int i = 0; i <= n; ++i) {
                const double x = -1 + 2.0 * i / n, y = -1 + 2.0 * j / n;
                const double ox = std::max(0.0, std::fabs(x) - half), oy = std::max(0.0, std::fabs(y) - half);
                set(xyz, cloth + j * (n + 1) + i, {x, y, -depth * std::exp(-(ox * ox + oy * oy) / (0.3 * 0.3))});
              }
            const double bottom = -depth + closing_gap(r, s);
            for (int k = 0; k <= bz; ++k)
              for (int j = 0; j <= bx; ++j)
                for (int i = 0; i <= bx; ++i)
                  set(xyz, block + (k * (bx + 1) + j) * (bx + 1) + i,
                      {-half + 0.6 * i / bx, -half + 0.6 * j / bx, bottom + 0.3 * k / bz});
            return xyz;
          });
        }}},
      {"softbody_gift",
       {2528, 0.06,
        "4 soft blocks (2 x 2 x 0.8, 2 x 2 x 1 cells, lattice vertices) stacked with gaps 4r -> r/2, two closed "
        "straps of 120 x 6 vertices (0.75 wide) around the stack in the x-z and y-z planes; the stack squashes "
        "(block height x (1 - 0.15 s)) and the straps tighten (clearance 3r -> r/2, crossing 2r -> r/2 apart)",
        [](ref::Mesh& m, double mult, const std::string&) {
          const int bxy = at_least(2 * mult, 1), bz = at_least(mult, 1);
          const int around = at_least(120 * mult, 4), across = at_least(6 * mult, 2);
          std::vector<int32_t> blocks, straps;
          for (int b = 0; b < 4; ++b) blocks.push_back(add_block(m, bxy, bxy, bz));
          for (int k = 0; k < 2; ++k) straps.push_back(add_grid(m, around, across, true));
          const double r = 0.06 / mult;
          return std::function<std::vector<float>(double)>([=](double s) {
            std::vector<float> xyz(3 * (4 * size_t(bxy + 1) * (bxy + 1) * (bz + 1) + 2 * size_t(around) * across));
            const double h = 0.8 * (1 - 0.15 * s), gap = closing_gap(r, s);
            const double stack = 4 * h + 3 * gap;
            for (int b = 0; b < 4; ++b)
              for (int k = 0; k <= bz; ++k)
                for (int j = 0; j <= bxy; ++j)
                  for (int i = 0; i <= bxy; ++i)
                    set(xyz, blocks[b] + (k * (bxy + 1) + j) * (bxy + 1) + i,
                        {-1 + 2.0 * i / bxy, -1 + 2.0 * j / bxy, b * (h + gap) + h * k / bz});
            const double clearance = r * (3 - 2.5 * s), crossing = r * (2 - 1.5 * s);
            for (int k = 0; k < 2; ++k) {
              const double off = clearance + k * crossing;  // strap 1 rides over strap 0
              const double a = 1 + off, zlo = -off, zhi = stack + off;
              const double perimeter = 2 * (2 * a) + 2 * (zhi - zlo);
              for (int i = 0; i < around; ++i) {
                double t = perimeter * i / around;  // walk the rectangle (x or y, z) from (-a, zlo)
                double p, z;
                if (t < 2 * a) { p = -a + t; z = zlo; }
                else if ((t -= 2 * a) < zhi - zlo) { p = a; z = zlo + t; }
                else if ((t -= zhi - zlo) < 2 * a) { p = a - t; z = zhi; }
                else { t -= 2 * a; p = -a; z = zhi - t; }
                for (int j = 0; j < across; ++j) {
                  const double q = -0.375 + 0.75 * j / (across - 1);
                  set(xyz, straps[k] + j * around + i, k == 0 ? P3{p, q, z} : P3{q, p, z});
                }
              }
            }
            return xyz;
          });
        }}},
      {"cloth_franka",
       {12736, 0.2,
        "Newton's unisex_shirt (cm; midpoint-subdivided to scale) pressed flat front-to-back: "
        "z -> zc + (z - zc)(1 - s (1 - r / (2 x 27.5 cm))), so front and back close from 27.5 cm to r/2",
        [](ref::Mesh& m, double mult, const std::string& data) {
          const ref::Mesh base = load_subdivided(mesh_path("newton/unisex_shirt.obj", data), mult);
          m.xyz = base.xyz;
          m.tris = base.tris;
          const ref::Mesh rest = m;
          double zlo = 1e30, zhi = -1e30;
          for (size_t v = 0; v < rest.vertex_count(); ++v) {
            zlo = std::min(zlo, double(rest.xyz[3 * v + 2]));
            zhi = std::max(zhi, double(rest.xyz[3 * v + 2]));
          }
          const double zc = 0.5 * (zlo + zhi), squeeze = 1 - 0.5 * (0.2 / subdivision_factor(mult)) / (zhi - zlo);
          return std::function<std::vector<float>(double)>([rest, zc, squeeze](double s) {
            return deform(rest, [s, zc, squeeze](P3 p) { return P3{p.x, p.y, zc + (p.z - zc) * (1 - squeeze * s)}; });
          });
        }}},
  };
  return table;
}

}  // namespace

const std::vector<std::string>& procedural_scene_names() {
  static const std::vector<std::string> names = {"cloth_bending", "cloth_hanging", "cloth_poker_cards",
                                                 "cloth_twist", "cloth_rollers", "softbody_dropping_to_cloth",
                                                 "softbody_gift", "cloth_franka"};
  return names;
}

ref::Mesh subdivide(const ref::Mesh& m) {
  ref::Mesh out;
  out.xyz = m.xyz;
  std::map<std::pair<int32_t, int32_t>, int32_t> mid;
  auto midpoint = [&](int32_t a, int32_t b) {
    const auto key = std::minmax(a, b);
    const auto it = mid.find(key);
    if (it != mid.end()) return it->second;
    const int32_t id = int32_t(out.xyz.size() / 3);
    for (int k = 0; k < 3; ++k)
      out.xyz.push_back(float(0.5 * (double(m.xyz[3 * size_t(a) + k]) + double(m.xyz[3 * size_t(b) + k]))));
    mid.emplace(key, id);
    return id;
  };
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const int32_t a = m.tris[3 * t], b = m.tris[3 * t + 1], c = m.tris[3 * t + 2];
    const int32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
    out.tris.insert(out.tris.end(), {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca});
  }
  out.edges = ref::derive_edges(out.tris);
  return out;
}

SceneFrames make_scene(const std::string& name, double target_triangles, int frames, const std::string& data_dir) {
  if (frames < 1) throw std::invalid_argument("make_scene: frames must be >= 1");
  SceneFrames scene;
  scene.name = name;
  if (name == "twist_target") {
    // REFERENCES.md's twisted sheet: n x n grid on [0,1]^2, 3 turns about the u axis, r = 0.25 x
    // mean edge. Reference size n = 256 (130k triangles); frame k has 3 - 0.05 k turns.
    const double n_real = target_triangles > 0 ? std::sqrt(target_triangles / 2.0) + 1 : 256;
    const int n = std::max(2, int(std::lround(n_real)));
    scene.recipe = "REFERENCES.md's twisted sheet: " + std::to_string(n) + "^2 grid on [0,1]^2, 3 turns about the u "
                   "axis in frame 0, 3 - 0.05k turns in frame k";
    scene.mesh = ref::twisted_sheet(n, 3.0);
    for (int k = 0; k < frames; ++k) scene.frames.push_back(ref::twisted_sheet(n, 3.0 - 0.05 * k).xyz);
    scene.mean_edge = ref::mean_edge_length(scene.mesh);
    scene.radius_factor = 0.25;
    scene.reference_radius = 0.25 * ref::mean_edge_length(ref::twisted_sheet(256, 3.0));
    scene.scale = double(scene.mesh.triangle_count()) / (2.0 * 255 * 255);
    return scene;
  }
  const auto it = recipes().find(name);
  if (it == recipes().end()) throw std::invalid_argument("unknown scene '" + name + "'");
  const Recipe& recipe = it->second;
  scene.recipe = recipe.text;
  scene.reference_radius = recipe.margin;
  {  // the reference instance fixes radius / mean edge
    ref::Mesh m0;
    const auto positions = recipe.build(m0, 1.0, data_dir);
    m0.xyz = positions(0.0);
    m0.edges = ref::derive_edges(m0.tris);
    scene.radius_factor = recipe.margin / ref::mean_edge_length(m0);
  }
  const double mult = target_triangles > 0 ? std::sqrt(target_triangles / recipe.reference_triangles) : 1.0;
  const auto positions = recipe.build(scene.mesh, mult, data_dir);
  scene.mesh.edges = ref::derive_edges(scene.mesh.tris);
  for (int k = 0; k < frames; ++k) scene.frames.push_back(positions(frames == 1 ? 1.0 : double(k) / (frames - 1)));
  scene.mesh.xyz = scene.frames[0];
  scene.mean_edge = ref::mean_edge_length(scene.mesh);
  scene.scale = double(scene.mesh.triangle_count()) / recipe.reference_triangles;
  return scene;
}

const std::vector<RealMesh>& real_meshes() {
  static const std::vector<RealMesh> list = {
      {"unisex_shirt", "newton/unisex_shirt.obj"},
      {"square_cloth", "newton/square_cloth.obj"},
      {"bunny", "newton/bunny.obj"},
      {"bear", "newton/bear.obj"},
      {"multilayer_drape", "codim-ipc/multilayer_drape.obj"},
      {"skirt32K", "codim-ipc/skirt32K.obj"},
      {"tableCloth", "codim-ipc/tableCloth.obj"},
      {"card1K", "codim-ipc/card1K.obj"},
      {"square26K", "codim-ipc/square26K.obj"},
      {"cloth-ball92", "scalable-ccd/cloth-ball_frames_cloth_ball92.ply"},
      {"rod-twist3036", "scalable-ccd/rod-twist_frames_3036.ply"},
      {"armadillo-rollers326", "scalable-ccd/armadillo-rollers_frames_326.ply"},
  };
  return list;
}

std::vector<RealMesh> available_real_meshes(const std::string& data_dir) {
  std::vector<RealMesh> found;
  for (const RealMesh& m : real_meshes()) {
    if (!find_mesh(m.path, data_dir).empty()) {
      found.push_back(m);
      continue;
    }
    std::fprintf(stderr, "bench: skipped real mesh %s: %s is in neither %s nor %s (benchmark-only meshes: "
                 "../shared/data beside the repository, or --data DIR)\n",
                 m.name.c_str(), m.path.c_str(), MINKQ_BENCH_MESH_DIR, data_dir.c_str());
  }
  return found;
}

SceneFrames load_real_scene(const RealMesh& m, const std::string& data_dir) {
  SceneFrames scene;
  scene.name = m.name;
  scene.recipe = "real mesh " + m.path + " (static, one frame)";
  scene.mesh = ref::load_mesh(mesh_path(m.path, data_dir));
  scene.frames = {scene.mesh.xyz};
  scene.mean_edge = ref::mean_edge_length(scene.mesh);
  scene.radius_factor = 0.25;
  scene.reference_radius = 0.25 * scene.mean_edge;
  scene.scale = 1.0;
  return scene;
}

}  // namespace minkq::bench
