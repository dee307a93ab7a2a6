// Decodes fuzzer bytes into a scene of many geometries (testing/geometry_scene_checks.h's
// GeometryScene): 2 to 5 triangle meshes, edge sets (rods) and vertex sets (particles), each
// a random soup, a small sheet (flat or tilted) or a copy of an earlier geometry (coincident,
// or shifted a little: parallel edges, exact contacts), with random kinds, SELF and
// DROP_INCIDENT, STATIC, FLOAT64 input, worlds (-1 included), groups and masks, and per-vertex
// thickness from 0 to several r (or none); then one step: none, a refit or rebuild of the whole
// scene or of one geometry (static ones included: refused), or a swept step (still, jittered,
// translated or stretched). Coordinates are multiples of 2^-16 in a unit frame, scaled by a power
// of two and offset by a whole number of scales, so that every position is dyadic and the swept
// step's positions at times k/16 are exact in double for the oracle.
#pragma once

#include <fuzzer/FuzzedDataProvider.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "geometry_scene_checks.h"

namespace minkq::fuzz {

class GeometryDecoder {
 public:
  GeometryDecoder(FuzzedDataProvider& body, FuzzedDataProvider& params) : in_(body), p_(params) {}

  GeometryScene scene() {
    GeometryScene s;
    const int count = p_.ConsumeIntegralInRange<int>(2, 5);
    scale_ = std::ldexp(1.0, p_.ConsumeIntegralInRange<int>(-8, 8));
    offset_ = double(pick(p_, {0, 0, 1, 1000, 4095}));
    s.variant = p_.ConsumeIntegral<uint32_t>();
    std::vector<std::vector<double>> unit;  // each geometry's unit-frame coordinates
    for (int g = 0; g < count; ++g) {
      ref::Geometry x;
      unit.push_back(shape(x, unit));
      rules(x);
      s.geometries.push_back(std::move(x));
    }
    s.r = radius();
    for (size_t g = 0; g < s.geometries.size(); ++g) {
      place(s.geometries[g], unit[g]);
      thickness(s.geometries[g], s.r);
    }
    s.step = GeometryStep(p_.ConsumeIntegralInRange<int>(0, 4));
    s.moving = p_.ConsumeBool() ? -1 : p_.ConsumeIntegralInRange<int>(0, count - 1);
    const int motion = p_.ConsumeIntegralInRange<int>(0, 4);
    for (size_t g = 0; g < s.geometries.size(); ++g) s.moved.push_back(move(s.geometries[g], step_moves(s, g), motion));
    s.label = label_ + "r " + fmt_g(s.r) + ", step " + std::to_string(int(s.step)) + " of " + std::to_string(s.moving) +
              ", motion " + std::to_string(motion);
    return s;
  }

 private:
  static constexpr int kMaxTriangles = 16;

  template <class T>
  static T pick(FuzzedDataProvider& from, std::initializer_list<T> options) {
    return *(options.begin() + from.ConsumeIntegralInRange<size_t>(0, options.size() - 1));
  }
  // A unit-frame coordinate: a multiple of 2^-16 in [0, 1), or of 2^-8 (coarse: more ties).
  double unit(bool coarse) {
    return coarse ? in_.ConsumeIntegral<uint8_t>() / 256.0 : in_.ConsumeIntegral<uint16_t>() / 65536.0;
  }

