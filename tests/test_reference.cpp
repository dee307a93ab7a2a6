// Tests of the reference oracle (minkq_reference) itself: every other test trusts it, so it is
// checked here against hand-computed distances, dense sampling, and its own brute force.
#include "minkq_reference.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <sys/stat.h>

namespace ref = minkq::reference;

namespace {

using P = const double[3];

double pt(P p, P a, P b, P c) { return double(ref::point_triangle_distance(p, a, b, c)); }
double ss(P p0, P p1, P q0, P q1) { return double(ref::segment_segment_distance(p0, p1, q0, q1)); }

// A mesh of the repository's data/meshes.tar.xz, unpacked at configure time into the build tree
// (MINKQ_MESH_DIR). A missing file fails the test that needs it, naming the file.
std::string mesh_file(const std::string& relative) {
  const std::string path = std::string(MINKQ_MESH_DIR) + "/" + relative;
  struct stat st;
  if (stat(path.c_str(), &st) != 0)
    ADD_FAILURE() << "mesh " << path << " not found: it comes from data/meshes.tar.xz, unpacked when CMake configures";
  return path;
}

// Big-endian 32-bit words, as a binary_big_endian PLY stores them.
void put_be(std::ofstream& f, uint32_t w) {
  const char b[4] = {char(w >> 24), char(w >> 16), char(w >> 8), char(w)};
  f.write(b, 4);
}
void put_be(std::ofstream& f, float x) {
  uint32_t w;
  std::memcpy(&w, &x, 4);
  put_be(f, w);
}

}  // namespace

TEST(ReferenceDistance, PointTriangleRegions) {
  const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0};
  const double face[3] = {0.25, 0.25, 2}, vert_a[3] = {-1, -1, 0}, edge_ab[3] = {0.5, -3, 4};
  const double edge_bc[3] = {1, 1, 0}, vert_b[3] = {2, 0, 0}, on[3] = {0.2, 0.2, 0}, vert_c[3] = {0, 2, -1};
  EXPECT_DOUBLE_EQ(pt(face, a, b, c), 2.0);
  EXPECT_DOUBLE_EQ(pt(vert_a, a, b, c), std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(pt(edge_ab, a, b, c), 5.0);
  EXPECT_DOUBLE_EQ(pt(edge_bc, a, b, c), std::sqrt(0.5));
  EXPECT_DOUBLE_EQ(pt(vert_b, a, b, c), 1.0);
  EXPECT_DOUBLE_EQ(pt(vert_c, a, b, c), std::sqrt(2.0));
  EXPECT_EQ(pt(on, a, b, c), 0.0);
  EXPECT_DOUBLE_EQ(pt(face, c, b, a), 2.0);  // orientation does not matter
}

TEST(ReferenceDistance, PointTriangleDegenerate) {
  const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {2, 0, 0};  // collinear
  const double p1[3] = {1, 1, 0}, p2[3] = {3, 0, 0}, p3[3] = {-1, 0, 1}, p4[3] = {1.5, 0, 0};
  EXPECT_DOUBLE_EQ(pt(p1, a, b, c), 1.0);
  EXPECT_DOUBLE_EQ(pt(p2, a, b, c), 1.0);
  EXPECT_DOUBLE_EQ(pt(p3, a, b, c), std::sqrt(2.0));
  EXPECT_EQ(pt(p4, a, b, c), 0.0);
  const double z[3] = {0, 0, 1}, q[3] = {1, 0, 0.5};  // repeated vertex: the segment a-z
  EXPECT_DOUBLE_EQ(pt(q, a, a, z), 1.0);
  const double s[3] = {1, 2, 3}, t[3] = {1, 2, 5};  // all three vertices equal
  EXPECT_DOUBLE_EQ(pt(t, s, s, s), 2.0);
}

