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