  // The geometry's topology and unit-frame positions: a soup, a sheet, or a copy.
  std::vector<double> shape(ref::Geometry& x, const std::vector<std::vector<double>>& earlier) {
    const int type = in_.ConsumeIntegralInRange<int>(0, 2);  // mesh, rods, particles
    const int how = in_.ConsumeIntegralInRange<int>(0, earlier.empty() ? 1 : 2);
    std::vector<double> u;
    ref::Mesh& m = x.mesh;
    if (how == 2) {  // a copy of an earlier geometry's positions, shifted by 0 or a little
      const std::vector<double>& from = earlier[in_.ConsumeIntegralInRange<size_t>(0, earlier.size() - 1)];
      const double shift[3] = {pick(in_, {0.0, 0.0, 0x1p-8, 0x1p-12}), pick(in_, {0.0, 0x1p-10}),
                               pick(in_, {0.0, 0.0, 0x1p-6, -0x1p-9})};
      for (size_t i = 0; i < from.size(); ++i) u.push_back(from[i] + shift[i % 3]);
      label_ += "copy ";
    } else if (how == 1) {  // an nx x ny sheet in a square of side `size`, tilted or flat
      const int nx = in_.ConsumeIntegralInRange<int>(2, 4), ny = in_.ConsumeIntegralInRange<int>(2, 4);
      const double x0 = unit(true), y0 = unit(true), z0 = unit(true), size = pick(in_, {0.25, 0.5, 1.0});
      const double tilt = pick(in_, {0.0, 0.0, 0.125, -0.5});
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const double a = size * i / 4.0, b = size * j / 4.0;
          u.insert(u.end(), {x0 + a, y0 + b, z0 + tilt * a});
        }
      for (int j = 0; j + 1 < ny; ++j)
        for (int i = 0; i + 1 < nx; ++i) {
          const int32_t v = j * nx + i;
          m.tris.insert(m.tris.end(), {v, v + 1, v + nx + 1, v, v + nx + 1, v + nx});
        }
      label_ += "sheet ";
    } else {  // a soup: random vertices and triangles among them (repeated indices allowed)
      const bool coarse = in_.ConsumeBool();
      const int nv = in_.ConsumeIntegralInRange<int>(1, 12);
      for (int i = 0; i < 3 * nv; ++i) u.push_back(unit(coarse));
      const int nt = in_.ConsumeIntegralInRange<int>(0, 8);
      for (int i = 0; i < 3 * nt; ++i) m.tris.push_back(in_.ConsumeIntegralInRange<int32_t>(0, nv - 1));
      label_ += "soup ";
    }
    const int32_t nv = int32_t(u.size() / 3);
    if (how == 2) m.tris.clear();
    if (how == 2 && type == 0) {  // a copy gets the triangles of a fan over its vertices
      for (int32_t v = 1; v + 1 < nv && v < kMaxTriangles; ++v) m.tris.insert(m.tris.end(), {0, v, v + 1});
    }
    if (int32_t(m.tris.size() / 3) > kMaxTriangles) m.tris.resize(3 * kMaxTriangles);
    m.xyz.assign(u.size(), 0.0f);
    if (type == 0 && in_.ConsumeBool()) {  // explicit edges: derived plus extra, repeated or zero-length ones
      m.edges = ref::derive_edges(m.tris);
      for (int e = in_.ConsumeIntegralInRange<int>(0, 3); e > 0; --e)
        m.edges.insert(m.edges.end(), {in_.ConsumeIntegralInRange<int32_t>(0, nv - 1),
                                       in_.ConsumeIntegralInRange<int32_t>(0, nv - 1)});
    } else if (type == 1) {  // rods: a polyline and a few random edges, no triangles
      for (int32_t v = 0; v + 1 < nv; ++v) m.edges.insert(m.edges.end(), {v, v + 1});
      for (int e = in_.ConsumeIntegralInRange<int>(0, 3); e > 0; --e)
        m.edges.insert(m.edges.end(), {in_.ConsumeIntegralInRange<int32_t>(0, nv - 1),
                                       in_.ConsumeIntegralInRange<int32_t>(0, nv - 1)});
      m.tris.clear();
    } else if (type == 2) {
      m.tris.clear();
    }
    label_ += type == 0 ? "mesh, " : type == 1 ? "rods, " : "particles, ";
    return u;
  }

