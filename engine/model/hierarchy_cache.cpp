// HierarchyCache: certified reuse of same-object lists under rigid motion.
#include "engine/model/hierarchy_cache.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "engine/core/threads.h"
#include "engine/geometry/kabsch.h"

namespace dynscope {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Slack for rounding, relative to the coordinates' magnitude (absolute part) and to a distance
// (relative part): every rounding in the fit, the residuals and the squared distances is a few
// units of 1e-16 of these, so 1e-12 is a wide margin.
constexpr double kRoundingSlack = 1e-12;
// A list's object is searched afresh and anchored again when more than this fraction of its rows
// cannot be certified (the object deformed, or other points took the same places).
constexpr double kMaxUncertifiedFraction = 0.25;
// Below this many rows a parallel region costs more than it saves.
constexpr size_t kMinParallelRows = 256;

// Runs body(r, found) for r in [0, n) on the compute threads (each row is independent).
template <typename Body>
void for_rows(size_t n, const Body& body) {
  const int threads = n >= kMinParallelRows ? compute_threads() : 1;
  const auto rows = static_cast<int64_t>(n);
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    std::vector<Neighbor> found;
#pragma omp for schedule(static)
    for (int64_t r = 0; r < rows; ++r) body(static_cast<size_t>(r), found);
  }
}

// The query rows of each object id, in ascending row order, ordered by id.
std::vector<std::pair<int32_t, std::vector<Eigen::Index>>> rows_by_object(
    const std::vector<int32_t>& ids) {
  std::vector<Eigen::Index> order(ids.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<Eigen::Index>(i);
  std::stable_sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) {
    return ids[static_cast<size_t>(a)] < ids[static_cast<size_t>(b)];
  });
  std::vector<std::pair<int32_t, std::vector<Eigen::Index>>> out;
  for (const Eigen::Index row : order) {
    const int32_t id = ids[static_cast<size_t>(row)];
    if (out.empty() || out.back().first != id) out.push_back({id, {}});
    out.back().second.push_back(row);
  }
  return out;
}

// How far any distance between the entry's points can have moved from `anchor` to `current`
// (rows matched): |d' − d| <= bound.first + bound.second·d. Infinite when no rigid motion fits.
std::pair<double, double> motion_bound(const Points& anchor, const Points& current) {
  const Pose motion = fit_rigid_transform(anchor, current);
  const Mat3 r = motion.rotation.toRotationMatrix();
  double residual = 0.0;
  for (Eigen::Index i = 0; i < anchor.rows(); ++i) {
    const Vec3 a = anchor.row(i).transpose();
    residual = std::max(residual, (r * a + motion.position - current.row(i).transpose()).norm());
  }
  const double scale = 1.0 + std::max({anchor.cwiseAbs().maxCoeff(), current.cwiseAbs().maxCoeff(),
                                       motion.position.cwiseAbs().maxCoeff()});
  const double absolute = 2.0 * residual + kRoundingSlack * scale;
  const double relative = (r.transpose() * r - Mat3::Identity()).norm() + kRoundingSlack;
  if (!std::isfinite(absolute) || !std::isfinite(relative)) return {kInf, kInf};
  return {absolute, relative};
}

}  // namespace

