// Mesh helpers and primitive shapes.
#include "engine/scene/mesh.h"

#include <cmath>

#include "engine/core/error.h"

namespace dynscope {

Eigen::VectorXd Mesh::face_areas() const {
  Eigen::VectorXd areas(faces.rows());
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Vec3 a = vertices.row(faces(f, 0)).transpose();
    const Vec3 b = vertices.row(faces(f, 1)).transpose();
    const Vec3 c = vertices.row(faces(f, 2)).transpose();
    areas[f] = 0.5 * (b - a).cross(c - a).norm();
  }
  return areas;
}

double Mesh::area() const { return face_areas().sum(); }

double Mesh::volume() const {
  double v = 0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Vec3 a = vertices.row(faces(f, 0)).transpose();
    const Vec3 b = vertices.row(faces(f, 1)).transpose();
    const Vec3 c = vertices.row(faces(f, 2)).transpose();
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

Mesh Mesh::scaled(const Vec3& scale) const {
  Mesh out = *this;
  for (Eigen::Index i = 0; i < out.vertices.rows(); ++i) {
    out.vertices.row(i) = out.vertices.row(i).cwiseProduct(scale.transpose());
  }
  return out;
}

void Mesh::validate(const std::string& what) const {
  if (!vertices.allFinite()) throw ValueError(what, "mesh has non-finite vertex coordinates");
  const auto n = static_cast<int32_t>(vertices.rows());
  if (faces.size() > 0 && (faces.minCoeff() < 0 || faces.maxCoeff() >= n)) {
    throw ValueError(what, "face index out of range [0, " + std::to_string(n) + ")");
  }
}

Mesh make_box_mesh(const Vec3& size) {
  Mesh m;
  const Vec3 h = 0.5 * size;
  m.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i) {
    m.vertices.row(i) << ((i & 1) ? h.x() : -h.x()), ((i & 2) ? h.y() : -h.y()),
        ((i & 4) ? h.z() : -h.z());
  }
  // Two CCW (outward) triangles per face.
  m.faces.resize(12, 3);
  m.faces << 0, 2, 3, 0, 3, 1,  // -z
      4, 5, 7, 4, 7, 6,         // +z
      0, 1, 5, 0, 5, 4,         // -y
      2, 6, 7, 2, 7, 3,         // +y
      0, 4, 6, 0, 6, 2,         // -x
      1, 3, 7, 1, 7, 5;         // +x
  return m;
}

Mesh make_sphere_mesh(double radius, int rings, int segments) {
  if (rings < 2 || segments < 3) throw ValueError("sphere", "needs rings >= 2 and segments >= 3");
  Mesh m;
  const int n = 2 + (rings - 1) * segments;
  m.vertices.resize(n, 3);
  m.vertices.row(0) << 0, 0, -radius;
  m.vertices.row(n - 1) << 0, 0, radius;
  for (int r = 1; r < rings; ++r) {
    const double theta = M_PI * r / rings - M_PI / 2;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2 * M_PI * s / segments;
      m.vertices.row(1 + (r - 1) * segments + s) << radius * std::cos(theta) * std::cos(phi),
          radius * std::cos(theta) * std::sin(phi), radius * std::sin(theta);
    }
  }
  std::vector<Eigen::Vector3i> tris;
  auto ring_vertex = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) {
    tris.emplace_back(0, ring_vertex(1, s + 1), ring_vertex(1, s));
    tris.emplace_back(n - 1, ring_vertex(rings - 1, s), ring_vertex(rings - 1, s + 1));
  }
  for (int r = 1; r < rings - 1; ++r) {
    for (int s = 0; s < segments; ++s) {
      const int a = ring_vertex(r, s), b = ring_vertex(r, s + 1);
      const int c = ring_vertex(r + 1, s), d = ring_vertex(r + 1, s + 1);
      tris.emplace_back(a, b, d);
      tris.emplace_back(a, d, c);
    }
  }
  m.faces.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t i = 0; i < tris.size(); ++i) m.faces.row(static_cast<Eigen::Index>(i)) = tris[i];
  return m;
}

Mesh make_cylinder_mesh(double radius, double height, int segments) {
  if (segments < 3) throw ValueError("cylinder", "needs segments >= 3");
  Mesh m;
  const int n = 2 + 2 * segments;
  m.vertices.resize(n, 3);
  m.vertices.row(0) << 0, 0, -height / 2;
  m.vertices.row(1) << 0, 0, height / 2;
  for (int s = 0; s < segments; ++s) {
    const double phi = 2 * M_PI * s / segments;
    const double x = radius * std::cos(phi), y = radius * std::sin(phi);
    m.vertices.row(2 + s) << x, y, -height / 2;
    m.vertices.row(2 + segments + s) << x, y, height / 2;
  }
  std::vector<Eigen::Vector3i> tris;
  for (int s = 0; s < segments; ++s) {
    const int b0 = 2 + s, b1 = 2 + (s + 1) % segments;
    const int t0 = 2 + segments + s, t1 = 2 + segments + (s + 1) % segments;
    tris.emplace_back(0, b1, b0);
    tris.emplace_back(1, t0, t1);
    tris.emplace_back(b0, b1, t1);
    tris.emplace_back(b0, t1, t0);
  }
  m.faces.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t i = 0; i < tris.size(); ++i) m.faces.row(static_cast<Eigen::Index>(i)) = tris[i];
  return m;
}

}  // namespace dynscope
