// The mesh of the apps, the oracle and the tests: edges derived from triangles, double input,
// and the OBJ / PLY / OFF loaders.
#include "mesh_io.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace minkq::meshio {

std::vector<int32_t> derive_edges(const std::vector<int32_t>& tris) {
  std::vector<std::pair<int32_t, int32_t>> e;
  e.reserve(tris.size());
  for (size_t t = 0; t + 2 < tris.size(); t += 3)
    for (int k = 0; k < 3; ++k) {
      const int32_t a = tris[t + k], b = tris[t + (k + 1) % 3];
      e.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  std::vector<int32_t> out;
  out.reserve(2 * e.size());
  for (const auto& [a, b] : e) out.insert(out.end(), {a, b});
  return out;
}

double mean_edge_length(const Mesh& m) {
  const std::vector<int32_t> edges = m.edges.empty() ? derive_edges(m.tris) : m.edges;
  if (edges.empty()) return 0.0;
  double sum = 0;
  for (size_t e = 0; e < edges.size(); e += 2) {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double d = double(m.xyz[3 * size_t(edges[e]) + a]) - m.xyz[3 * size_t(edges[e + 1]) + a];
      d2 += d * d;
    }
    sum += std::sqrt(d2);
  }
  return sum / double(edges.size() / 2);
}

void set_float64(Mesh& m, std::vector<double> xyz64) {
  if (xyz64.size() % 3) throw std::invalid_argument("set_float64: xyz64 size is not a multiple of 3");
  m.xyz.assign(xyz64.begin(), xyz64.end());  // to nearest
  m.xyz64 = std::move(xyz64);
}

// ---- Loaders -------------------------------------------------------------------------------
namespace {

// A polygon's triangles, fanned from its first vertex, appended to tris (PLY and OFF faces).
void append_fan(std::vector<int32_t>& tris, const std::vector<int32_t>& poly) {
  for (size_t k = 2; k < poly.size(); ++k) tris.insert(tris.end(), {poly[0], poly[k - 1], poly[k]});
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw std::runtime_error("load_mesh: " + path + ": " + what);
}

void check_indices(const std::string& path, Mesh& m) {
  for (int32_t v : m.tris)
    if (v < 0 || size_t(v) >= m.vertex_count())
      fail(path, "face refers to vertex " + std::to_string(v) + " of " + std::to_string(m.vertex_count()));
  for (float x : m.xyz)
    if (!std::isfinite(x)) fail(path, "non-finite vertex coordinate");
  m.edges = derive_edges(m.tris);
}

// The OBJ's vertex lines ("v x y z ...") parsed as doubles, in file order (tinyobjloader's).
std::vector<double> obj_doubles(const std::string& path) {
  std::ifstream f(path);
  std::vector<double> xyz;
  std::string line;
  while (std::getline(f, line)) {
    const size_t at = line.find_first_not_of(" \t");
    if (at == std::string::npos || (line.compare(at, 2, "v ") != 0 && line.compare(at, 2, "v\t") != 0)) continue;
    const char* p = line.c_str() + at + 2;
    for (int a = 0; a < 3; ++a) {
      char* end = nullptr;
      const double x = std::strtod(p, &end);
      if (end == p) fail(path, "malformed vertex line '" + line + "'");
      xyz.push_back(x);
      p = end;
    }
  }
  return xyz;
}

Mesh load_obj(const std::string& path, bool float64) {
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  // Materials are irrelevant here; a missing .mtl only produces a warning, which is ignored.
  if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, path.c_str(), nullptr, true))
    fail(path, err.empty() ? "cannot read OBJ" : err);
  Mesh m;
  m.xyz.assign(attrib.vertices.begin(), attrib.vertices.end());
  for (const tinyobj::shape_t& s : shapes) {
    size_t at = 0;
    for (unsigned char fv : s.mesh.num_face_vertices) {
      if (fv == 3)
        for (int k = 0; k < 3; ++k) m.tris.push_back(s.mesh.indices[at + k].vertex_index);
      at += fv;  // faces under 3 vertices (if any survive triangulation) are skipped
    }
  }
  if (m.tris.empty()) fail(path, "no triangles");
  if (float64) {
    std::vector<double> xyz = obj_doubles(path);
    if (xyz.size() != m.xyz.size()) fail(path, "vertex lines and parsed vertices differ in number");
    set_float64(m, std::move(xyz));
  }
  check_indices(path, m);
  return m;
}

// A minimal PLY reader: one pass over the elements in header order; "vertex" gives x, y, z,
// "face" gives the list property vertex_indices (or vertex_index); other elements and
// properties are read and dropped.
struct PlyProperty {
  std::string name, type, count_type;  // count_type non-empty for a list
};
struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> props;
};

size_t ply_size(const std::string& path, const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  fail(path, "unknown PLY property type '" + t + "'");
}

class PlyReader {
 public:
  PlyReader(const std::string& path, std::string data, size_t at, int format)
      : path_(path), data_(std::move(data)), at_(at), format_(format) {
    if (format_ == 0) text_.str(data_.substr(at_));
  }
  // The next scalar of type t as a double (exact for every PLY type).
  double read(const std::string& t) {
    if (format_ == 0) {
      double x;
      if (!(text_ >> x)) fail(path_, "truncated or malformed ascii data");
      return x;
    }
    const size_t n = ply_size(path_, t);
    if (at_ + n > data_.size()) fail(path_, "file ends inside the binary data");
    unsigned char b[8];
    std::memcpy(b, data_.data() + at_, n);
    at_ += n;
    const bool little_host = [] { const uint16_t one = 1; return *reinterpret_cast<const unsigned char*>(&one) == 1; }();
    if ((format_ == 1) != little_host) std::reverse(b, b + n);  // 1: little-endian file
    auto as = [&b](auto v) { std::memcpy(&v, b, sizeof v); return double(v); };
    if (t == "char" || t == "int8") return as(int8_t());
    if (t == "uchar" || t == "uint8") return as(uint8_t());
    if (t == "short" || t == "int16") return as(int16_t());
    if (t == "ushort" || t == "uint16") return as(uint16_t());
    if (t == "int" || t == "int32") return as(int32_t());
    if (t == "uint" || t == "uint32") return as(uint32_t());
    if (t == "float" || t == "float32") return as(float());
    return as(double());
  }