NeighborList HierarchyCache::same_object_list(int slot, const Points& query,
                                              const std::vector<int32_t>& query_ids,
                                              const std::vector<int32_t>& query_origin,
                                              const Points& source_points,
                                              const ObjectIndex& sources,
                                              const std::vector<int32_t>& source_origin, int k) {
  NeighborList out;
  out.index = IndexMatrix::Constant(query.rows(), k, -1);
  out.mask = MaskMatrix::Zero(query.rows(), k);
  if (slot >= static_cast<int>(slots_.size())) slots_.resize(static_cast<size_t>(slot) + 1);
  std::vector<Entry>& previous = slots_[static_cast<size_t>(slot)];
  std::vector<Entry> next;
  for (const auto& [id, rows] : rows_by_object(query_ids)) {
    const ObjectIndex::Object* object = sources.find(id);
    if (object == nullptr) continue;  // no source point of this object: rows stay masked
    const size_t nq = rows.size();
    const size_t ns = object->global.size();
    std::vector<int32_t> q_origin(nq), s_origin(ns);
    Points current(static_cast<Eigen::Index>(nq + ns), 3);
    for (size_t i = 0; i < nq; ++i) {
      q_origin[i] = query_origin[static_cast<size_t>(rows[i])];
      current.row(static_cast<Eigen::Index>(i)) = query.row(rows[i]);
    }
    for (size_t j = 0; j < ns; ++j) {
      const int32_t s = object->global[j];
      s_origin[j] = source_origin[static_cast<size_t>(s)];
      current.row(static_cast<Eigen::Index>(nq + j)) = source_points.row(s);
    }
    auto write = [&](size_t i, const int32_t* local, int count) {
      for (int j = 0; j < count; ++j) {
        out.index(rows[i], j) = object->global[static_cast<size_t>(local[j])];
        out.mask(rows[i], j) = 1;
      }
    };
    auto search = [&](size_t i, std::vector<Neighbor>& found) {
      object->tree.knn(current.row(static_cast<Eigen::Index>(i)).transpose(), k, found);
      for (size_t j = 0; j < found.size(); ++j) {
        out.index(rows[i], static_cast<Eigen::Index>(j)) =
            object->global[static_cast<size_t>(found[j].index)];
        out.mask(rows[i], static_cast<Eigen::Index>(j)) = 1;
      }
    };

    Entry* cached = nullptr;
    for (Entry& e : previous) {
      if (e.id == id && e.k == k && e.query_origin == q_origin && e.source_origin == s_origin) {
        cached = &e;
      }
    }
    // A row is certified when its stored neighbours' consecutive distances are more than twice
    // the bound apart: then no two of them, nor the last stored one and any farther source, can
    // have changed places.
    std::vector<uint8_t> certified(nq, 0);
    size_t uncertified = nq;
    if (cached != nullptr && cached->anchored) {
      const auto [absolute, relative] = motion_bound(cached->anchor, current);
      uncertified = 0;
      for (size_t i = 0; i < nq; ++i) {
        const double bound = absolute + relative * cached->farthest[i];
        certified[i] = cached->gap[i] > 2.0 * bound ? 1 : 0;
        uncertified += certified[i] ? 0 : 1;
      }
    }

    if (cached == nullptr) {
      // Points that were not there at the last step (a new object, or the voxel grid kept other
      // points of a moving one): a plain search, remembering the points. Only a list whose points
      // come back at the next step is anchored, so objects that keep moving pay no more than a
      // fresh search.
      for_rows(nq, search);
      next.emplace_back(id, k, std::move(q_origin), std::move(s_origin), std::move(current));
      searched_rows_ += static_cast<int64_t>(nq);
      continue;
    }
    if (!cached->anchored ||
        static_cast<double>(uncertified) > kMaxUncertifiedFraction * static_cast<double>(nq)) {
      // Search every row afresh with one more neighbour and anchor the list here.
      Entry e(id, k, std::move(q_origin), std::move(s_origin), std::move(current));
      e.anchored = true;
      e.width = static_cast<int>(std::min(static_cast<size_t>(k) + 1, ns));
      e.nearest.assign(nq * static_cast<size_t>(e.width), 0);
      e.farthest.assign(nq, 0.0);
      e.gap.assign(nq, kInf);
      const int listed = std::min(k, e.width);
      for_rows(nq, [&](size_t i, std::vector<Neighbor>& found) {
        object->tree.knn(e.anchor.row(static_cast<Eigen::Index>(i)).transpose(), e.width, found);
        int32_t* nearest = &e.nearest[i * static_cast<size_t>(e.width)];
        double last = 0.0;
        for (int j = 0; j < e.width; ++j) {
          nearest[j] = found[static_cast<size_t>(j)].index;
          const double d = std::sqrt(found[static_cast<size_t>(j)].sq_dist);
          if (j > 0) e.gap[i] = std::min(e.gap[i], d - last);
          last = d;
        }
        e.farthest[i] = last;
        write(i, nearest, listed);
      });
      searched_rows_ += static_cast<int64_t>(nq);
      next.push_back(std::move(e));
      continue;
    }

    const int listed = std::min(k, cached->width);
    for_rows(nq, [&](size_t i, std::vector<Neighbor>& found) {
      if (certified[i]) {
        write(i, &cached->nearest[i * static_cast<size_t>(cached->width)], listed);
      } else {
        search(i, found);
      }
    });
    reused_rows_ += static_cast<int64_t>(nq - uncertified);
    searched_rows_ += static_cast<int64_t>(uncertified);
    next.push_back(std::move(*cached));
  }
  previous = std::move(next);
  return out;
}

}  // namespace dynscope
