// Decodes fuzzer bytes into structured scenes (FuzzedDataProvider: every byte string is a
// valid scene, and small mutations make small changes). Scenes are built in a unit frame from
// quantized coordinates (so coincident points, equal coordinates and exactly parallel edges
// are common), then scaled and offset in double and rounded to float:
//   - random triangle soups;
//   - cloth-like sheets: flat, twisted, folded over onto themselves, or stacked at a gap;
//   - clusters of coincident or nearly coincident vertices with triangles among them;
//   - degenerate triangles (repeated vertices, collinear, points), zero-length edges,
//     translated copies (parallel edges), extra explicit edges;
//   - scales 2^-8..2^8 and 10^-3..10^3, offsets 1e3..1e7 (per axis or shared);
//   - radii from 1e-9 to 1e3 of the scene size, 0, multiples of the mean edge, and exactly a
//     gap or a vertex distance in float, a few ulps either side;
//   - optionally moved positions, for a refit;
//   - rarely, coordinates near FLT_MAX (no Embree comparison there: Embree drops them);
//   - a quarter of the mesh scenes float64 input (MINKQ_SCENE_FLOAT64): the doubles the float
//     scene was rounded from, those plus sub-ulp noise, halfway ties, or doubles that are floats;
//   - a third of them a swept step: zero motion, jitter, a part still and the rest flying through
//     it (up to 1000 scene sizes), the whole scene translated, a part still and the rest stretched.
// Sizes stay small (<= 96 vertices, <= 64 triangles) so that a campaign checks many scenes.
#pragma once

#include <fuzzer/FuzzedDataProvider.h>

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <string>
#include <vector>

#include "scene_checks.h"

namespace minkq::fuzz {

constexpr int kMaxVertices = 96;
constexpr int kMaxTriangles = 64;

// Two streams: `params` (the input's last bytes) picks the scene's kind, scale, offset, radius
// and options; `body` (the rest) gives the geometry. Parameters thus never starve when a long
// scene uses up the body, and mutations of either part change one aspect at a time.
class SceneDecoder {
 public:
  SceneDecoder(FuzzedDataProvider& body, FuzzedDataProvider& params) : in_(body), p_(params) {}

  MeshScene mesh() {
    MeshScene s;
    // The extensions (float64 input, a swept step) are chosen by the parameter block's first
    // bytes: ConsumeBytes takes them from its front, where the other parameters (read from its
    // back) reach only in a scene that uses all 32. So an input decodes to the same float
    // scene as before they existed; these bytes then make a quarter of the scenes float64 and
    // a third swept (see extend()).
    const std::vector<uint8_t> ext = p_.ConsumeBytes<uint8_t>(3);
    const int kind = p_.ConsumeIntegralInRange<int>(0, 7);
    switch (kind) {
      case 0: soup(); break;
      case 1: sheet(); break;
      case 2: cluster(); break;
      case 3: degenerate(); break;
      case 4: sheet(); soup(); break;
      case 5: sheet(); cluster(); break;
      case 6: soup(); degenerate(); break;
      default: stacked(); break;
    }
    if (tris_.empty()) soup();
    trim();
    snaps();
    transform();  // fills xyz_ (float) from unit_
    s.xyz = xyz_;
    s.xyz64 = xyz64_;  // kept for float64 scenes only (extend)
    s.tris = tris_;
    s.edges = edges();
    s.label = label_;
    s.r = radius(s.xyz);
    // At radii beyond a quarter of the scene nearly every pair is a candidate: the first 12
    // triangles say as much as 64 would, at a fraction of the checking cost.
    if (!(s.r <= 0.25 * scale_) && s.tris.size() > 36) shrink(s, 12);
    s.drop_incident = p_.ConsumeBool();
    s.moved = moved(s.xyz, s.xyz64, s.moved64);
    s.variant = p_.ConsumeIntegral<uint32_t>();
    extend(s, ext);
    s.label += " r=" + fmt_g(s.r);
    return s;
  }

