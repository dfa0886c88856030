// Collision shape parts of simulated bodies and the triangle meshes that match them.
#pragma once

#include <string>
#include <vector>

#include "engine/core/types.h"
#include "engine/scene/mesh.h"

namespace dynscope {

/// Kind of one convex collision part.
enum class ShapeKind { kBox, kSphere, kCylinder, kConvexHull };

/// One convex part of a body, in the body frame before the object's scale is applied.
/// A body is the union of its parts; the same description yields the Bullet shape and the mesh.
struct ShapePart {
  ShapeKind kind = ShapeKind::kBox;
  /// Box: half side lengths. Sphere: radius in every component. Cylinder: radius in x and y,
  /// half height in z (the cylinder axis is the part's z axis). Unused for kConvexHull.
  Vec3 half_extents = Vec3::Ones();
  /// kConvexHull only: a closed mesh whose vertices span the hull; it is also the stored mesh.
  Mesh hull_mesh;
  /// Frame of the part inside the body frame.
  Pose local;
};

/// Tessellation density of the primitive meshes (enough vertices for the model's mesh mode).
inline constexpr int kBoxDivisions = 4;
inline constexpr int kSphereRings = 16;
inline constexpr int kSphereSegments = 32;
inline constexpr int kCylinderSegments = 32;
inline constexpr int kCylinderRows = 4;
inline constexpr int kCylinderCapRings = 2;

/// How densely the stored meshes tessellate the primitive parts (the collision shapes, and so the
/// simulation, are the same either way). kDense: the grids above, vertices spread over every face
/// (unit box 98 vertices, cylinder 226, sphere 482). kSparse: the fewest vertices that keep each
/// shape: a box's 8 corners, a cylinder's two rims of kCylinderSegments and a centre per cap (66),
/// the same sphere; flat faces then hold no vertices inside them, the situation of the simple
/// shapes of the paper's MOVi-A in which its mesh-face reasoning helped. Hulls are kept as given.
enum class MeshDensity { kDense, kSparse };

/// "dense" or "sparse".
std::string mesh_density_name(MeshDensity density);

/// The density named `name` ("dense" or "sparse"); throws ValueError(`what`) for another name.
MeshDensity parse_mesh_density(const std::string& name, const std::string& what);

/// Closed box centred at the origin with each face split into `divisions`² quads (welded
/// vertices, outward CCW faces). Throws ValueError if a half extent is not positive or
/// divisions < 1.
Mesh make_grid_box_mesh(const Vec3& half_extents, int divisions = kBoxDivisions);

/// Closed cylinder along z centred at the origin: `rows` bands along the side and `cap_rings`
/// concentric rings per cap, every ring with `segments` vertices. Throws ValueError for
/// non-positive sizes, segments < 3, rows < 1 or cap_rings < 1.
Mesh make_grid_cylinder_mesh(double radius, double half_height, int segments = kCylinderSegments,
                             int rows = kCylinderRows, int cap_rings = kCylinderCapRings);

/// Closed triangular prism (a ramp): the right triangle (0,0), (length,0), (0,height) in the x-z
/// plane extruded over y in [-half_width, half_width]. Throws ValueError for non-positive sizes.
Mesh make_wedge_mesh(double length, double height, double half_width);

/// Throws ValueError(`what`) unless the part can be built with `scale`: positive finite sizes, a
/// sphere with equal components, a cylinder with equal x/y radius, a non-empty hull mesh, and a
/// uniform scale wherever the part is rotated inside the body.
void check_part(const ShapePart& part, const Vec3& scale, const std::string& what);

/// The part with the object's component-wise `scale` baked into its sizes and position.
/// Requires check_part to pass.
ShapePart scaled_part(const ShapePart& part, const Vec3& scale);

/// Triangle mesh of one part in the body frame (unscaled), matching its collision shape: box
/// and hull exactly, sphere and cylinder as inscribed tessellations, at `density`.
Mesh part_mesh(const ShapePart& part, MeshDensity density = MeshDensity::kDense);

/// Concatenated meshes of all parts in the body frame (unscaled); parts stay separate
/// components, so a concave body made of convex parts keeps its exact shape.
Mesh body_mesh(const std::vector<ShapePart>& parts, MeshDensity density = MeshDensity::kDense);

/// Volume (scene units³) of a body with `scale` applied: sum of its parts (overlaps counted
/// twice; the generators never overlap parts). Hull volume is its mesh's enclosed volume.
double body_volume(const std::vector<ShapePart>& parts, const Vec3& scale);

/// World-space axis-aligned bounds of the scaled body placed at `pose` (exact for boxes,
/// spheres and cylinders, vertex bounds for hulls).
Aabb body_aabb(const std::vector<ShapePart>& parts, const Vec3& scale, const Pose& pose);

}  // namespace dynscope