TEST(ReferenceDistance, SegmentSegment) {
  const double o[3] = {0, 0, 0}, x1[3] = {1, 0, 0}, x2[3] = {2, 0, 0}, mx[3] = {-1, 0, 0};
  {  // crossing at a right angle, 2 apart
    const double q0[3] = {0, -1, 2}, q1[3] = {0, 1, 2};
    EXPECT_DOUBLE_EQ(ss(mx, x1, q0, q1), 2.0);
  }
  {  // parallel, overlapping in x
    const double q0[3] = {1, 1, 0}, q1[3] = {3, 1, 0};
    EXPECT_DOUBLE_EQ(ss(o, x2, q0, q1), 1.0);
    EXPECT_DOUBLE_EQ(ss(o, x2, q1, q0), 1.0);
  }
  {  // parallel, disjoint in x
    const double q0[3] = {3, 1, 0}, q1[3] = {4, 1, 0};
    EXPECT_DOUBLE_EQ(ss(o, x1, q0, q1), std::sqrt(5.0));
  }
  {  // collinear: disjoint, then overlapping
    const double q0[3] = {3, 0, 0}, q1[3] = {4, 0, 0}, r0[3] = {0.5, 0, 0};
    EXPECT_DOUBLE_EQ(ss(o, x1, q0, q1), 2.0);
    EXPECT_EQ(ss(o, x1, r0, q1), 0.0);
  }
  {  // zero-length segments
    const double q[3] = {3, 4, 0}, r[3] = {0, 1, 0};
    EXPECT_DOUBLE_EQ(ss(o, o, q, q), 5.0);
    EXPECT_DOUBLE_EQ(ss(r, r, mx, x1), 1.0);
    EXPECT_DOUBLE_EQ(ss(mx, x1, r, r), 1.0);
  }
  {  // skew, closest point at an endpoint of the first
    const double q0[3] = {2, -1, 1}, q1[3] = {2, 1, 1};
    EXPECT_DOUBLE_EQ(ss(o, x1, q0, q1), std::sqrt(2.0));
  }
  {  // touching at a shared endpoint
    const double q1[3] = {0, 5, 7};
    EXPECT_EQ(ss(o, x1, x1, q1), 0.0);
  }
}

// Two nearly parallel segments whose lines cross just beyond both (s = -1.5e-6, t = 1 + 4e-12):
// the closed-form parameters of the textbook (bf - ce) / nn cancelled in long double and put
// the crossing inside, giving distance 0 for 3.339e23 (fuzz_differential, fuzz/RESULTS.md).
TEST(ReferenceDistance, NearlyParallelSegmentsDoNotTakeTheLinesCrossing) {
  const double z = -0x1p+126;
  const double p0[3] = {0x1.ffffeep+96, 0x1.ffffeep+96, z}, p1[3] = {0x1.fffff8p+97, 0x1.fffff8p+97, z};
  const double q0[3] = {-0x1.0c6f7ap+78, -0x1.0b60fp+78, z}, q1[3] = {0x1.ffffbcp+96, 0x1.ffffbcp+96, z};
  const double expected = 3.3392173632851924e+23;  // exact rational arithmetic: |p0 - q1|
  EXPECT_NEAR(ss(p0, p1, q0, q1), expected, 1e-12 * expected);
  EXPECT_NEAR(ss(q0, q1, p0, p1), expected, 1e-12 * expected);
}

// The distance is a minimum, so it never exceeds a sampled distance, and the best of a dense
// sample is within the sampling step times the Lipschitz constant of it.
TEST(ReferenceDistance, AgreesWithDenseSampling) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  auto rnd = [&](double* v) { for (int k = 0; k < 3; ++k) v[k] = u(rng); };
  auto dist = [](const double* a, const double* b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
  };
  const int n = 200;
  for (int trial = 0; trial < 50; ++trial) {
    double p0[3], p1[3], q0[3], q1[3], c[3];
    rnd(p0), rnd(p1), rnd(q0), rnd(q1), rnd(c);
    const double d = ss(p0, p1, q0, q1);
    double best = 1e300;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) {
        double x[3], y[3];
        for (int k = 0; k < 3; ++k)
          x[k] = p0[k] + (p1[k] - p0[k]) * i / n, y[k] = q0[k] + (q1[k] - q0[k]) * j / n;
        best = std::min(best, dist(x, y));
      }
    EXPECT_LE(d, best + 1e-12);
    EXPECT_GE(d, best - (dist(p0, p1) + dist(q0, q1)) / n);
    EXPECT_NEAR(d, ss(q1, q0, p1, p0), 1e-12);  // symmetric

    const double t = pt(q0, p0, p1, c);
    best = 1e300;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        double x[3];
        for (int k = 0; k < 3; ++k) x[k] = p0[k] + ((p1[k] - p0[k]) * i + (c[k] - p0[k]) * j) / n;
        best = std::min(best, dist(x, q0));
      }
    EXPECT_LE(t, best + 1e-12);
    EXPECT_GE(t, best - (dist(p0, p1) + dist(p0, c)) / n);
  }
}

