// Triangle mesh: vertices in the object's local frame and triangle indices.
#pragma once

#include <string>

#include "engine/core/types.h"

namespace dynscope {

/// Indexed triangle mesh. Vertices `[V,3]` in object-local units, faces `[F,3]` (CCW outward).
struct Mesh {
  Points vertices = Points(0, 3);
  Faces faces = Faces(0, 3);

  Eigen::Index num_vertices() const { return vertices.rows(); }
  Eigen::Index num_faces() const { return faces.rows(); }
  bool empty() const { return vertices.rows() == 0 || faces.rows() == 0; }

  /// Total surface area (scene units squared).
  double area() const;
  /// Signed enclosed volume (divergence theorem); positive for a closed mesh with outward faces.
  double volume() const;
  /// Area of each face, `[F]`.
  Eigen::VectorXd face_areas() const;
  /// A copy with every vertex multiplied component-wise by `scale`.
  Mesh scaled(const Vec3& scale) const;
  /// Throws ValueError(`what`) if a face index is out of range or a vertex is not finite.
  void validate(const std::string& what) const;
};

/// Axis-aligned box centred at the origin with the given full side lengths (12 triangles).
Mesh make_box_mesh(const Vec3& size);
/// UV sphere of `radius` with `rings` latitude bands and `segments` longitude segments.
Mesh make_sphere_mesh(double radius, int rings = 12, int segments = 24);
/// Closed cylinder along z, centred at the origin.
Mesh make_cylinder_mesh(double radius, double height, int segments = 24);

}  // namespace dynscope
