// RenderScene helpers: building series and geometry from engine types, bounds and validation.
#include "render/render_scene.h"

#include <cmath>

#include "engine/core/error.h"

namespace dynscope::render {

void PointSeries::validate(const std::string& what) const {
  validate_sizes(what);
  for (float v : positions) {
    if (!std::isfinite(v)) throw ValueError(what, "positions contain a non-finite value");
  }
}

void PointSeries::validate_sizes(const std::string& what) const {
  if (num_frames < 0 || num_points < 0) throw ValueError(what, "negative size");
  const size_t tn = static_cast<size_t>(num_frames) * num_points;
  if (positions.size() != tn * 3) {
    throw ValueError(what, "positions has " + std::to_string(positions.size()) +
                               " values, expected T*N*3 = " + std::to_string(tn * 3));
  }
  if (!scalars.empty() && scalars.size() != tn) {
    throw ValueError(what, "scalars has " + std::to_string(scalars.size()) +
                               " values, expected T*N = " + std::to_string(tn));
  }
  if (!colors.empty() && colors.size() != static_cast<size_t>(num_points) * 3) {
    throw ValueError(what, "colors has " + std::to_string(colors.size()) +
                               " values, expected N*3 = " + std::to_string(num_points * 3));
  }
}

Vec3 PointSeries::position(int frame, int i) const {
  const size_t k = (static_cast<size_t>(frame) * num_points + i) * 3;
  return Vec3(positions[k], positions[k + 1], positions[k + 2]);
}

Aabb PointSeries::bounds(int frame) const {
  Aabb box;
  for (int i = 0; i < num_points; ++i) box.extend(position(frame, i));
  return box;
}

std::shared_ptr<PointSeries> make_point_series(const std::vector<Points>& frames) {
  auto series = std::make_shared<PointSeries>();
  series->num_frames = static_cast<int>(frames.size());
  series->num_points = frames.empty() ? 0 : static_cast<int>(frames[0].rows());
  series->positions.reserve(frames.size() * series->num_points * 3);
  for (size_t f = 0; f < frames.size(); ++f) {
    if (frames[f].rows() != series->num_points) {
      throw ValueError("point series",
                       "frame " + std::to_string(f) + " has " + std::to_string(frames[f].rows()) +
                           " points, frame 0 has " + std::to_string(series->num_points));
    }
    for (Eigen::Index i = 0; i < frames[f].rows(); ++i) {
      for (int k = 0; k < 3; ++k) series->positions.push_back(static_cast<float>(frames[f](i, k)));
    }
  }
  return series;
}

std::shared_ptr<MeshGeometry> make_mesh_geometry(const Mesh& mesh) {
  mesh.validate("mesh");
  auto geometry = std::make_shared<MeshGeometry>();
  geometry->vertices.reserve(mesh.num_vertices() * 3);
  for (Eigen::Index i = 0; i < mesh.num_vertices(); ++i) {
    for (int k = 0; k < 3; ++k)
      geometry->vertices.push_back(static_cast<float>(mesh.vertices(i, k)));
  }
  geometry->faces.reserve(mesh.num_faces() * 3);
  for (Eigen::Index i = 0; i < mesh.num_faces(); ++i) {
    for (int k = 0; k < 3; ++k) geometry->faces.push_back(static_cast<uint32_t>(mesh.faces(i, k)));
  }
  return geometry;
}

Eigen::Matrix4f pose_matrix(const Pose& pose, const Vec3& scale) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<3, 3>(0, 0) = pose.rotation.normalized().toRotationMatrix() * scale.asDiagonal();
  m.block<3, 1>(0, 3) = pose.position;
  return m.cast<float>();
}

void LineSet::add(const Vec3& a, const Vec3& b, const Color& c) {
  for (const Vec3* p : {&a, &b}) {
    for (int k = 0; k < 3; ++k) {
      positions.push_back(static_cast<float>((*p)[k]));
      colors.push_back(c[k]);
    }
  }
}