TEST(ReferenceMesh, DeriveEdges) {
  const std::vector<int32_t> tris = {2, 1, 0, 2, 1, 3, 5, 4, 4};
  const std::vector<int32_t> want = {0, 1, 0, 2, 1, 2, 1, 3, 2, 3, 4, 4, 4, 5};
  EXPECT_EQ(ref::derive_edges(tris), want);
}

TEST(ReferenceMesh, Generators) {
  const ref::Mesh g = ref::grid_sheet(3);
  EXPECT_EQ(g.vertex_count(), 9u);
  EXPECT_EQ(g.triangle_count(), 8u);
  EXPECT_EQ(g.edge_count(), 16u);  // 12 axis-aligned + 4 diagonals
  EXPECT_EQ(ref::twisted_sheet(388, 3).triangle_count(), 299538u);
  EXPECT_EQ(ref::stacked_sheets(4, 3, 0.01).triangle_count(), 3u * 18u);
  EXPECT_EQ(ref::random_soup(10, 1, 0.1).xyz, ref::random_soup(10, 1, 0.1).xyz);
  EXPECT_NE(ref::random_soup(10, 1, 0.1).xyz, ref::random_soup(10, 2, 0.1).xyz);
  EXPECT_NEAR(ref::mean_edge_length(g), (12 * 0.5 + 4 * std::sqrt(0.5)) / 16, 1e-7);
  ref::Mesh t = g;
  ref::transform(t, 2.0, 10.0);
  EXPECT_EQ(t.xyz[3 * 8], 12.0f);
}

// The grid must find exactly the brute-force set, on every kind of scene and radius. Returns
// the number of contacts (without dropping), so callers can check the case was not empty.
// (Sizes are kept small: the brute force is O(N * M) long double distances.)
size_t expect_grid_equals_brute(const ref::Mesh& m, double r, const std::string& what) {
  size_t found = 0;
  for (bool drop : {false, true}) {
    const ref::Pairs vt = ref::vt_contacts(m, r, drop), ee = ref::ee_contacts(m, r, drop);
    EXPECT_EQ(vt, ref::vt_contacts_brute(m, r, drop)) << what << " r=" << r << " drop=" << drop;
    EXPECT_EQ(ee, ref::ee_contacts_brute(m, r, drop)) << what << " r=" << r << " drop=" << drop;
    if (!drop) found = vt.size() + ee.size();
  }
  return found;
}

TEST(ReferenceContacts, GridEqualsBruteOnSoups) {
  const ref::Mesh m = ref::random_soup(500, 1, 0.1);
  for (double r : {0.0, 1e-3, 1e-2, 5e-2}) {
    const size_t n = expect_grid_equals_brute(m, r, "soup");
    if (r > 0) EXPECT_GT(n, 3 * m.triangle_count() + m.edge_count()) << "r=" << r;  // more than self-contacts
  }
  EXPECT_GT(expect_grid_equals_brute(ref::random_soup(300, 2, 0.3), 0.03, "large triangles"), 0u);
  expect_grid_equals_brute(ref::random_soup(200, 3, 0.0), 1e-2, "point soup");  // all degenerate
  expect_grid_equals_brute(ref::random_soup(100, 4, 0.05), 10.0, "huge radius");
  ref::Mesh far = ref::random_soup(300, 5, 0.1);
  ref::transform(far, 1e3, 1e7);  // far from the origin: the float coordinates have ulp 1
  EXPECT_GT(expect_grid_equals_brute(far, 20.0, "offset soup"), 0u);
}

