// The previous neighbour search (PCL float kd-trees, one map of trees per list, serial), kept
// only so that geometry_bench can time the library beside the formulation it replaced.
#pragma once

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <vector>

#include "engine/core/types.h"
#include "engine/geometry/grid_downsample.h"
#include "engine/geometry/kdtree_index.h"
#include "engine/geometry/neighbors.h"
#include "engine/model/hierarchy.h"

namespace dynscope::legacy {

inline bool neighbor_less(const Neighbor& a, const Neighbor& b) {
  return a.sq_dist < b.sq_dist || (a.sq_dist == b.sq_dist && a.index < b.index);
}

/// PCL's float KdTreeFLANN proposing candidates with a safety margin, distances recomputed in
/// double (the KdIndex this library used before; exact, finite inputs below 1e18 only).
class PclKdIndex {
 public:
  explicit PclKdIndex(const Points& points) : points_(points) {
    if (points_.rows() == 0) return;
    const Aabb box = Aabb::of(points_);
    centre_ = 0.5 * (box.min + box.max);
    auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    cloud->resize(static_cast<size_t>(points_.rows()));
    for (Eigen::Index i = 0; i < points_.rows(); ++i) {
      const Vec3 p = points_.row(i).transpose() - centre_;
      extent_ = std::max(extent_, p.norm());
      (*cloud)[static_cast<size_t>(i)] = pcl::PointXYZ(
          static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    }
    flann_ = std::make_unique<pcl::KdTreeFLANN<pcl::PointXYZ>>();
    flann_->setInputCloud(cloud);
  }

  /// The min(k, size) nearest points, sorted by (squared distance, index).
  void knn(const Vec3& query, int k, std::vector<Neighbor>& out) const {
    out.clear();
    const auto n = static_cast<int>(points_.rows());
    if (n == 0 || k <= 0) return;
    k = std::min(k, n);
    const int fetch = std::min(n, k + 2);
    thread_local pcl::Indices indices;
    thread_local std::vector<float> sq_dists;
    flann_->nearestKSearch(to_float(query), fetch, indices, sq_dists);
    float farthest_sq = 0.0f;
    for (size_t j = 0; j < indices.size(); ++j) {
      out.push_back({squared_distance(query, point(indices[j])), static_cast<int32_t>(indices[j])});
      farthest_sq = std::max(farthest_sq, sq_dists[j]);
    }
    std::sort(out.begin(), out.end(), neighbor_less);
    const double kth = std::sqrt(out[static_cast<size_t>(k) - 1].sq_dist);
    const bool complete =
        fetch == n || std::sqrt(static_cast<double>(farthest_sq)) - margin(query, kth) > kth;
    if (!complete) {
      const double limit = out[static_cast<size_t>(k) - 1].sq_dist;
      flann_->radiusSearch(to_float(query), kth + 2.0 * margin(query, kth), indices, sq_dists);
      out.clear();
      for (const auto i : indices) {
        const double d = squared_distance(query, point(i));
        if (d <= limit) out.push_back({d, static_cast<int32_t>(i)});
      }
      std::sort(out.begin(), out.end(), neighbor_less);
    }
    out.resize(static_cast<size_t>(k));
  }

 private:
  Vec3 point(Eigen::Index i) const { return points_.row(i).transpose(); }
  pcl::PointXYZ to_float(const Vec3& query) const {
    const Vec3 c = query - centre_;
    return {static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z())};
  }
  double margin(const Vec3& query, double distance) const {
    return 4e-6 * (extent_ + (query - centre_).norm() + distance) +
           std::numeric_limits<double>::min();
  }

