// Same-object, other-object and plain kNN built on one exact kd-tree per object.
#include "engine/geometry/neighbors.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "engine/core/error.h"
#include "engine/geometry/kdtree_index.h"

namespace dynscope {
namespace {

// Source points of one object: its kd-tree, the global index of each local point and its box.
struct ObjectTree {
  std::vector<int32_t> global;
  KdIndex tree;
  Aabb box;
};

void check_points(const Points& points, const std::vector<int32_t>* ids, const std::string& what) {
  if (ids != nullptr && static_cast<size_t>(points.rows()) != ids->size()) {
    throw ValueError(what + "_ids", "has " + std::to_string(ids->size()) + " entries for " +
                                        std::to_string(points.rows()) + " " + what + " points");
  }
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    if (!points.row(i).allFinite()) {
      throw ValueError(what, "point " + std::to_string(i) + " is not finite");
    }
  }
}

void check_k(int k) {
  if (k <= 0) throw ValueError("k", "must be positive, got " + std::to_string(k));
}

NeighborList empty_list(Eigen::Index rows, int k) {
  NeighborList out;
  out.index = IndexMatrix::Constant(rows, k, -1);
  out.mask = MaskMatrix::Zero(rows, k);
  return out;
}

// Builds one tree per object id; local indices follow ascending global order, so tie-breaking by
// local index equals tie-breaking by global index.
std::map<int32_t, ObjectTree> build_object_trees(const Points& source,
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
    trees.emplace(id, ObjectTree{std::move(global), KdIndex(local, "source"), box});
  }
  return trees;
}

void write_row(NeighborList& out, Eigen::Index row, const std::vector<Neighbor>& found,
               const std::vector<int32_t>* global) {
  for (size_t j = 0; j < found.size(); ++j) {
    const auto col = static_cast<Eigen::Index>(j);
    out.index(row, col) =
        global != nullptr ? (*global)[static_cast<size_t>(found[j].index)] : found[j].index;
    out.mask(row, col) = 1;
  }
}

double squared_distance_to_box(const Vec3& p, const Aabb& box) {
  const Vec3 d = (box.min - p).cwiseMax(p - box.max).cwiseMax(0.0);
  // Same summation order as squared_distance, so the monotonicity argument below holds.
  return d.x() * d.x() + d.y() * d.y() + d.z() * d.z();
}

}  // namespace

int NeighborList::valid_count(Eigen::Index row) const {
  int n = 0;
  for (Eigen::Index j = 0; j < mask.cols(); ++j) n += mask(row, j) != 0 ? 1 : 0;
  return n;
}

NeighborList knn_same_object(const Points& query, const std::vector<int32_t>& query_ids,
                             const Points& source, const std::vector<int32_t>& source_ids, int k) {
  check_k(k);
  check_points(query, &query_ids, "query");
  check_points(source, &source_ids, "source");
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

NeighborList knn_other_objects(const Points& query, const std::vector<int32_t>& query_ids,
                               const Points& source, const std::vector<int32_t>& source_ids, int k,
                               double radius) {
  check_k(k);
  if (!std::isfinite(radius) || radius < 0.0) {
    throw ValueError("radius", "must be finite and >= 0, got " + std::to_string(radius));
  }
  check_points(query, &query_ids, "query");
  check_points(source, &source_ids, "source");
  NeighborList out = empty_list(query.rows(), k);
  const std::map<int32_t, ObjectTree> trees = build_object_trees(source, source_ids);
  const double sq_radius = radius * radius;
  std::vector<Neighbor> found, merged;
  for (Eigen::Index i = 0; i < query.rows(); ++i) {
    const Vec3 q = query.row(i).transpose();
    const int32_t own = query_ids[static_cast<size_t>(i)];
    merged.clear();
    for (const auto& [id, object] : trees) {
      // Rounding is monotone, so a point's computed squared distance is never below its box's:
      // skipping boxes beyond the radius cannot lose a neighbour.
      if (id == own || squared_distance_to_box(q, object.box) > sq_radius) {
        continue;
      }
      // The exact k nearest of each other object contain the exact k nearest of their union.
      object.tree.knn(q, k, found);
      for (const Neighbor& n : found) {
        if (n.sq_dist > sq_radius) break;
        merged.push_back({n.sq_dist, object.global[static_cast<size_t>(n.index)]});
      }
    }
    std::sort(merged.begin(), merged.end(), [](const Neighbor& a, const Neighbor& b) {
      return a.sq_dist < b.sq_dist || (a.sq_dist == b.sq_dist && a.index < b.index);
    });
    if (merged.size() > static_cast<size_t>(k)) merged.resize(static_cast<size_t>(k));
    write_row(out, i, merged, nullptr);
  }
  return out;
}

NeighborList knn_all(const Points& query, const Points& source, int k) {
  check_k(k);
  check_points(query, nullptr, "query");
  check_points(source, nullptr, "source");
  NeighborList out = empty_list(query.rows(), k);
  const KdIndex tree(source, "source");
  std::vector<Neighbor> found;
  for (Eigen::Index i = 0; i < query.rows(); ++i) {
    tree.knn(query.row(i).transpose(), k, found);
    write_row(out, i, found, nullptr);
  }
  return out;
}

}  // namespace dynscope