TEST(ReferenceContacts, GridEqualsBruteOnSheets) {
  const ref::Mesh m = ref::twisted_sheet(20, 3);
  const double h = ref::mean_edge_length(m);
  for (double f : {0.1, 0.25, 0.5, 1.0}) expect_grid_equals_brute(m, f * h, "twisted sheet");
  const ref::Mesh s = ref::stacked_sheets(12, 3, 0.0625);  // a gap exact in binary
  for (double r : {0.03, 0.0625, 0.1}) expect_grid_equals_brute(s, r, "stacked sheets");
  // The layers touch at r = gap, vertex over vertex, and not below it: each vertex meets the
  // triangles incident to the vertex straight above or below it, 3 per triangle, in 2 layer
  // pairs both ways.
  EXPECT_TRUE(ref::vt_contacts(s, 0.0624, true).empty());
  EXPECT_EQ(ref::vt_contacts(s, 0.0625, true).size(), 2u * 2u * 3u * 242u);
}

// fuzz/RESULTS.md's oracle finding: at r = 0, two edges whose long double distance is 0 (their
// coordinates mix 2^-151 with 1/4, so the computation rounds the gap away) while their boxes
// miss each other by less than that rounding. The grid's boxes must be widened by the
// distance's rounding, relative to the coordinates' size, to keep the brute force's pairs.
TEST(ReferenceContacts, GridKeepsPairsTheDistanceRoundsToTouching) {
  ref::Mesh m;
  ref::set_float64(m, {-0x1.4e3f4e3f4e3f5p-151, -0x1.000000d2e5d2ep-2, -0x1.0b590b590b59p-153,
                       0x1.ffffffba85ba8p-2, -0x1.000000f7b7f7bp-2, 0x1.1a62630320925p-54,
                       -0x1.59eb59eb59eb6p-151, 0x1.8ed98ed98ed98p-153, 0x1.9a599a599a598p-153,
                       0x1.941394139413ap-151, -0x1.8437843784378p-151, 0x1.3ee33ee33ee34p-151,
                       0x1.e333e333e333ep-151, 0x1.000000ba33ba3p-2, -0x1.01bf01bf01bfp-151,
                       0x1.fffffe0ebc0ecp-2, 0x1.fffffe8034803p-3, -0x1.1a626392e7221p-54});
  m.tris = {0, 1, 3, 0, 3, 2, 2, 3, 5, 2, 5, 4};
  m.edges = ref::derive_edges(m.tris);
  EXPECT_GT(expect_grid_equals_brute(m, 0.0, "sub-float coordinates at r = 0"), 0u);
}

TEST(ReferenceContacts, DropIncidentAndClosedBound) {
  // Unit square: triangles (0,1,3), (0,3,2); edges 01 02 03 13 23. At r = 1 every pair is a
  // contact (distance <= r, the bound included); the opposite sides are exactly 1 apart.
  const ref::Mesh g = ref::grid_sheet(2);
  EXPECT_EQ(ref::vt_contacts(g, 1.0, false).size(), 8u);
  EXPECT_EQ(ref::vt_contacts(g, 1.0, true), (ref::Pairs{{1, 1}, {2, 0}}));  // the corner off each triangle
  EXPECT_EQ(ref::ee_contacts(g, 1.0, false).size(), 10u);
  EXPECT_EQ(ref::ee_contacts(g, 1.0, true), (ref::Pairs{{0, 4}, {1, 3}}));  // 01-23 and 02-13
  EXPECT_TRUE(ref::ee_contacts(g, 0.99, true).empty());
}

TEST(ReferenceLoad, ObjAndPly) {
  const ref::Mesh bear = ref::load_mesh(mesh_file("newton/bear.obj"));
  EXPECT_EQ(bear.vertex_count(), 1986u);
  EXPECT_EQ(bear.triangle_count(), 3968u);
  EXPECT_EQ(bear.edges, ref::derive_edges(bear.tris));
  const ref::Mesh arma = ref::load_mesh(mesh_file("scalable-ccd/armadillo-rollers_frames_326.ply"));  // little-endian doubles
  EXPECT_EQ(arma.vertex_count(), 12135u);
  EXPECT_EQ(arma.triangle_count(), 24242u);
  EXPECT_GT(ref::mean_edge_length(arma), 0.0);
}