  Points points_;
  Vec3 centre_ = Vec3::Zero();
  double extent_ = 0.0;
  std::unique_ptr<pcl::KdTreeFLANN<pcl::PointXYZ>> flann_;
};

struct ObjectTree {
  std::vector<int32_t> global;
  PclKdIndex tree;
  Aabb box;
};

inline std::map<int32_t, ObjectTree> build_object_trees(const Points& source,
                                                        const std::vector<int32_t>& source_ids) {
  std::map<int32_t, std::vector<int32_t>> members;
  for (size_t i = 0; i < source_ids.size(); ++i) {
    members[source_ids[i]].push_back(static_cast<int32_t>(i));
  }
  std::map<int32_t, ObjectTree> trees;
  for (auto& [id, global] : members) {
    Points local(static_cast<Eigen::Index>(global.size()), 3);
    for (size_t j = 0; j < global.size(); ++j) {
      local.row(static_cast<Eigen::Index>(j)) = source.row(global[j]);
    }
    const Aabb box = Aabb::of(local);
    trees.emplace(id, ObjectTree{std::move(global), PclKdIndex(local), box});
  }
  return trees;
}

inline NeighborList empty_list(Eigen::Index rows, int k) {
  NeighborList out;
  out.index = IndexMatrix::Constant(rows, k, -1);
  out.mask = MaskMatrix::Zero(rows, k);
  return out;
}

inline void write_row(NeighborList& out, Eigen::Index row, const std::vector<Neighbor>& found,
                      const std::vector<int32_t>* global) {
  for (size_t j = 0; j < found.size(); ++j) {
    const auto col = static_cast<Eigen::Index>(j);
    out.index(row, col) =
        global != nullptr ? (*global)[static_cast<size_t>(found[j].index)] : found[j].index;
    out.mask(row, col) = 1;
  }
}

/// The previous knn_same_object: a fresh map of PCL trees per call, serial queries.
inline NeighborList knn_same_object(const Points& query, const std::vector<int32_t>& query_ids,
                                    const Points& source, const std::vector<int32_t>& source_ids,
                                    int k) {
  NeighborList out = empty_list(query.rows(), k);
  const std::map<int32_t, ObjectTree> trees = build_object_trees(source, source_ids);
  std::vector<Neighbor> found;
  for (Eigen::Index i = 0; i < query.rows(); ++i) {
    const auto it = trees.find(query_ids[static_cast<size_t>(i)]);
    if (it == trees.end()) continue;
    it->second.tree.knn(query.row(i).transpose(), k, found);
    write_row(out, i, found, &it->second.global);
  }
  return out;
}

/// The previous knn_other_objects: unbounded k nearest per other object, filtered afterwards.
inline NeighborList knn_other_objects(const Points& query, const std::vector<int32_t>& query_ids,
                                      const Points& source, const std::vector<int32_t>& source_ids,
                                      int k, double radius) {
  NeighborList out = empty_list(query.rows(), k);
  const std::map<int32_t, ObjectTree> trees = build_object_trees(source, source_ids);
  const double sq_radius = radius * radius;
  std::vector<Neighbor> found, merged;
  for (Eigen::Index i = 0; i < query.rows(); ++i) {
    const Vec3 q = query.row(i).transpose();
    const int32_t own = query_ids[static_cast<size_t>(i)];
    merged.clear();
    for (const auto& [id, object] : trees) {
      const Vec3 d = (object.box.min - q).cwiseMax(q - object.box.max).cwiseMax(0.0);
      if (id == own || d.x() * d.x() + d.y() * d.y() + d.z() * d.z() > sq_radius) continue;
      object.tree.knn(q, k, found);
      for (const Neighbor& n : found) {
        if (n.sq_dist > sq_radius) break;
        merged.push_back({n.sq_dist, object.global[static_cast<size_t>(n.index)]});
      }
    }
    std::sort(merged.begin(), merged.end(), neighbor_less);
    if (merged.size() > static_cast<size_t>(k)) merged.resize(static_cast<size_t>(k));
    write_row(out, i, merged, nullptr);
  }
  return out;
}

/// The previous knn_all: one PCL tree, serial queries.
inline NeighborList knn_all(const Points& query, const Points& source, int k) {
  NeighborList out = empty_list(query.rows(), k);
  const PclKdIndex tree(source);
  std::vector<Neighbor> found;
  for (Eigen::Index i = 0; i < query.rows(); ++i) {
    tree.knn(query.row(i).transpose(), k, found);
    write_row(out, i, found, nullptr);
  }
  return out;
}

/// The previous build_hierarchy of point input (object-centric): four calls per level, each
/// building its own trees.
inline Hierarchy build_hierarchy(const Points& points, const std::vector<int32_t>& object_ids,
                                 const HierarchyOptions& o) {
  Hierarchy h;
  h.grid_anchor = Vec3(points.col(0).minCoeff(), points.col(1).minCoeff(), 0.0);
  h.levels.resize(static_cast<size_t>(o.levels));
  for (int l = 0; l < o.levels; ++l) {
    HierarchyLevel& level = h.levels[static_cast<size_t>(l)];
    level.radius = o.radius * std::pow(o.growth, l);
    if (l == 0) {
      level.points = points;
      level.object_ids = object_ids;
    } else {
      const HierarchyLevel& prev = h.levels[static_cast<size_t>(l - 1)];
      level.voxel = o.voxel * std::pow(o.growth, l - 1);
      Points shifted = prev.points;
      shifted.rowwise() -= h.grid_anchor.transpose();
      level.kept = grid_downsample_per_object(shifted, prev.object_ids, level.voxel);
      level.points.resize(static_cast<Eigen::Index>(level.kept.size()), 3);
      for (size_t i = 0; i < level.kept.size(); ++i) {
        level.points.row(static_cast<Eigen::Index>(i)) = prev.points.row(level.kept[i]);
        level.object_ids.push_back(prev.object_ids[static_cast<size_t>(level.kept[i])]);
      }
      level.down =
          knn_same_object(level.points, level.object_ids, prev.points, prev.object_ids, o.k);
      level.up = knn_same_object(prev.points, prev.object_ids, level.points, level.object_ids, o.k);
    }
    level.same =
        knn_same_object(level.points, level.object_ids, level.points, level.object_ids, o.k);
    level.relational = knn_other_objects(level.points, level.object_ids, level.points,
                                         level.object_ids, o.k_relational, level.radius);
  }
  return h;
}

}  // namespace dynscope::legacy