  BoxScene boxes() {
    BoxScene s;
    const int nb = in_.ConsumeIntegralInRange<int>(1, 40);
    const double size = pick({1.0, 0.3, 0.05, 0.0});
    for (int i = 0; i < nb; ++i) {
      const V c = point();
      V e = {unit() * size, unit() * size, unit() * size};
      if (in_.ConsumeIntegralInRange<int>(0, 7) == 0) e[in_.ConsumeIntegralInRange<int>(0, 2)] = 0;  // flat
      unit_.push_back({c[0] - e[0] / 2, c[1] - e[1] / 2, c[2] - e[2] / 2});
      unit_.push_back({c[0] + e[0] / 2, c[1] + e[1] / 2, c[2] + e[2] / 2});
    }
    s.shape = minkq_shape(p_.ConsumeIntegralInRange<int>(0, 2));
    const int nq = in_.ConsumeIntegralInRange<int>(1, 24);
    const double reach = pick({0.3, 1.0, 0.02, 0.0});
    for (int q = 0; q < nq; ++q) {
      V a = point();
      if (in_.ConsumeIntegralInRange<int>(0, 5) == 0) a = unit_[in_.ConsumeIntegralInRange<size_t>(0, unit_.size() - 1)];
      V b = {a[0] + (unit() - 0.5) * reach, a[1] + (unit() - 0.5) * reach, a[2] + (unit() - 0.5) * reach};
      if (in_.ConsumeIntegralInRange<int>(0, 5) == 0) {  // parallel to a coordinate plane
        const int k = in_.ConsumeIntegralInRange<int>(0, 2);
        b[k] = a[k];
      }
      if (s.shape == MINKQ_SHAPE_BOX)
        for (int k = 0; k < 3; ++k)
          if (a[k] > b[k]) std::swap(a[k], b[k]);
      unit_.push_back(a);
      if (s.shape != MINKQ_SHAPE_SPHERE) unit_.push_back(b);
    }
    label_ = std::string("boxes/") + (s.shape == 0 ? "spheres " : s.shape == 1 ? "capsules " : "boxes ");
    transform();
    const size_t box_floats = 6 * size_t(nb);
    s.boxes.assign(xyz_.begin(), xyz_.begin() + box_floats);
    for (size_t i = box_floats, q = 0; i < xyz_.size(); i += 3, ++q) {
      std::vector<float>& to = (s.shape == MINKQ_SHAPE_SPHERE || q % 2 == 0) ? s.first : s.second;
      to.insert(to.end(), xyz_.begin() + i, xyz_.begin() + i + 3);
    }
    s.r = s.shape == MINKQ_SHAPE_BOX ? 0.0f : radius(s.boxes);
    if (p_.ConsumeIntegralInRange<int>(0, 2) == 0) {
      const double amount = pick(p_, {0.01, 0.3, 1e-6}) * scale_;
      s.moved = s.boxes;
      for (size_t i = 0; i < s.moved.size(); i += 6)
        for (int k = 0; k < 3; ++k) {
          const double shift = (unit() - 0.5) * amount;
          float lo = to_float(s.moved[i + k] + shift), hi = to_float(s.moved[i + 3 + k] + shift);
          if (lo > hi) std::swap(lo, hi);
          s.moved[i + k] = lo;
          s.moved[i + 3 + k] = hi;
        }
      for (float x : s.moved)
        if (!std::isfinite(x)) s.moved.clear();
    }
    s.variant = p_.ConsumeIntegral<uint32_t>();
    s.label = label_ + " r=" + fmt_g(s.r);
    return s;
  }

 private:
  using V = std::array<double, 3>;

  double unit() { return in_.ConsumeIntegral<uint16_t>() / 65535.0; }
  V point() { return {unit(), unit(), unit()}; }
  template <class T>
  static T pick(FuzzedDataProvider& from, std::initializer_list<T> options) {
    return *(options.begin() + from.ConsumeIntegralInRange<size_t>(0, options.size() - 1));
  }
  template <class T>
  T pick(std::initializer_list<T> options) { return pick(in_, options); }
  int32_t add(const V& p) {
    unit_.push_back(p);
    return int32_t(unit_.size() - 1);
  }
  void triangle(int32_t a, int32_t b, int32_t c) { tris_.insert(tris_.end(), {a, b, c}); }
  bool full() const { return int(unit_.size()) >= max_vertices_ - 3 || int(tris_.size() / 3) >= max_triangles_; }

  void soup() {
    label_ += "soup ";
    const int n = in_.ConsumeIntegralInRange<int>(1, 16);
    const double size = pick({1.0, 0.3, 0.1, 0.01});
    for (int t = 0; t < n && !full(); ++t) {
      const V c = point();
      int32_t v[3];
      for (int32_t& i : v) i = add({c[0] + (unit() - 0.5) * size, c[1] + (unit() - 0.5) * size, c[2] + (unit() - 0.5) * size});
      triangle(v[0], v[1], v[2]);
    }
  }