TEST(ReferenceLoad, BigEndianPly) {
  // As the Scalable-CCD frames store them: big-endian floats, a uchar-counted int list, and
  // a quad (split into a fan).
  const std::string path = testing::TempDir() + "minkq_reference_big_endian.ply";
  const float xyz[12] = {0.5f, -1.25f, 3.0f, 1e7f, 2.0f, -0.0f, 1.5f, 1.5f, 1e-7f, -4.0f, 0.25f, 8.0f};
  {
    std::ofstream f(path, std::ios::binary);
    f << "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
         "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
    for (float x : xyz) put_be(f, x);
    f.put(char(3));
    for (uint32_t i : {0u, 1u, 2u}) put_be(f, i);
    f.put(char(4));
    for (uint32_t i : {0u, 2u, 3u, 1u}) put_be(f, i);
  }
  const ref::Mesh m = ref::load_mesh(path);
  std::remove(path.c_str());
  EXPECT_EQ(m.xyz, std::vector<float>(xyz, xyz + 12));
  EXPECT_EQ(m.tris, (std::vector<int32_t>{0, 1, 2, 0, 2, 3, 0, 3, 1}));
}

TEST(ReferenceLoad, OffPolygonsAreFanTriangulated) {
  const std::string path = testing::TempDir() + "minkq_reference_quad.off";
  {
    std::ofstream f(path);
    f << "OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 0.1\n4 0 1 2 3\n3 0 1 4\n";
  }
  const ref::Mesh q = ref::load_mesh(path);
  EXPECT_EQ(q.xyz, (std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5f, 0.5f, 0.1f}));
  EXPECT_EQ(q.tris, (std::vector<int32_t>{0, 1, 2, 0, 2, 3, 0, 1, 4}));
  EXPECT_EQ(q.edges, ref::derive_edges(q.tris));
  EXPECT_EQ(ref::load_mesh(path, true).xyz64[14], 0.1);
  {
    std::ofstream f(path);
    f << "OFF\n3 1 0\n0 0 0\n1 0 0\n1 1 0\n3 0 1 7\n";  // a vertex out of range
  }
  EXPECT_THROW(ref::load_mesh(path), std::runtime_error);
  {
    std::ofstream f(path);
    f << "OFF\n3 2 0\n0 0 0\n1 0 0\n1 1 0\n3 0 1 2\n";  // a face missing
  }
  EXPECT_THROW(ref::load_mesh(path), std::runtime_error);
  std::remove(path.c_str());
}

TEST(ReferenceLoad, AsciiPlyAndErrors) {
  const std::string path = testing::TempDir() + "minkq_reference_quad.ply";
  {
    std::ofstream f(path);
    f << "ply\nformat ascii 1.0\ncomment a unit quad\nelement vertex 4\nproperty float x\nproperty float y\n"
         "property float z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0 4\n4 0 1 2 3\n";
  }
  const ref::Mesh q = ref::load_mesh(path);
  EXPECT_EQ(q.xyz, (std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}));
  EXPECT_EQ(q.tris, (std::vector<int32_t>{0, 1, 2, 0, 2, 3}));
  std::remove(path.c_str());
  EXPECT_THROW(ref::load_mesh("/nonexistent/mesh.obj"), std::runtime_error);
  const std::string bad = testing::TempDir() + "minkq_reference_bad.ply";
  {
    std::ofstream f(bad);
    f << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
         "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n3 0 0 7\n";
  }
  EXPECT_THROW(ref::load_mesh(bad), std::runtime_error);
  std::remove(bad.c_str());
}

// ---- Scenes of many geometries ----------------------------------------------------------------
namespace {

const ref::Kind kKinds[] = {ref::Kind::VT, ref::Kind::EE, ref::Kind::VV, ref::Kind::EV};
constexpr uint32_t kAllKinds = ref::kKindVT | ref::kKindEE | ref::kKindVV | ref::kKindEV;

ref::Geometry geometry(ref::Mesh mesh, uint32_t kinds = kAllKinds, uint32_t flags = ref::kSelf | ref::kDropIncident) {
  ref::Geometry g;
  g.mesh = std::move(mesh);
  g.kinds = kinds;
  g.flags = flags;
  return g;
}

ref::Mesh points(std::vector<float> xyz) {
  ref::Mesh m;
  m.xyz = std::move(xyz);
  return m;
}

// A sheet of n x n vertices moved by (dx, dy, dz).
ref::Mesh moved_sheet(int n, double dx, double dy, double dz) {
  ref::Mesh m = ref::grid_sheet(n);
  for (size_t v = 0; v < m.vertex_count(); ++v)
    m.xyz[3 * v] += float(dx), m.xyz[3 * v + 1] += float(dy), m.xyz[3 * v + 2] += float(dz);
  return m;
}

}  // namespace

