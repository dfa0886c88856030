// Shape parts of simulated bodies: tessellated meshes, volumes and bounds that match Bullet.
#include "engine/sim/shapes.h"

#include <array>
#include <cmath>
#include <map>

#include "engine/core/error.h"

namespace dynscope {
namespace {

Mesh from_lists(const std::vector<Vec3>& vertices, const std::vector<Eigen::Vector3i>& tris) {
  Mesh m;
  m.vertices.resize(static_cast<Eigen::Index>(vertices.size()), 3);
  for (size_t i = 0; i < vertices.size(); ++i) {
    m.vertices.row(static_cast<Eigen::Index>(i)) = vertices[i].transpose();
  }
  m.faces.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t i = 0; i < tris.size(); ++i) m.faces.row(static_cast<Eigen::Index>(i)) = tris[i];
  return m;
}

bool is_identity(const Quat& q) { return std::abs(std::abs(q.normalized().w()) - 1.0) < 1e-12; }

bool is_uniform(const Vec3& s) { return s.x() == s.y() && s.y() == s.z(); }

}  // namespace

Mesh make_grid_box_mesh(const Vec3& half_extents, int divisions) {
  if (!(half_extents.array() > 0).all() || !half_extents.allFinite()) {
    throw ValueError("box half_extents", "must be positive and finite");
  }
  if (divisions < 1) throw ValueError("box divisions", "must be >= 1");
  const int n = divisions;
  std::vector<Vec3> vertices;
  std::map<std::array<int, 3>, int> index_of;
  // Vertices live on an integer lattice over the box surface so that shared edges are welded.
  auto vertex = [&](const std::array<int, 3>& c) {
    auto [it, inserted] = index_of.emplace(c, static_cast<int>(vertices.size()));
    if (inserted) {
      Vec3 p;
      for (int a = 0; a < 3; ++a) p[a] = half_extents[a] * (2.0 * c[a] / n - 1.0);
      vertices.push_back(p);
    }
    return it->second;
  };
  std::vector<Eigen::Vector3i> tris;
  for (int a = 0; a < 3; ++a) {
    const int u = (a + 1) % 3, v = (a + 2) % 3;  // e_u x e_v = e_a
    for (int side = 0; side < 2; ++side) {
      for (int iu = 0; iu < n; ++iu) {
        for (int iv = 0; iv < n; ++iv) {
          auto at = [&](int du, int dv) {
            std::array<int, 3> c{};
            c[a] = side ? n : 0;
            c[u] = iu + du;
            c[v] = iv + dv;
            return vertex(c);
          };
          const int p00 = at(0, 0), p10 = at(1, 0), p11 = at(1, 1), p01 = at(0, 1);
          if (side) {
            tris.emplace_back(p00, p10, p11);
            tris.emplace_back(p00, p11, p01);
          } else {
            tris.emplace_back(p00, p11, p10);
            tris.emplace_back(p00, p01, p11);
          }
        }
      }
    }
  }
  return from_lists(vertices, tris);
}

