// Vertex clustering: one vertex per occupied voxel (the mean), faces remapped and cleaned.
#include "engine/geometry/mesh_simplify.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>

#include "engine/core/error.h"

namespace dynscope {
namespace {

// Faces whose area falls below this fraction of a voxel face are slivers left by clustering.
constexpr double kDegenerateAreaFraction = 1e-12;
// Voxel coordinates beyond this would not fit the 64-bit key exactly.
constexpr double kMaxVoxelCoordinate = 4.0e15;

}  // namespace

Mesh simplify_vertex_clustering(const Mesh& mesh, double voxel) {
  if (!std::isfinite(voxel) || voxel <= 0.0) {
    throw ValueError("voxel", "must be finite and positive, got " + std::to_string(voxel));
  }
  mesh.validate("mesh");
  const Eigen::Index v_count = mesh.vertices.rows();

  // Only vertices used by a face take part, so stray vertices cannot pull a cluster mean.
  std::vector<bool> used(static_cast<size_t>(v_count), false);
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
    for (int c = 0; c < 3; ++c) used[static_cast<size_t>(mesh.faces(f, c))] = true;
  }

  // Clusters are numbered in order of their first vertex, which keeps the output deterministic.
  std::map<std::array<int64_t, 3>, int32_t> cluster_of_cell;
  std::vector<int32_t> cluster(static_cast<size_t>(v_count), -1);
  std::vector<Vec3> sum;
  std::vector<int> members;
  for (Eigen::Index v = 0; v < v_count; ++v) {
    if (!used[static_cast<size_t>(v)]) continue;
    const Vec3 p = mesh.vertices.row(v).transpose();
    const Vec3 cell = (p / voxel).array().floor();
    if (cell.cwiseAbs().maxCoeff() > kMaxVoxelCoordinate) {
      throw ValueError("voxel", "vertex " + std::to_string(v) +
                                    " is too far from the origin for "
                                    "voxel " +
                                    std::to_string(voxel));
    }
    const std::array<int64_t, 3> key{static_cast<int64_t>(cell.x()), static_cast<int64_t>(cell.y()),
                                     static_cast<int64_t>(cell.z())};
    const auto [it, inserted] = cluster_of_cell.try_emplace(key, static_cast<int32_t>(sum.size()));
    if (inserted) {
      sum.push_back(Vec3::Zero());
      members.push_back(0);
    }
    cluster[static_cast<size_t>(v)] = it->second;
    sum[static_cast<size_t>(it->second)] += p;
    ++members[static_cast<size_t>(it->second)];
  }
  std::vector<Vec3> centre(sum.size());
  for (size_t c = 0; c < sum.size(); ++c) centre[c] = sum[c] / members[c];

  // Remap faces; drop collapsed ones and repeats of the same vertex triple (either winding).
  const double min_area = kDegenerateAreaFraction * voxel * voxel;
  std::set<std::array<int32_t, 3>> seen;
  std::vector<std::array<int32_t, 3>> faces;
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
    std::array<int32_t, 3> tri{};
    for (int c = 0; c < 3; ++c) tri[c] = cluster[static_cast<size_t>(mesh.faces(f, c))];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
    const Vec3& a = centre[static_cast<size_t>(tri[0])];
    const Vec3& b = centre[static_cast<size_t>(tri[1])];
    const Vec3& c = centre[static_cast<size_t>(tri[2])];
    if (0.5 * (b - a).cross(c - a).norm() <= min_area) continue;
    std::array<int32_t, 3> sorted = tri;
    std::sort(sorted.begin(), sorted.end());
    if (!seen.insert(sorted).second) continue;
    faces.push_back(tri);
  }

  // Keep only clusters some surviving face uses, in cluster order.
  std::vector<bool> referenced(centre.size(), false);
  for (const auto& tri : faces) {
    for (const int32_t c : tri) referenced[static_cast<size_t>(c)] = true;
  }
  std::vector<int32_t> new_index(centre.size(), -1);
  int32_t next = 0;
  for (size_t c = 0; c < centre.size(); ++c) {
    if (referenced[c]) new_index[c] = next++;
  }
  Mesh out;
  out.vertices.resize(next, 3);
  for (size_t c = 0; c < centre.size(); ++c) {
    if (new_index[c] >= 0) out.vertices.row(new_index[c]) = centre[c].transpose();
  }
  out.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) {
    for (int c = 0; c < 3; ++c) {
      out.faces(static_cast<Eigen::Index>(f), c) = new_index[static_cast<size_t>(faces[f][c])];
    }
  }
  return out;
}

}  // namespace dynscope