// Thickness adds to the reach exactly (binary fractions), the bound included; worlds, groups,
// masks, kinds and SELF decide which pairs are looked for at all.
TEST(ReferenceGeometries, ReachAndRulesByHand) {
  std::vector<ref::Geometry> two = {geometry(points({0, 0, 0})), geometry(points({1, 0, 0}))};
  two[0].thickness = {0.25};
  two[1].thickness = {0.125};
  EXPECT_EQ(ref::geometry_contacts(two, ref::Kind::VV, 0.625), (ref::Pairs{{0, 1}}));
  EXPECT_TRUE(ref::geometry_contacts(two, ref::Kind::VV, 0.624).empty());
  const auto m = ref::measure_pairs(two, ref::Kind::VV, {{0, 1}}, 0.5);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(double(m[0].distance), 1.0);
  EXPECT_EQ(m[0].reach, 0.875);
  EXPECT_EQ(m[0].scale, 1.0);
  // A triangle's thickness is its thickest vertex's, wherever that is.
  ref::Mesh tri = points({0, 0, 0, 1, 0, 0, 0, 1, 0});
  tri.tris = {0, 1, 2};
  std::vector<ref::Geometry> over = {geometry(tri), geometry(points({0.25f, 0.25f, 0.5f}))};
  over[0].thickness = {0, 0, 0.25};
  over[1].thickness = {0.25};
  EXPECT_EQ(ref::geometry_contacts(over, ref::Kind::VT, 0.0), (ref::Pairs{{3, 0}}));
  over[0].thickness = {0, 0, 0.125};
  EXPECT_TRUE(ref::geometry_contacts(over, ref::Kind::VT, 0.0).empty());

  // Four particles at one point: worlds 0, 1, -1, and 0 again in another group.
  std::vector<ref::Geometry> g;
  for (int32_t world : {0, 1, -1, 0}) {
    g.push_back(geometry(points({0, 0, 0}), ref::kKindVV));
    g.back().world = world;
  }
  g[3].group = 2, g[3].mask = 2;  // passes only its own group's mask; the others' group 1 fails it
  EXPECT_EQ(ref::geometry_contacts(g, ref::Kind::VV, 0.0), (ref::Pairs{{0, 2}, {1, 2}}));
  g[3].mask = 1;  // now each passes the other's mask (group 2 & mask ~0, group 1 & mask 1)
  EXPECT_EQ(ref::geometry_contacts(g, ref::Kind::VV, 0.0), (ref::Pairs{{0, 2}, {0, 3}, {1, 2}, {2, 3}}));
  g[2].kinds = ref::kKindVT;  // takes no part in VV
  EXPECT_EQ(ref::geometry_contacts(g, ref::Kind::VV, 0.0), (ref::Pairs{{0, 3}}));
  EXPECT_EQ(ref::not_allowed(g, ref::Kind::VV, {{0, 3}, {0, 1}, {3, 0}, {0, 2}, {0, 9}}),
            (ref::Pairs{{0, 1}, {3, 0}, {0, 2}, {0, 9}}));

  // SELF and DROP_INCIDENT act within a geometry only: a unit square (grid_sheet(2)) against
  // itself, then beside a copy of itself one unit up (exactly r away).
  std::vector<ref::Geometry> square = {geometry(ref::grid_sheet(2), kAllKinds, 0)};
  for (ref::Kind kind : kKinds) EXPECT_TRUE(ref::geometry_contacts(square, kind, 1.0).empty());
  square[0].flags = ref::kSelf | ref::kDropIncident;
  EXPECT_EQ(ref::geometry_contacts(square, ref::Kind::VT, 1.0), (ref::Pairs{{1, 1}, {2, 0}}));
  EXPECT_EQ(ref::geometry_contacts(square, ref::Kind::EV, 1.0).size(), 5u * 2u);  // each edge's 2 other vertices
  square[0].flags = ref::kSelf;
  EXPECT_EQ(ref::geometry_contacts(square, ref::Kind::VT, 1.0).size(), 8u);
  square[0].flags = 0;
  square.push_back(geometry(moved_sheet(2, 0, 0, 1), kAllKinds, 0));
  // Each square's vertices over the other's triangles: the diagonal's two ends over both, the
  // other two corners over one (the other triangle is sqrt(1.5) away), both ways: 2 * 6.
  EXPECT_EQ(ref::geometry_contacts(square, ref::Kind::VT, 1.0).size(), 12u);
  EXPECT_TRUE(ref::geometry_contacts(square, ref::Kind::VT, 0.99).empty());
  EXPECT_EQ(ref::geometry_contacts(square, ref::Kind::VV, 1.0), (ref::Pairs{{0, 4}, {1, 5}, {2, 6}, {3, 7}}));
}