Mesh make_grid_cylinder_mesh(double radius, double half_height, int segments, int rows,
                             int cap_rings) {
  if (!(radius > 0) || !(half_height > 0) || !std::isfinite(radius) ||
      !std::isfinite(half_height)) {
    throw ValueError("cylinder", "radius and half height must be positive and finite");
  }
  if (segments < 3 || rows < 1 || cap_rings < 1) {
    throw ValueError("cylinder", "needs segments >= 3, rows >= 1 and cap_rings >= 1");
  }
  std::vector<Vec3> vertices;
  auto add_ring = [&](double r, double z) {
    const int first = static_cast<int>(vertices.size());
    for (int s = 0; s < segments; ++s) {
      const double phi = 2 * M_PI * s / segments;
      vertices.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
    }
    return first;
  };
  std::vector<int> side(rows + 1);
  for (int k = 0; k <= rows; ++k)
    side[k] = add_ring(radius, -half_height + 2 * half_height * k / rows);
  // cap[0] is the centre vertex, cap[j] the ring at radius j/cap_rings, cap[cap_rings] the rim.
  auto make_cap = [&](double z, int rim) {
    std::vector<int> cap(cap_rings + 1);
    cap[0] = static_cast<int>(vertices.size());
    vertices.emplace_back(0, 0, z);
    for (int j = 1; j < cap_rings; ++j) cap[j] = add_ring(radius * j / cap_rings, z);
    cap[cap_rings] = rim;
    return cap;
  };
  const std::vector<int> bottom = make_cap(-half_height, side[0]);
  const std::vector<int> top = make_cap(half_height, side[rows]);

  std::vector<Eigen::Vector3i> tris;
  auto at = [&](int ring, int s) { return ring + (s % segments); };
  for (int k = 0; k < rows; ++k) {
    for (int s = 0; s < segments; ++s) {
      const int a = at(side[k], s), b = at(side[k], s + 1);
      const int c = at(side[k + 1], s), d = at(side[k + 1], s + 1);
      tris.emplace_back(a, b, d);
      tris.emplace_back(a, d, c);
    }
  }
  for (int s = 0; s < segments; ++s) {
    tris.emplace_back(bottom[0], at(bottom[1], s + 1), at(bottom[1], s));
    tris.emplace_back(top[0], at(top[1], s), at(top[1], s + 1));
  }
  for (int j = 1; j < cap_rings; ++j) {
    for (int s = 0; s < segments; ++s) {
      {
        const int a = at(bottom[j], s), b = at(bottom[j], s + 1);
        const int c = at(bottom[j + 1], s), d = at(bottom[j + 1], s + 1);
        tris.emplace_back(a, d, c);
        tris.emplace_back(a, b, d);
      }
      {
        const int a = at(top[j], s), b = at(top[j], s + 1);
        const int c = at(top[j + 1], s), d = at(top[j + 1], s + 1);
        tris.emplace_back(a, c, d);
        tris.emplace_back(a, d, b);
      }
    }
  }
  return from_lists(vertices, tris);
}

Mesh make_wedge_mesh(double length, double height, double half_width) {
  if (!(length > 0) || !(height > 0) || !(half_width > 0)) {
    throw ValueError("wedge", "length, height and half width must be positive");
  }
  std::vector<Vec3> v;
  for (double y : {-half_width, half_width}) {
    v.emplace_back(0, y, 0);
    v.emplace_back(length, y, 0);
    v.emplace_back(0, y, height);
  }
  const std::vector<Eigen::Vector3i> tris = {{0, 1, 2}, {3, 5, 4},   // sides (-y, +y)
                                             {0, 3, 4}, {0, 4, 1},   // bottom (-z)
                                             {0, 2, 5}, {0, 5, 3},   // back (-x)
                                             {1, 4, 5}, {1, 5, 2}};  // slope
  return from_lists(v, tris);
}

void check_part(const ShapePart& part, const Vec3& scale, const std::string& what) {
  if (!(scale.array() > 0).all() || !scale.allFinite()) {
    throw ValueError(what, "scale must be positive and finite");
  }
  if (!part.local.position.allFinite() || !part.local.rotation.coeffs().allFinite()) {
    throw ValueError(what, "part pose is not finite");
  }
  if (!is_identity(part.local.rotation) && !is_uniform(scale)) {
    throw ValueError(what, "a rotated part needs a uniform scale");
  }
  const Vec3 h = part.half_extents.cwiseProduct(scale);
  switch (part.kind) {
    case ShapeKind::kBox:
      if (!(h.array() > 0).all() || !h.allFinite()) {
        throw ValueError(what, "box half extents must be positive");
      }
      break;
    case ShapeKind::kSphere:
      if (!(h.x() > 0) || !std::isfinite(h.x()) || std::abs(h.y() - h.x()) > 1e-12 * h.x() ||
          std::abs(h.z() - h.x()) > 1e-12 * h.x()) {
        throw ValueError(what, "sphere needs one positive radius (equal components)");
      }
      break;
    case ShapeKind::kCylinder:
      if (!(h.x() > 0) || !(h.z() > 0) || !h.allFinite() ||
          std::abs(h.y() - h.x()) > 1e-12 * h.x()) {
        throw ValueError(what, "cylinder needs a positive radius (x = y) and half height (z)");
      }
      break;
    case ShapeKind::kConvexHull:
      if (part.hull_mesh.num_vertices() < 4 || part.hull_mesh.num_faces() < 4) {
        throw ValueError(what, "convex hull part needs a mesh with at least 4 vertices and faces");
      }
      part.hull_mesh.validate(what);
      break;
  }
}