  // Kinds, SELF and DROP_INCIDENT, STATIC, FLOAT64, world, group and mask.
  void rules(ref::Geometry& x) {
    const uint32_t k = in_.ConsumeIntegralInRange<uint32_t>(1, 15);
    x.kinds = (k & 3u) | ((k & 12u) << 2);
    const uint8_t f = in_.ConsumeIntegral<uint8_t>();
    x.flags = (f & 3u) | ((f & 0x30) == 0x30 ? uint32_t(MINKQ_GEOMETRY_STATIC) : 0u) |
              ((f & 0xC0) == 0xC0 ? uint32_t(MINKQ_GEOMETRY_FLOAT64) : 0u);
    x.world = pick(in_, {0, 0, 0, 1, 2, -1, -1});
    const uint8_t gm = in_.ConsumeIntegral<uint8_t>();
    x.group = (gm & 0x80) ? uint32_t(in_.ConsumeIntegral<uint8_t>()) : 1u << (gm % 3);
    x.mask = (gm & 0x40) ? uint32_t((gm >> 3) & 7) : ~0u;
  }

  // Unit frame -> the geometry's positions: (u + offset) * scale, exact in double; floats are
  // that rounded once; FLOAT64 adds a multiple of 2^-36 scales (detail below the float spacing).
  void place(ref::Geometry& x, const std::vector<double>& u) {
    std::vector<double> xyz(u.size());
    for (size_t i = 0; i < u.size(); ++i) xyz[i] = (u[i] + offset_) * scale_;
    for (size_t i = 0; i < u.size(); ++i) x.mesh.xyz[i] = float(xyz[i]);
    if (x.flags & MINKQ_GEOMETRY_FLOAT64) {
      const int detail = in_.ConsumeIntegralInRange<int>(0, 2);  // none, small, up to a float spacing
      for (double& c : xyz)
        if (detail) c += std::ldexp(double(in_.ConsumeIntegral<int8_t>()), detail == 1 ? -36 : -24) * scale_;
      ref::set_float64(x.mesh, std::move(xyz));
    }
  }

  // The radius: 0, or a part of the unit frame (2^-12 to 1/2), in scales, rounded to float.
  float radius() {
    if (p_.ConsumeIntegralInRange<int>(0, 7) == 0) return 0.0f;
    const double r = std::ldexp(double(p_.ConsumeIntegralInRange<int>(1, 64)), -p_.ConsumeIntegralInRange<int>(7, 18));
    return float(r * scale_);
  }

  // Per-vertex thickness: none, zeros, or random multiples of up to 4 r (of 2^-6 scales at r 0).
  void thickness(ref::Geometry& x, float r) {
    const int how = in_.ConsumeIntegralInRange<int>(0, 3);
    if (how == 0) return;
    const double most = (r > 0 ? double(r) : std::ldexp(scale_, -6)) * pick(in_, {0.25, 1.0, 4.0});
    x.thickness.resize(x.mesh.vertex_count());
    for (double& t : x.thickness) t = how == 1 ? 0.0 : double(float(most * in_.ConsumeIntegral<uint8_t>() / 255.0));
  }

  // The positions after the step: unchanged unless `moves`; else by `motion`: none (a still
  // step), jitter of 2^-10 units, a translation, or up to 1/4 or 2 units per coordinate.
  ref::Mesh move(const ref::Geometry& x, bool moves, int motion) {
    ref::Mesh m;
    m.xyz = x.mesh.xyz;
    m.xyz64 = x.mesh.xyz64;
    if (!moves || motion == 0) return m;
    const double t[3] = {double(in_.ConsumeIntegral<int8_t>()), double(in_.ConsumeIntegral<int8_t>()),
                         double(in_.ConsumeIntegral<int8_t>())};
    const int e = motion == 1 ? -17 : motion == 2 ? -8 : motion == 3 ? -9 : -6;
    auto delta = [&](size_t i) {
      return std::ldexp(motion == 2 ? t[i % 3] : double(in_.ConsumeIntegral<int8_t>()), e) * scale_;
    };
    if (!m.xyz64.empty()) {
      for (size_t i = 0; i < m.xyz64.size(); ++i) m.xyz64[i] += delta(i);
      ref::set_float64(m, std::vector<double>(m.xyz64));
    } else {
      for (size_t i = 0; i < m.xyz.size(); ++i) m.xyz[i] = float(double(m.xyz[i]) + delta(i));
    }
    return m;
  }

  FuzzedDataProvider& in_;
  FuzzedDataProvider& p_;
  double scale_ = 1, offset_ = 0;
  std::string label_;
};

}  // namespace minkq::fuzz