// One geometry with SELF is the one-mesh oracle; cross pairs of two are those of the
// concatenated mesh between the two; thickness 0 is no thickness; the grid is the brute force.
TEST(ReferenceGeometries, AgreeWithTheOneMeshOracle) {
  const ref::Mesh sheet = ref::twisted_sheet(14, 2.0);
  const double r = 0.5 * ref::mean_edge_length(sheet);
  for (bool drop : {false, true}) {
    const std::vector<ref::Geometry> one = {
        geometry(sheet, kAllKinds, ref::kSelf | (drop ? ref::kDropIncident : 0u))};
    EXPECT_EQ(ref::geometry_contacts(one, ref::Kind::VT, r), ref::vt_contacts(sheet, r, drop)) << drop;
    EXPECT_EQ(ref::geometry_contacts(one, ref::Kind::EE, r), ref::ee_contacts(sheet, r, drop)) << drop;
  }
  // Two twisted sheets crossing each other, neither with SELF.
  ref::Mesh other = ref::twisted_sheet(11, -1.5);
  ref::transform(other, 1.0, 0.05);
  std::vector<ref::Geometry> two = {geometry(sheet, kAllKinds, 0), geometry(other, kAllKinds, 0)};
  const ref::Mesh both = ref::concatenate(two);
  EXPECT_EQ(both.edges, ref::derive_edges(both.tris));  // two meshes sharing no vertex
  const size_t nv0 = sheet.vertex_count(), nt0 = sheet.triangle_count(), ne0 = sheet.edge_count();
  EXPECT_EQ(ref::geometry_range(two, 1, 0), (std::pair<size_t, size_t>{nv0, other.vertex_count()}));
  EXPECT_EQ(ref::geometry_range(two, 1, 1), (std::pair<size_t, size_t>{nt0, other.triangle_count()}));
  EXPECT_EQ(ref::geometry_range(two, 1, 2), (std::pair<size_t, size_t>{ne0, other.edge_count()}));
  auto cross = [](const ref::Pairs& all, size_t first_a, size_t first_b) {
    ref::Pairs out;
    for (const auto& [a, b] : all)
      if ((size_t(a) < first_a) != (size_t(b) < first_b)) out.emplace_back(a, b);
    return out;
  };
  const ref::Pairs vt = ref::geometry_contacts(two, ref::Kind::VT, r), ee = ref::geometry_contacts(two, ref::Kind::EE, r);
  EXPECT_FALSE(vt.empty());
  EXPECT_FALSE(ee.empty());
  EXPECT_EQ(vt, cross(ref::vt_contacts(both, r, false), nv0, nt0));
  EXPECT_EQ(ee, cross(ref::ee_contacts(both, r, false), ne0, ne0));
  // Thickness 0 everywhere is no thickness; the grid equals the brute force, for every kind.
  for (ref::Geometry& g : two) g.flags = ref::kSelf | ref::kDropIncident;
  std::vector<ref::Geometry> zero = two;
  for (ref::Geometry& g : zero) g.thickness.assign(g.mesh.vertex_count(), 0.0);
  for (ref::Kind kind : kKinds) {
    const ref::Pairs plain = ref::geometry_contacts(two, kind, r);
    EXPECT_FALSE(plain.empty());
    EXPECT_EQ(ref::geometry_contacts(zero, kind, r), plain);
    EXPECT_EQ(ref::geometry_contacts_brute(two, kind, r), plain);
  }
  // A uniform thickness t is the radius r + 2t (binary fractions: both reaches exact).
  std::vector<ref::Geometry> thick = two;
  for (ref::Geometry& g : thick) g.thickness.assign(g.mesh.vertex_count(), 1.0 / 128);
  for (ref::Kind kind : kKinds)
    EXPECT_EQ(ref::geometry_contacts(thick, kind, 1.0 / 64), ref::geometry_contacts(two, kind, 1.0 / 32));
}