ShapePart scaled_part(const ShapePart& part, const Vec3& scale) {
  ShapePart out = part;
  out.local.position = part.local.position.cwiseProduct(scale);
  out.half_extents = part.half_extents.cwiseProduct(scale);
  if (part.kind == ShapeKind::kConvexHull) out.hull_mesh = part.hull_mesh.scaled(scale);
  return out;
}

std::string mesh_density_name(MeshDensity density) {
  return density == MeshDensity::kSparse ? "sparse" : "dense";
}

MeshDensity parse_mesh_density(const std::string& name, const std::string& what) {
  if (name == "dense") return MeshDensity::kDense;
  if (name == "sparse") return MeshDensity::kSparse;
  throw ValueError(what, "must be \"dense\" or \"sparse\", got \"" + name + "\"");
}

Mesh part_mesh(const ShapePart& part, MeshDensity density) {
  const bool sparse = density == MeshDensity::kSparse;
  Mesh m;
  switch (part.kind) {
    case ShapeKind::kBox:
      m = make_grid_box_mesh(part.half_extents, sparse ? 1 : kBoxDivisions);
      break;
    case ShapeKind::kSphere:
      m = make_sphere_mesh(part.half_extents.x(), kSphereRings, kSphereSegments);
      break;
    case ShapeKind::kCylinder:
      m = sparse ? make_grid_cylinder_mesh(part.half_extents.x(), part.half_extents.z(),
                                           kCylinderSegments, 1, 1)
                 : make_grid_cylinder_mesh(part.half_extents.x(), part.half_extents.z());
      break;
    case ShapeKind::kConvexHull:
      m = part.hull_mesh;
      break;
  }
  m.vertices = part.local.apply(m.vertices);
  return m;
}

Mesh body_mesh(const std::vector<ShapePart>& parts, MeshDensity density) {
  Mesh out;
  for (const ShapePart& part : parts) {
    const Mesh m = part_mesh(part, density);
    const Eigen::Index v0 = out.vertices.rows(), f0 = out.faces.rows();
    out.vertices.conservativeResize(v0 + m.vertices.rows(), 3);
    out.vertices.bottomRows(m.vertices.rows()) = m.vertices;
    out.faces.conservativeResize(f0 + m.faces.rows(), 3);
    out.faces.bottomRows(m.faces.rows()) = m.faces.array() + static_cast<int32_t>(v0);
  }
  return out;
}

double body_volume(const std::vector<ShapePart>& parts, const Vec3& scale) {
  double total = 0;
  for (const ShapePart& raw : parts) {
    const ShapePart p = scaled_part(raw, scale);
    const Vec3& h = p.half_extents;
    switch (p.kind) {
      case ShapeKind::kBox:
        total += 8.0 * h.x() * h.y() * h.z();
        break;
      case ShapeKind::kSphere:
        total += 4.0 / 3.0 * M_PI * h.x() * h.x() * h.x();
        break;
      case ShapeKind::kCylinder:
        total += M_PI * h.x() * h.x() * 2.0 * h.z();
        break;
      case ShapeKind::kConvexHull:
        total += std::abs(p.hull_mesh.volume());
        break;
    }
  }
  return total;
}

Aabb body_aabb(const std::vector<ShapePart>& parts, const Vec3& scale, const Pose& pose) {
  Aabb box;
  for (const ShapePart& raw : parts) {
    const ShapePart p = scaled_part(raw, scale);
    const Quat q = pose.rotation.normalized() * p.local.rotation.normalized();
    const Vec3 centre = pose.apply(p.local.position);
    const Mat3 r = q.toRotationMatrix();
    const Vec3& h = p.half_extents;
    Vec3 extent = Vec3::Zero();
    switch (p.kind) {
      case ShapeKind::kBox:
        extent = r.cwiseAbs() * h;
        break;
      case ShapeKind::kSphere:
        extent = Vec3::Constant(h.x());
        break;
      case ShapeKind::kCylinder:
        for (int i = 0; i < 3; ++i) {
          const double axis = r(i, 2);
          extent[i] = std::abs(axis) * h.z() + h.x() * std::sqrt(std::max(0.0, 1.0 - axis * axis));
        }
        break;
      case ShapeKind::kConvexHull: {
        const Pose world{centre, q};
        box.extend(Aabb::of(world.apply(p.hull_mesh.vertices)));
        continue;
      }
    }
    box.extend(centre - extent);
    box.extend(centre + extent);
  }
  return box;
}

}  // namespace dynscope