  // An nx x ny grid on [0,1]^2, flat, twisted about the u axis, or folded over onto itself.
  void sheet() {
    const int nx = in_.ConsumeIntegralInRange<int>(2, 6), ny = in_.ConsumeIntegralInRange<int>(2, 6);
    const int how = in_.ConsumeIntegralInRange<int>(0, 2);
    const double turns = pick({0.5, 1.0, 2.0, 3.0});
    const double fold_at = 0.2 + 0.6 * unit(), gap = pick({0.01, 0.05, 0.2, 1e-4});
    const double tilt = (unit() - 0.5) * 0.2;
    label_ += how == 0 ? "sheet " : how == 1 ? "twisted " : "folded ";
    const int32_t base = int32_t(unit_.size());
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const double u = double(i) / (nx - 1), v = double(j) / (ny - 1);
        V p = {u, v, tilt * u};
        if (how == 1) {
          const double t = turns * 2 * 3.14159265358979323846 * u;
          p = {u, (v - 0.5) * std::cos(t), (v - 0.5) * std::sin(t)};
        } else if (how == 2 && u > fold_at) {
          p = {2 * fold_at - u, v, gap};  // folded back over the sheet at height `gap`
          gap_ = {base + j * nx + i, base + j * nx};
        }
        add(p);
      }
    grid_triangles(base, nx, ny);
  }

