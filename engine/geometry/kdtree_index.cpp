// KdIndex: PCL float kd-tree for candidates, double-precision distances for the answer.
#include "engine/geometry/kdtree_index.h"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "engine/core/error.h"

namespace dynscope {
namespace {

// Float rounding of coordinates and of FLANN's arithmetic moves a distance by a few units of
// 2^-24 ≈ 6e-8 relative to the magnitudes involved; 4e-6 leaves a wide safety factor.
constexpr double kRelativeMargin = 4e-6;
// FLANN computes squared distances in float (max ~3e38); this keeps them finite.
constexpr double kMaxCoordinate = 1e18;
// Extra candidates fetched beyond k so that near-ties rarely need the radius fallback.
constexpr int kExtraCandidates = 2;

bool neighbor_less(const Neighbor& a, const Neighbor& b) {
  return a.sq_dist < b.sq_dist || (a.sq_dist == b.sq_dist && a.index < b.index);
}

// Every point of `points` sorted by exact distance: the answer when the float tree cannot be used.
void brute_force(const Points& points, const Vec3& query, std::vector<Neighbor>& out) {
  out.clear();
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    out.push_back({squared_distance(query, points.row(i).transpose()), static_cast<int32_t>(i)});
  }
  std::sort(out.begin(), out.end(), neighbor_less);
}

}  // namespace

struct KdIndex::Tree {
  pcl::KdTreeFLANN<pcl::PointXYZ> flann;
};

KdIndex::KdIndex(const Points& points, const char* what) : points_(points) {
  for (Eigen::Index i = 0; i < points_.rows(); ++i) {
    if (!points_.row(i).allFinite() || points_.row(i).cwiseAbs().maxCoeff() > kMaxCoordinate) {
      throw ValueError(what, "point " + std::to_string(i) + " is not finite or exceeds 1e18");
    }
  }
  if (points_.rows() == 0) return;
  const Aabb box = Aabb::of(points_);
  centre_ = 0.5 * (box.min + box.max);
  // Centring keeps float coordinates small, so the float rounding error stays small.
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  cloud->resize(static_cast<size_t>(points_.rows()));
  for (Eigen::Index i = 0; i < points_.rows(); ++i) {
    const Vec3 p = points_.row(i).transpose() - centre_;
    extent_ = std::max(extent_, p.norm());
    (*cloud)[static_cast<size_t>(i)] = pcl::PointXYZ(
        static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  }
  tree_ = std::make_unique<Tree>();
  tree_->flann.setInputCloud(cloud);
}

KdIndex::~KdIndex() = default;
KdIndex::KdIndex(KdIndex&&) noexcept = default;
KdIndex& KdIndex::operator=(KdIndex&&) noexcept = default;

double KdIndex::margin(const Vec3& query, double distance) const {
  return kRelativeMargin * (extent_ + (query - centre_).norm() + distance) +
         std::numeric_limits<double>::min();
}

void KdIndex::radius_candidates(const Vec3& query, double float_radius, double exact_sq_limit,
                                std::vector<Neighbor>& out) const {
  thread_local pcl::Indices indices;
  thread_local std::vector<float> sq_dists;
  const Vec3 c = query - centre_;
  out.clear();
  if (c.cwiseAbs().maxCoeff() > kMaxCoordinate) {
    brute_force(points_, query, out);
    while (!out.empty() && out.back().sq_dist > exact_sq_limit) out.pop_back();
    return;
  }
  const pcl::PointXYZ q(static_cast<float>(c.x()), static_cast<float>(c.y()),
                        static_cast<float>(c.z()));
  tree_->flann.radiusSearch(q, float_radius, indices, sq_dists);
  for (const auto i : indices) {
    const double d = squared_distance(query, point(i));
    if (d <= exact_sq_limit) out.push_back({d, static_cast<int32_t>(i)});
  }
  std::sort(out.begin(), out.end(), neighbor_less);
}

void KdIndex::knn(const Vec3& query, int k, std::vector<Neighbor>& out) const {
  out.clear();
  if (!query.allFinite()) throw ValueError("query", "point is not finite");
  const auto n = static_cast<int>(points_.rows());
  if (n == 0 || k <= 0) return;
  k = std::min(k, n);
  const Vec3 c = query - centre_;
  if (c.cwiseAbs().maxCoeff() > kMaxCoordinate) {
    brute_force(points_, query, out);
    out.resize(static_cast<size_t>(k));
    return;
  }
  const int fetch = std::min(n, k + kExtraCandidates);
  thread_local pcl::Indices indices;
  thread_local std::vector<float> sq_dists;
  const pcl::PointXYZ q(static_cast<float>(c.x()), static_cast<float>(c.y()),
                        static_cast<float>(c.z()));
  tree_->flann.nearestKSearch(q, fetch, indices, sq_dists);
  float farthest_sq = 0.0f;
  for (size_t j = 0; j < indices.size(); ++j) {
    out.push_back({squared_distance(query, point(indices[j])), static_cast<int32_t>(indices[j])});
    farthest_sq = std::max(farthest_sq, sq_dists[j]);
  }
  std::sort(out.begin(), out.end(), neighbor_less);
  if (static_cast<int>(out.size()) >= k) {
    const double kth = std::sqrt(out[static_cast<size_t>(k) - 1].sq_dist);
    // Every point the float search did not return lies at least this far away (exactly); when
    // that exceeds the k-th exact distance the candidates already contain the exact answer.
    const bool complete =
        fetch == n || std::sqrt(static_cast<double>(farthest_sq)) - margin(query, kth) > kth;
    if (!complete) {
      radius_candidates(query, kth + 2.0 * margin(query, kth),
                        out[static_cast<size_t>(k) - 1].sq_dist, out);
      // The margin guarantees at least k candidates; the scan only guards that guarantee.
      if (static_cast<int>(out.size()) < k) brute_force(points_, query, out);
    }
  } else {
    // The float search returned fewer points than asked (not expected for finite points); the
    // full scan keeps the answer exact anyway.
    brute_force(points_, query, out);
  }
  out.resize(static_cast<size_t>(k));
}

void KdIndex::radius(const Vec3& query, double radius, std::vector<Neighbor>& out) const {
  out.clear();
  if (!query.allFinite()) throw ValueError("query", "point is not finite");
  if (points_.rows() == 0 || !(radius >= 0.0)) return;
  radius_candidates(query, radius + 2.0 * margin(query, radius), radius * radius, out);
}

}  // namespace dynscope
