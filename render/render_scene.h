// RenderScene: the plain description of one image the renderer draws (no GL, no tensors).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "engine/core/types.h"
#include "engine/scene/mesh.h"
#include "render/colormap.h"

namespace dynscope::render {

/// All frames of one point set. The renderer uploads it once (on first draw) and then draws any
/// frame by offset, so scrubbing re-uploads nothing as long as the same object is drawn.
struct PointSeries {
  int num_frames = 0;
  int num_points = 0;
  std::vector<float> positions;  ///< `[T,N,3]` world positions (scene units).
  std::vector<float> scalars;    ///< `[T,N]` per-point scalars (e.g. error), or empty.
  std::vector<float> colors;  ///< `[N,3]` per-point RGB in [0,1] (same for every frame), or empty.

  /// Throws ValueError(`what`) if array sizes disagree with num_frames/num_points or values are
  /// not finite (O(T·N): done once, when the renderer uploads the series).
  void validate(const std::string& what) const;
  /// The size checks of validate only (O(1)): what every drawn frame checks.
  void validate_sizes(const std::string& what) const;
  /// Positions of point `i` at `frame` (no bounds check beyond assert-free Eigen copy).
  Vec3 position(int frame, int i) const;
  /// Bounding box of frame `frame` (empty for no points).
  Aabb bounds(int frame) const;
};

/// Builds a series from per-frame `[N,3]` arrays (all with the same N); throws ValueError if the
/// frames disagree in size.
std::shared_ptr<PointSeries> make_point_series(const std::vector<Points>& frames);

/// How a point layer is coloured.
enum class PointColoring {
  kUniform,   ///< PointLayer::color.
  kPerPoint,  ///< PointSeries::colors.
  kScalar,    ///< PointSeries::scalars of the drawn frame through PointLayer::colormap.
};

/// How points are drawn: ray-cast sphere impostors (lit, exact depth, 4 vertices per point) or
/// flat screen-aligned discs (one point sprite each, flat depth), for large clouds.
enum class PointStyle {
  kAuto,     ///< Discs when the scene draws more than kDiscPointThreshold points, else spheres.
  kSpheres,  ///< Sphere impostors.
  kDiscs,    ///< Flat round sprites.
};

/// Points drawn per frame above which kAuto switches to discs.
constexpr int kDiscPointThreshold = 50000;

/// "auto", "spheres" or "discs".
const char* point_style_name(PointStyle style);
/// Parses point_style_name's names; throws ValueError("point_style") otherwise.
PointStyle parse_point_style(const std::string& name);

/// One set of sphere impostors: a frame of a point series with a style.
struct PointLayer {
  std::string name;
  std::shared_ptr<const PointSeries> series;
  int frame = 0;
  PointColoring coloring = PointColoring::kUniform;
  Color color = Color(0.85f, 0.85f, 0.85f);
  std::string colormap = "viridis";
  float range_min = 0.0f;  ///< Scalar shown at the colormap's first colour.
  float range_max = 1.0f;  ///< Scalar shown at the colormap's last colour.
  float radius = 0.02f;    ///< Sphere radius (scene units).
  float opacity = 1.0f;    ///< < 1 draws a blended "ghost" after the opaque layers.
  bool pickable = true;
};

/// Triangle mesh in its own frame, uploaded once and shared by instances.
struct MeshGeometry {
  std::vector<float> vertices;  ///< `[V,3]` object-frame positions.
  std::vector<uint32_t> faces;  ///< `[F,3]` vertex indices (CCW outward).
};

/// Converts an engine mesh (double, int32) into GPU-ready geometry; throws ValueError if invalid.
std::shared_ptr<MeshGeometry> make_mesh_geometry(const Mesh& mesh);

/// One drawn mesh: shared geometry, its object-to-world transform and style.
struct MeshInstance {
  std::string name;
  std::shared_ptr<const MeshGeometry> geometry;
  Eigen::Matrix4f model = Eigen::Matrix4f::Identity();  ///< Object frame to world.
  Color color = Color(0.7f, 0.7f, 0.7f);
  bool smooth = false;  ///< Interpolated vertex normals instead of flat faces.
  float opacity = 1.0f;
};

/// Object-to-world matrix of `pose` with component-wise `scale` applied first.
Eigen::Matrix4f pose_matrix(const Pose& pose, const Vec3& scale = Vec3::Ones());

/// Line segments drawn with per-vertex colours (e.g. neighbour edges).
struct LineSet {
  std::string name;
  std::vector<float> positions;  ///< `[S*2,3]` segment endpoints (world).
  std::vector<float> colors;     ///< `[S*2,3]` RGB per endpoint, or empty for `color`.
  Color color = Color(0.1f, 0.1f, 0.1f);
  float width = 1.5f;  ///< Pixels (clamped to what the driver supports).
  float opacity = 1.0f;

  /// Appends segment a-b with colour `c` (keeps `colors` consistent when used throughout).
  void add(const Vec3& a, const Vec3& b, const Color& c);
};

/// Axis-aligned wire box (e.g. one voxel of a U-Net level).
struct WireBox {
  Eigen::Vector3f min = Eigen::Vector3f::Zero();
  Eigen::Vector3f max = Eigen::Vector3f::Zero();
  Color color = Color(0.2f, 0.2f, 0.2f);
};

/// Ground grid in the plane z = height (z up).
struct GroundGrid {
  bool visible = true;
  float height = 0.0f;
  Eigen::Vector2f center = Eigen::Vector2f::Zero();
  float extent = 5.0f;   ///< Half side of the square drawn.
  float spacing = 0.5f;  ///< Minor line spacing; major lines every 5.
  Color line_color = Color(0.55f, 0.55f, 0.55f);
};

/// Everything in one image. Drawn in the order: grid, meshes, opaque points, boxes, lines,
/// translucent meshes and points (ghosts).
struct RenderScene {
  Color background = Color(1.0f, 1.0f, 1.0f);
  GroundGrid grid;
  std::vector<MeshInstance> meshes;
  std::vector<PointLayer> points;
  std::vector<LineSet> lines;
  std::vector<WireBox> boxes;
  float box_line_width = 1.0f;
  PointStyle point_style = PointStyle::kAuto;

  /// Points drawn in this image (over all point layers).
  int64_t point_count() const;
  /// point_style with kAuto resolved by point_count().
  PointStyle resolved_point_style() const;

  /// World bounding box of everything drawn except the grid (for camera fitting).
  Aabb bounds() const;
  /// Throws ValueError naming the first inconsistent element (frame out of range, sizes, names).
  /// Costs O(layers + mesh faces), not O(points): point values are checked at upload.
  void validate() const;
};

}  // namespace dynscope::render