// The grid equals the brute force on mixed scenes: random thickness up to several r, worlds,
// groups and masks, particles, rods and meshes, double input, SELF on some.
TEST(ReferenceGeometries, GridEqualsBruteOnMixedScenes) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 4; ++trial) {
    std::vector<ref::Geometry> scene;
    for (int k = 0; k < 6; ++k) {
      ref::Mesh m = ref::random_soup(40, 100 * trial + k, 0.15);
      if (k % 3 == 1) m.tris.clear();  // rods: the soup's edges only
      if (k % 3 == 2) m.tris.clear(), m.edges.clear();  // particles
      if (k == 4) {
        std::vector<double> xyz(m.xyz.begin(), m.xyz.end());
        for (double& x : xyz) x += 1e-9 * u(rng);
        ref::set_float64(m, std::move(xyz));
      }
      ref::Geometry g = geometry(std::move(m), kAllKinds, (k % 2 ? ref::kSelf : 0u) | ref::kDropIncident);
      g.world = int32_t(rng() % 3) - 1;
      g.group = 1u << (rng() % 3);
      g.mask = uint32_t(rng() % 8);
      if (k != 3) g.thickness.resize(g.mesh.vertex_count());
      for (double& t : g.thickness) t = u(rng) < 0.3 ? 0.0 : 0.05 * u(rng);
      scene.push_back(std::move(g));
    }
    for (ref::Kind kind : kKinds) {
      const ref::Pairs grid = ref::geometry_contacts(scene, kind, 0.01);
      EXPECT_EQ(grid, ref::geometry_contacts_brute(scene, kind, 0.01)) << "trial " << trial;
      EXPECT_TRUE(ref::not_allowed(scene, kind, grid).empty());
      for (const ref::PairMeasure& m : ref::measure_pairs(scene, kind, grid, 0.01)) EXPECT_LE(m.distance, m.reach);
    }
  }
}

TEST(ReferenceGeometries, EdgesRangesAndRefusals) {
  // A VT-only geometry derives no edges (the C API's rule); given edges are kept.
  std::vector<ref::Geometry> g = {geometry(ref::grid_sheet(3), ref::kKindVT), geometry(ref::grid_sheet(2))};
  g[0].mesh.edges.clear();
  g[1].mesh.edges.clear();
  EXPECT_TRUE(ref::geometry_edges(g[0]).empty());
  EXPECT_EQ(ref::geometry_edges(g[1]), ref::derive_edges(g[1].mesh.tris));
  const ref::Mesh all = ref::concatenate(g);
  EXPECT_EQ(all.vertex_count(), 13u);
  EXPECT_EQ(all.edges, (std::vector<int32_t>{9, 10, 9, 11, 9, 12, 10, 12, 11, 12}));
  EXPECT_EQ(ref::geometry_range(g, 1, 2), (std::pair<size_t, size_t>{0, 5}));
  EXPECT_THROW(ref::geometry_range(g, 2, 0), std::invalid_argument);
  auto refused = [&](auto change) {
    std::vector<ref::Geometry> bad = g;
    change(bad[1]);
    try {
      ref::geometry_contacts(bad, ref::Kind::VT, 0.1);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what()).find("geometry 1: ") != std::string::npos;
    }
    return false;
  };
  EXPECT_TRUE(refused([](ref::Geometry& x) { x.thickness = {0.1}; }));
  EXPECT_TRUE(refused([](ref::Geometry& x) { x.thickness = {0, 0, NAN, 0}; }));
  EXPECT_TRUE(refused([](ref::Geometry& x) { x.thickness = {0, 0, -1, 0}; }));
  EXPECT_TRUE(refused([](ref::Geometry& x) { x.world = -2; }));
  EXPECT_TRUE(refused([](ref::Geometry& x) { x.kinds = 0; }));
  EXPECT_TRUE(refused([](ref::Geometry& x) { x.flags = 64; }));
  EXPECT_TRUE(refused([](ref::Geometry& x) { x.mesh.tris[4] = 4; }));
  EXPECT_THROW(ref::geometry_contacts({}, ref::Kind::VT, 0.1), std::invalid_argument);
}