const char* point_style_name(PointStyle style) {
  switch (style) {
    case PointStyle::kSpheres:
      return "spheres";
    case PointStyle::kDiscs:
      return "discs";
    case PointStyle::kAuto:
      break;
  }
  return "auto";
}

PointStyle parse_point_style(const std::string& name) {
  for (PointStyle s : {PointStyle::kAuto, PointStyle::kSpheres, PointStyle::kDiscs}) {
    if (name == point_style_name(s)) return s;
  }
  throw ValueError("point_style", "'" + name + "' is not one of auto, spheres, discs");
}

int64_t RenderScene::point_count() const {
  int64_t n = 0;
  for (const PointLayer& layer : points) n += layer.series ? layer.series->num_points : 0;
  return n;
}

PointStyle RenderScene::resolved_point_style() const {
  if (point_style != PointStyle::kAuto) return point_style;
  return point_count() > kDiscPointThreshold ? PointStyle::kDiscs : PointStyle::kSpheres;
}

Aabb RenderScene::bounds() const {
  Aabb box;
  for (const MeshInstance& m : meshes) {
    if (!m.geometry) continue;
    const auto& v = m.geometry->vertices;
    for (size_t i = 0; i + 2 < v.size(); i += 3) {
      const Eigen::Vector4f p = m.model * Eigen::Vector4f(v[i], v[i + 1], v[i + 2], 1.0f);
      box.extend(Vec3(p.x(), p.y(), p.z()));
    }
  }
  for (const PointLayer& layer : points) {
    if (layer.series && layer.frame >= 0 && layer.frame < layer.series->num_frames) {
      box.extend(layer.series->bounds(layer.frame));
    }
  }
  for (const LineSet& l : lines) {
    for (size_t i = 0; i + 2 < l.positions.size(); i += 3) {
      box.extend(Vec3(l.positions[i], l.positions[i + 1], l.positions[i + 2]));
    }
  }
  for (const WireBox& b : boxes) {
    box.extend(b.min.cast<double>());
    box.extend(b.max.cast<double>());
  }
  return box;
}

void RenderScene::validate() const {
  for (size_t i = 0; i < points.size(); ++i) {
    const PointLayer& layer = points[i];
    const std::string what = "point layer '" + layer.name + "'";
    if (!layer.series) throw ValueError(what, "has no point series");
    // Values are checked once per series when it is uploaded; per frame only the sizes.
    layer.series->validate_sizes(what);
    if (layer.frame < 0 || layer.frame >= layer.series->num_frames) {
      throw ValueError(what, "frame " + std::to_string(layer.frame) + " is outside [0, " +
                                 std::to_string(layer.series->num_frames) + ")");
    }
    if (layer.coloring == PointColoring::kScalar) {
      check_colormap(layer.colormap);
      if (layer.series->scalars.empty()) throw ValueError(what, "scalar colouring without scalars");
    }
    if (layer.coloring == PointColoring::kPerPoint && layer.series->colors.empty()) {
      throw ValueError(what, "per-point colouring without colors");
    }
    if (!(layer.radius > 0.0f)) throw ValueError(what, "radius must be > 0");
  }
  if (points.size() > 254) throw ValueError("point layers", "at most 254 (picking ids)");
  for (const MeshInstance& m : meshes) {
    const std::string what = "mesh '" + m.name + "'";
    if (!m.geometry) throw ValueError(what, "has no geometry");
    const size_t v = m.geometry->vertices.size() / 3;
    if (m.geometry->vertices.size() % 3 || m.geometry->faces.size() % 3) {
      throw ValueError(what, "arrays are not multiples of 3");
    }
    for (uint32_t f : m.geometry->faces) {
      if (f >= v) throw ValueError(what, "face index " + std::to_string(f) + " >= vertex count");
    }
  }
  for (const LineSet& l : lines) {
    const std::string what = "line set '" + l.name + "'";
    if (l.positions.size() % 6) throw ValueError(what, "positions is not a multiple of 6");
    if (!l.colors.empty() && l.colors.size() != l.positions.size()) {
      throw ValueError(what, "colors and positions differ in size");
    }
  }
}

}  // namespace dynscope::render