 private:
  std::string path_, data_;
  size_t at_;
  int format_;  // 0 ascii, 1 binary little-endian, 2 binary big-endian
  std::istringstream text_;
};

Mesh load_ply(const std::string& path, std::string data, bool float64) {
  const size_t end = data.find("end_header");
  if (end == std::string::npos) fail(path, "PLY header has no end_header");
  const size_t body = data.find('\n', end);
  if (body == std::string::npos) fail(path, "PLY header has no end of line after end_header");
  std::istringstream header(data.substr(0, end));
  std::string line, word;
  std::getline(header, line);  // "ply"
  int format = -1;
  std::vector<PlyElement> elements;
  while (std::getline(header, line)) {
    std::istringstream ls(line);
    ls >> word;
    if (word == "format") {
      ls >> word;
      format = word == "ascii" ? 0 : word == "binary_little_endian" ? 1 : word == "binary_big_endian" ? 2 : -1;
      if (format < 0) fail(path, "unknown PLY format '" + word + "'");
    } else if (word == "element") {
      PlyElement e;
      if (!(ls >> e.name >> e.count)) fail(path, "malformed line '" + line + "'");
      elements.push_back(e);
    } else if (word == "property") {
      if (elements.empty()) fail(path, "property before any element");
      PlyProperty p;
      ls >> p.type;
      if (p.type == "list") ls >> p.count_type >> p.type;
      if (!(ls >> p.name)) fail(path, "malformed line '" + line + "'");
      ply_size(path, p.type);
      if (!p.count_type.empty()) ply_size(path, p.count_type);
      elements.back().props.push_back(p);
    }  // comment, obj_info: ignored
  }
  if (format < 0) fail(path, "PLY header has no format line");

  PlyReader in(path, std::move(data), body + 1, format);
  Mesh m;
  for (const PlyElement& e : elements) {
    int axis[3] = {-1, -1, -1};
    for (size_t i = 0; i < e.props.size(); ++i)
      for (int a = 0; a < 3; ++a)
        if (e.props[i].name == std::string(1, char('x' + a)) && e.props[i].count_type.empty()) axis[a] = int(i);
    if (e.name == "vertex" && (axis[0] < 0 || axis[1] < 0 || axis[2] < 0)) fail(path, "vertex element lacks x, y or z");
    std::vector<double> row(e.props.size());
    std::vector<int32_t> poly;
    for (size_t r = 0; r < e.count; ++r) {
      for (size_t i = 0; i < e.props.size(); ++i) {
        const PlyProperty& p = e.props[i];
        if (p.count_type.empty()) {
          row[i] = in.read(p.type);
          continue;
        }
        const double n = in.read(p.count_type);
        if (!(n >= 0 && n < 1e6)) fail(path, "bad list length in element '" + e.name + "'");
        poly.clear();
        for (int k = 0; k < int(n); ++k) {
          const double v = in.read(p.type);
          if (!(v >= -2147483648.0 && v <= 2147483647.0)) fail(path, "list value out of int32 range");
          poly.push_back(int32_t(v));
        }
        if (e.name == "face" && (p.name == "vertex_indices" || p.name == "vertex_index"))
          append_fan(m.tris, poly);
      }
      if (e.name == "vertex")
        for (int a = 0; a < 3; ++a) {
          m.xyz.push_back(float(row[axis[a]]));
          if (float64) m.xyz64.push_back(row[axis[a]]);
        }
    }
  }
  if (m.tris.empty()) fail(path, "no triangles");
  check_indices(path, m);
  return m;
}

// OFF (Geomview's and CGAL's format): "OFF", the vertex, face and edge counts, the vertices, then
// each face as its vertex count and indices (polygons fan-triangulated).
Mesh load_off(const std::string& path, const std::string& data, bool float64) {
  std::istringstream in(data);
  std::string head;
  size_t nv = 0, nf = 0, ne = 0;
  if (!(in >> head >> nv >> nf >> ne) || head != "OFF") fail(path, "not an OFF file");
  std::vector<double> xyz(3 * nv);
  for (double& x : xyz) in >> x;
  Mesh m;
  for (size_t f = 0; f < nf && in; ++f) {
    int k = 0;
    in >> k;
    std::vector<int32_t> poly(size_t(std::max(k, 0)));
    for (int32_t& v : poly) in >> v;
    append_fan(m.tris, poly);
  }
  if (!in) fail(path, "truncated OFF file");
  if (m.tris.empty()) fail(path, "no triangles");
  if (float64) set_float64(m, std::move(xyz));
  else m.xyz.assign(xyz.begin(), xyz.end());  // to nearest
  check_indices(path, m);
  return m;
}

}  // namespace

Mesh load_mesh(const std::string& path, bool float64) {
  std::ifstream f(path, std::ios::binary);
  if (!f) fail(path, "cannot open file");
  std::string data((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (data.compare(0, 4, "ply\n") == 0 || data.compare(0, 5, "ply\r\n") == 0) return load_ply(path, std::move(data), float64);
  std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".obj") return load_obj(path, float64);
  if (ext == ".off") return load_off(path, data, float64);
  fail(path, "unknown mesh format (expected .obj, .off or a PLY file)");
}

}  // namespace minkq::meshio