  // Layers of a grid stacked at a gap (aligned, shifted, or slightly rotated).
  void stacked() {
    const int nx = in_.ConsumeIntegralInRange<int>(2, 5), ny = in_.ConsumeIntegralInRange<int>(2, 5);
    const int layers = in_.ConsumeIntegralInRange<int>(2, 3);
    const double gap = pick({0.1, 0.01, 0.3, 1e-5});
    const int how = in_.ConsumeIntegralInRange<int>(0, 2);
    label_ += how == 0 ? "stacked " : how == 1 ? "stacked-shifted " : "stacked-rotated ";
    for (int k = 0; k < layers && !full(); ++k) {
      const int32_t base = int32_t(unit_.size());
      const double shift = how == 1 ? 0.5 / (nx - 1) * k : 0.0, angle = how == 2 ? 0.05 * k : 0.0;
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const double u = double(i) / (nx - 1) + shift, v = double(j) / (ny - 1);
          add({u * std::cos(angle) - v * std::sin(angle), u * std::sin(angle) + v * std::cos(angle), k * gap});
        }
      grid_triangles(base, nx, ny);
      if (k == 1) gap_ = {base, base - nx * ny};
    }
  }

  void grid_triangles(int32_t base, int nx, int ny) {
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i) {
        if (int(tris_.size() / 3) + 2 > max_triangles_) return;
        const int32_t v00 = base + j * nx + i, v10 = v00 + 1, v01 = v00 + nx, v11 = v01 + 1;
        triangle(v00, v10, v11);
        triangle(v00, v11, v01);
      }
  }

  // Several vertices at (nearly) one point, triangles among them, repeated indices allowed.
  void cluster() {
    label_ += "cluster ";
    const V c = point();
    const int k = in_.ConsumeIntegralInRange<int>(3, 10);
    const double jitter = pick({0.0, 1e-7, 1e-4, 1e-2});
    const int32_t base = int32_t(unit_.size());
    for (int i = 0; i < k && !full(); ++i)
      add({c[0] + (unit() - 0.5) * jitter, c[1] + (unit() - 0.5) * jitter, c[2] + (unit() - 0.5) * jitter});
    const int32_t count = int32_t(unit_.size()) - base;
    const int m = in_.ConsumeIntegralInRange<int>(1, 10);
    for (int t = 0; t < m && count > 0 && !full(); ++t)
      triangle(base + in_.ConsumeIntegralInRange<int32_t>(0, count - 1), base + in_.ConsumeIntegralInRange<int32_t>(0, count - 1),
               base + in_.ConsumeIntegralInRange<int32_t>(0, count - 1));
  }

  // Collinear, repeated-vertex and point triangles, and translated copies (parallel edges).
  void degenerate() {
    label_ += "degenerate ";
    const int n = in_.ConsumeIntegralInRange<int>(1, 10);
    for (int t = 0; t < n && !full(); ++t) {
      const V a = point();
      const double size = pick({0.3, 0.01, 1e-6});
      const V b = {a[0] + (unit() - 0.5) * size, a[1] + (unit() - 0.5) * size, a[2] + (unit() - 0.5) * size};
      switch (in_.ConsumeIntegralInRange<int>(0, 4)) {
        case 0: {  // collinear
          const double s = pick({0.5, 2.0, -1.0, 1e-7, 1.0});
          const int32_t ia = add(a), ib = add(b);
          triangle(ia, ib, add({a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2])}));
          break;
        }
        case 1: {  // a repeated vertex: a zero-length edge
          const int32_t ia = add(a), ib = add(b);
          triangle(ia, ia, ib);
          break;
        }
        case 2: {  // a point
          const int32_t ia = add(a);
          triangle(ia, ia, ia);
          break;
        }
        case 3: {  // a triangle and a translated copy: three pairs of parallel edges
          const V c = {a[0] + (unit() - 0.5) * size, a[1] + (unit() - 0.5) * size, a[2]};
          const V shift = {(unit() - 0.5) * size, (unit() - 0.5) * size, pick({0.0, 1e-3, 0.05})};
          const int32_t ia = add(a), ib = add(b), ic = add(c);
          triangle(ia, ib, ic);
          if (full()) break;
          triangle(add({a[0] + shift[0], a[1] + shift[1], a[2] + shift[2]}),
                   add({b[0] + shift[0], b[1] + shift[1], b[2] + shift[2]}),
                   add({c[0] + shift[0], c[1] + shift[1], c[2] + shift[2]}));
          break;
        }
        default: {  // reuses existing vertices: shared edges, slivers
          if (unit_.empty()) break;
          const size_t last = unit_.size() - 1;
          triangle(int32_t(in_.ConsumeIntegralInRange<size_t>(0, last)), int32_t(in_.ConsumeIntegralInRange<size_t>(0, last)),
                   int32_t(in_.ConsumeIntegralInRange<size_t>(0, last)));
        }
      }
    }
  }

  // Keeps the first `keep` triangles and the vertices and edges they (or the edges) still use.
  static void shrink(MeshScene& s, size_t keep) {
    s.tris.resize(3 * keep);
    std::vector<int32_t> map(s.xyz.size() / 3, -1);
    std::vector<float> xyz;
    std::vector<double> xyz64;
    auto use = [&](int32_t& v) {
      if (map[v] < 0) {
        map[v] = int32_t(xyz.size() / 3);
        xyz.insert(xyz.end(), s.xyz.begin() + 3 * size_t(v), s.xyz.begin() + 3 * size_t(v) + 3);
        if (!s.xyz64.empty())
          xyz64.insert(xyz64.end(), s.xyz64.begin() + 3 * size_t(v), s.xyz64.begin() + 3 * size_t(v) + 3);
      }
      v = map[v];
    };
    for (int32_t& v : s.tris) use(v);
    std::vector<int32_t> edges;
    for (size_t e = 0; e + 1 < s.edges.size() && edges.size() < 48; e += 2) {
      int32_t a = s.edges[e], b = s.edges[e + 1];
      use(a);
      use(b);
      edges.insert(edges.end(), {a, b});
    }
    s.xyz = std::move(xyz);
    s.xyz64 = std::move(xyz64);
    s.edges = std::move(edges);
    s.label += "(shrunk) ";
  }

  void trim() {
    if (int(tris_.size() / 3) > max_triangles_) tris_.resize(3 * size_t(max_triangles_));
  }

  // Makes some vertices coincide exactly with others.
  void snaps() {
    const int n = in_.ConsumeIntegralInRange<int>(0, 3);
    for (int i = 0; i < n && unit_.size() > 1; ++i) {
      const size_t a = in_.ConsumeIntegralInRange<size_t>(0, unit_.size() - 1);
      const size_t b = in_.ConsumeIntegralInRange<size_t>(0, unit_.size() - 1);
      unit_[a] = unit_[b];
    }
  }

  // Unit frame -> float: x * scale + offset in double, rounded once.
  void transform() {
    const int scale_kind = p_.ConsumeIntegralInRange<int>(0, 9);
    if (scale_kind < 4) scale_ = 1.0;
    else if (scale_kind < 7) scale_ = std::ldexp(1.0, p_.ConsumeIntegralInRange<int>(-8, 8));
    else scale_ = std::pow(10.0, p_.ConsumeIntegralInRange<int>(-3, 3));
    double offset[3] = {0, 0, 0};
    const int offset_kind = p_.ConsumeIntegralInRange<int>(0, 5);
    auto magnitude = [&] {
      const double m = std::pow(10.0, double(p_.ConsumeIntegralInRange<int>(3, 7)));
      const double jitter = p_.ConsumeBool() ? 1.0 : 1.0 + p_.ConsumeIntegral<uint8_t>() / 255.0;
      return (p_.ConsumeBool() ? -m : m) * jitter;
    };
    if (offset_kind == 3) {
      offset[0] = offset[1] = offset[2] = magnitude();
      label_ += "offset ";
    } else if (offset_kind == 4) {
      for (double& o : offset) o = p_.ConsumeBool() ? magnitude() : 0.0;
      label_ += "offsets ";
    } else if (offset_kind == 5 && p_.ConsumeIntegralInRange<int>(0, 3) == 0) {
      if (p_.ConsumeBool()) {
        // Near the top of the float range: no Embree comparison, definition and oracle only.
        scale_ = std::ldexp(1.0, p_.ConsumeIntegralInRange<int>(60, 126));
        for (double& o : offset) o = p_.ConsumeBool() ? std::ldexp(p_.ConsumeBool() ? 1.0 : -1.0, 126) : 0.0;
        label_ += "huge ";
      } else {
        // Near the bottom: coordinates down to subnormal, where float roundings are absolute.
        scale_ = std::ldexp(1.0, -p_.ConsumeIntegralInRange<int>(100, 140));
        label_ += "tiny ";
      }
    }
    xyz_.clear();
    xyz64_.clear();
    for (const V& p : unit_)
      for (int k = 0; k < 3; ++k) {
        xyz_.push_back(to_float(p[k] * scale_ + offset[k]));
        xyz64_.push_back(clamp(p[k] * scale_ + offset[k]));  // the same before rounding
      }
  }

  // Clamps to the finite float range (a double beyond it is NON_FINITE as float64 input).
  static double clamp(double x) { return std::min(std::max(x, -double(FLT_MAX)), double(FLT_MAX)); }
  // Rounds to float, clamping to the finite range (a double beyond it has no float value).
  static float to_float(double x) { return float(clamp(x)); }

  std::vector<int32_t> edges() {
    const int how = p_.ConsumeIntegralInRange<int>(0, 5);
    if (how < 4 || unit_.empty()) return {};  // derived by minkq
    std::vector<int32_t> e = how == 4 ? reference::derive_edges(tris_) : std::vector<int32_t>{};
    const int extra = in_.ConsumeIntegralInRange<int>(1, 12);
    const int32_t last = int32_t(unit_.size() - 1);
    for (int i = 0; i < extra; ++i) {
      const int32_t a = in_.ConsumeIntegralInRange<int32_t>(0, last);
      const int32_t b = in_.ConsumeBool() ? a : in_.ConsumeIntegralInRange<int32_t>(0, last);  // (a, a): a point
      e.insert(e.end(), {a, b});
    }
    label_ += how == 4 ? "+edges " : "edges-only ";
    return e;
  }

  float ulps(float r) {
    const int steps = p_.ConsumeIntegralInRange<int>(-3, 3);
    for (int i = 0; i < steps; ++i) r = std::nextafter(r, INFINITY);
    for (int i = 0; i > steps; --i) r = std::nextafter(r, 0.0f);
    return r;
  }

  float radius(const std::vector<float>& xyz) {
    const int how = p_.ConsumeIntegralInRange<int>(0, 6);
    const size_t n = xyz.size() / 3;
    if (how == 0 || how == 1) {  // 1e-9 .. 1e3 of the scene size (the unit frame's scale)
      const double exponent = -9.0 + 12.0 * p_.ConsumeIntegral<uint8_t>() / 255.0;
      return to_float(scale_ * std::pow(10.0, exponent));
    }
    if (how == 2) return 0.0f;
    if (how == 3 && gap_[0] >= 0 && size_t(std::max(gap_[0], gap_[1])) < n) {  // the gap, in float, +- ulps
      const float z0 = xyz[3 * size_t(gap_[0]) + 2], z1 = xyz[3 * size_t(gap_[1]) + 2];
      return ulps(std::fabs(z1 - z0));
    }
    if (how == 4 && n > 1) {  // the distance of two vertices, +- ulps
      const size_t a = p_.ConsumeIntegralInRange<size_t>(0, n - 1), b = p_.ConsumeIntegralInRange<size_t>(0, n - 1);
      double d2 = 0;
      for (int k = 0; k < 3; ++k) {
        const double d = double(xyz[3 * a + k]) - xyz[3 * b + k];
        d2 += d * d;
      }
      return ulps(to_float(std::sqrt(d2)));
    }
    if (how == 5 && !tris_.empty()) {  // a multiple of the mean edge length
      reference::Mesh m;
      m.xyz = xyz;
      m.tris = tris_;
      return to_float(reference::mean_edge_length(m) * pick(p_, {0.1, 0.25, 0.5, 1.0, 2.0, 4.0}));
    }
    return to_float(scale_ * pick(p_, {0.01, 0.05, 0.1, 0.3}));
  }

  // New positions for a refit (or none): the float ones from `xyz`, and in `out64` the same
  // moves of the doubles `xyz64` (before rounding), for a float64 scene.
  std::vector<float> moved(const std::vector<float>& xyz, const std::vector<double>& xyz64, std::vector<double>& out64) {
    out64.clear();
    if (p_.ConsumeIntegralInRange<int>(0, 2) != 0) return {};
    std::vector<float> out = xyz;
    out64 = xyz64;
    const int how = p_.ConsumeIntegralInRange<int>(0, 3);
    if (how == 3) {  // the whole scene translated: same shape, new boxes everywhere
      const double shift[3] = {unit() * scale_, unit() * scale_, unit() * scale_};
      for (size_t i = 0; i < out.size(); ++i) {
        out[i] = to_float(double(out[i]) + shift[i % 3]);
        if (i < out64.size()) out64[i] = clamp(out64[i] + shift[i % 3]);
      }
      return out;
    }
    const double amount = scale_ * (how == 0 ? 1e-6 : how == 1 ? 0.01 : 0.3);
    for (size_t i = 0; i < out.size(); ++i) {
      const double shift = (unit() - 0.5) * amount;
      out[i] = to_float(double(out[i]) + shift);
      if (i < out64.size()) out64[i] = clamp(out64[i] + shift);
    }
    for (float x : out)
      if (!std::isfinite(x)) {
        out64.clear();
        return {};
      }
    return out;
  }

  // ---- Extensions: float64 input and a swept step ---------------------------------------------

  // The float spacing at |x| (below it at the top of the float range).
  static double spacing(float x) {
    const float a = std::fabs(x);
    return a == FLT_MAX ? double(a) - double(std::nextafter(a, 0.0f)) : double(std::nextafter(a, INFINITY)) - double(a);
  }
  static std::vector<float> rounded(const std::vector<double>& d) { return std::vector<float>(d.begin(), d.end()); }

  // Makes the scene float64 input (ext[0] % 4 == 3) and gives it a swept step (ext[1] % 3 == 2).
  // Float64 input, by ext[0] / 4 % 4: the doubles the float scene was rounded from (the same
  // float geometry, sub-ulp detail wherever the offset or scale leave it); those plus a random
  // part of the float spacing on every coordinate; every coordinate halfway between two floats
  // (a tie, rounded to even) or a hair either side; or doubles that are floats (rho 0: the float
  // scene's sets). The refit positions get the same treatment.
  void extend(MeshScene& s, const std::vector<uint8_t>& ext) {
    const int e0 = ext.size() > 0 ? ext[0] : 0, e1 = ext.size() > 1 ? ext[1] : 0, e2 = ext.size() > 2 ? ext[2] : 0;
    const bool float64 = e0 % 4 == 3;
    const int detail = e0 / 4 % 4;
    if (float64) {
      auto detailed = [&](std::vector<double>& d) {
        for (double& x : d) {
          const float f = float(x);
          if (detail == 1) x = clamp(x + (unit() - 0.5) * spacing(f));
          if (detail == 2) {
            const double nudge = pick({0.0, 0.0, 0x1p-30, -0x1p-30});
            x = clamp(double(f) + (in_.ConsumeBool() ? 0.5 : -0.5) * spacing(f) * (1 + nudge));
          }
          if (detail == 3) x = double(f);
        }
      };
      detailed(s.xyz64);
      detailed(s.moved64);
      s.xyz = rounded(s.xyz64);
      if (!s.moved64.empty()) s.moved = rounded(s.moved64);
      static const char* details[] = {"float64 ", "float64-noise ", "float64-ties ", "float64-floats "};
      s.label += details[detail];
    } else {
      s.xyz64.clear();
      s.moved64.clear();
    }
    if (e1 % 3 == 2) step(s, e1 / 3, e2, float64 && detail == 3);
  }

  // A swept step from the scene's positions, by `how` % 5: none (zero motion); every coordinate
  // moved by a random part of 1e-6, 0.01, 0.3 or 3 scene sizes; a part of the vertices (by
  // index) still and the rest flying through it, from -T to +T about their place (|T| 0.1 to 1000
  // scene sizes, along an axis, a diagonal, a skew direction or a random one); the whole scene
  // translated by T, plus a little jitter; a part still and the rest moved by up to 3 scene
  // sizes each (elements stretched far past their size). `floats`: the float64 step's
  // positions stay floats (as the scene's).
  void step(MeshScene& s, int how, int e2, bool floats) {
    const size_t n = s.xyz.size();
    std::vector<double> shift0(n, 0.0), shift1(n, 0.0);
    const int motion = how % 5;
    const double amount = scale_ * std::initializer_list<double>{1e-6, 0.01, 0.3, 3.0}.begin()[how / 5 % 4];
    const double length = scale_ * std::initializer_list<double>{0.1, 1.0, 10.0, 1000.0}.begin()[how / 5 % 4];
    V dir = {1.0, 0.0, 0.0};
    switch (e2 % 4) {
      case 1: dir = {1.0, 1.0, 1.0}; break;
      case 2: dir = {0.3, -1.0, 0.55}; break;
      case 3: dir = {unit() - 0.5, unit() - 0.5, unit() - 0.5}; break;
      default: break;
    }
    const double norm = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (double& d : dir) d = norm > 0 ? d / norm : 1.0;
    const size_t still = (n / 3) * size_t(1 + (e2 / 4) % 8) / 9;  // vertices [0, still) stay
    static const char* names[] = {"still", "jitter", "fly-through", "translated", "part-still"};
    for (size_t i = 0; i < n; ++i) {
      const bool moving = i / 3 >= still;
      switch (motion) {
        case 1: shift1[i] = (unit() - 0.5) * amount; break;
        case 2:
          if (moving) shift0[i] = -length * dir[i % 3], shift1[i] = length * dir[i % 3];
          break;
        case 3: shift1[i] = length * dir[i % 3] + (unit() - 0.5) * 0.01 * scale_; break;
        case 4:
          if (moving) shift1[i] = (unit() - 0.5) * 6.0 * scale_;
          break;
        default: break;
      }
    }
    if (!s.xyz64.empty()) {
      s.swept0_64 = s.swept1_64 = s.xyz64;
      for (size_t i = 0; i < n; ++i) {
        s.swept0_64[i] = clamp(s.xyz64[i] + shift0[i]);
        s.swept1_64[i] = clamp(s.xyz64[i] + shift1[i]);
        if (floats) s.swept0_64[i] = double(float(s.swept0_64[i])), s.swept1_64[i] = double(float(s.swept1_64[i]));
      }
    } else {
      s.swept0 = s.swept1 = s.xyz;
      for (size_t i = 0; i < n; ++i) {
        s.swept0[i] = to_float(double(s.xyz[i]) + shift0[i]);
        s.swept1[i] = to_float(double(s.xyz[i]) + shift1[i]);
      }
    }
    s.label += std::string("swept-") + names[motion] + " ";
  }

  FuzzedDataProvider& in_;  // geometry
  FuzzedDataProvider& p_;   // parameters
  std::vector<V> unit_;
  std::vector<int32_t> tris_;
  std::vector<float> xyz_;
  std::vector<double> xyz64_;  // xyz_ before rounding
  std::array<int32_t, 2> gap_ = {-1, -1};
  int max_vertices_ = kMaxVertices, max_triangles_ = kMaxTriangles;
  double scale_ = 1.0;
  std::string label_;
};

}  // namespace minkq::fuzz
