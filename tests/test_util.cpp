#include "test_util.h"

#include <lodkit/primitives.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

namespace lodkit::test {

std::string difference(const Mesh& a, const Mesh& b) {
  if (a.num_vertices() != b.num_vertices() || a.num_faces() != b.num_faces())
    return "counts: " + std::to_string(a.num_vertices()) + " vertices, " + std::to_string(a.num_faces()) + " faces against " +
           std::to_string(b.num_vertices()) + ", " + std::to_string(b.num_faces());
  if (a.positions != b.positions) return "positions";
  if (a.triangles != b.triangles) return "triangles";
  if (a.attributes.normals != b.attributes.normals) return "normals";
  if (a.attributes.uvs != b.attributes.uvs) return "uvs";
  if (a.attributes.colours != b.attributes.colours) return "colours";
  if (a.attributes.face_colours != b.attributes.face_colours) return "face colours";
  return "";
}

Mesh seamed_uv_sphere() {
  UvSphereOptions o;
  o.segments = 24;
  o.rings = 12;
  o.uvs = true;
  Mesh m = make_uv_sphere(o);
  m.attributes.normals = compute_vertex_normals(m);
  return m;
}

ScratchDir::ScratchDir(const std::string& tag) {
  std::random_device rd;
  path_ = std::filesystem::temp_directory_path() /
          ("lodkit-test-" + tag + "-" + std::to_string(rd()) + std::to_string(rd()));
  std::filesystem::create_directories(path_);
}

ScratchDir::~ScratchDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::size_t ScratchDir::entries() const {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(path_)) ++n;
  return n;
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

Mesh tetrahedron() {
  Mesh m;
  m.positions.resize(4, 3);
  m.positions << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  m.triangles.resize(4, 3);
  m.triangles << 0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2;
  return m;
}

Mesh single_triangle() {
  Mesh m;
  m.positions.resize(3, 3);
  m.positions << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  m.triangles.resize(1, 3);
  m.triangles << 0, 1, 2;
  return m;
}

Mesh bumpy_sphere(int subdivisions, double amplitude, unsigned seed) {
  Mesh m = make_icosphere({.subdivisions = subdivisions});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> noise(-amplitude, amplitude);
  for (Index v = 0; v < m.num_vertices(); ++v) m.positions.row(v) *= 1.0 + noise(rng);
  return m;
}

Mesh thin_lens() {
  Mesh lens = make_icosphere({.subdivisions = 5});
  lens.positions.col(2) *= 0.01;
  return lens;
}

Mesh flat_shaded(const Mesh& mesh) {
  Mesh flat;
  const Index faces = mesh.num_faces();
  flat.positions.resize(3 * faces, 3);
  flat.triangles.resize(faces, 3);
  flat.attributes.normals.resize(3 * faces, 3);
  for (Index f = 0; f < faces; ++f) {
    const Eigen::Vector3d a = mesh.positions.row(mesh.triangles(f, 0)), b = mesh.positions.row(mesh.triangles(f, 1)),
                          c = mesh.positions.row(mesh.triangles(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    for (int k = 0; k < 3; ++k) {
      flat.positions.row(3 * f + k) = mesh.positions.row(mesh.triangles(f, k));
      flat.attributes.normals.row(3 * f + k) = n.transpose();
      flat.triangles(f, k) = 3 * f + k;
    }
  }
  return flat;
}

SeamTwins u_seam_twins(const Mesh& m) {
  SeamTwins out;
  for (Index i = 0; i < m.num_vertices(); ++i) {
    if (m.attributes.uvs(i, 0) != 0.0) continue;
    ++out.seam;
    Index twins = 0;
    for (Index j = 0; j < m.num_vertices(); ++j)
      twins += m.positions.row(i) == m.positions.row(j) && m.attributes.uvs(j, 0) == 1.0 &&
               m.attributes.uvs(j, 1) == m.attributes.uvs(i, 1);
    out.without_twin += twins == 0;
    out.with_more_twins += twins > 1;
  }
  return out;
}

double widest_u_span(const Mesh& m, double band) {
  double widest = 0;
  for (Index f = 0; f < m.num_faces(); ++f) {
    double lo = 1, hi = 0;
    bool inside = true;
    for (int k = 0; k < 3; ++k) {
      const Index v = m.triangles(f, k);
      inside &= std::abs(m.attributes.uvs(v, 1) - 0.5) <= band;
      lo = std::min(lo, m.attributes.uvs(v, 0)), hi = std::max(hi, m.attributes.uvs(v, 0));
    }
    if (inside) widest = std::max(widest, hi - lo);
  }
  return widest;
}

}  // namespace lodkit::test
