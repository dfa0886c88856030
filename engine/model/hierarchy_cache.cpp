// HierarchyCache: certified reuse of same-object lists under rigid motion.
#include "engine/model/hierarchy_cache.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "engine/core/parallel.h"
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
constexpr int64_t kMinParallelRows = 256;
// Runs of rows per scheduling chunk.
constexpr int64_t kRunChunk = 8;

// The query rows of each object id, in ascending row order, ordered by id.
std::vector<std::pair<int32_t, std::vector<Eigen::Index>>> rows_by_object(
    const std::vector<int32_t>& ids) {
  std::vector<std::pair<int32_t, std::vector<Eigen::Index>>> out;
  for (const int32_t row : rows_by_id(ids)) {
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
  const Vec3& t = motion.position;
  // The largest residual (its square, one root at the end) and the largest coordinate, in one
  // pass over both point sets.
  double worst = 0.0, extent = t.cwiseAbs().maxCoeff();
  const double* a = anchor.data();  // row-major x, y, z
  const double* c = current.data();
  for (Eigen::Index i = 0; i < anchor.rows(); ++i, a += 3, c += 3) {
    const double ex = r(0, 0) * a[0] + r(0, 1) * a[1] + r(0, 2) * a[2] + t.x() - c[0];
    const double ey = r(1, 0) * a[0] + r(1, 1) * a[1] + r(1, 2) * a[2] + t.y() - c[1];
    const double ez = r(2, 0) * a[0] + r(2, 1) * a[1] + r(2, 2) * a[2] + t.z() - c[2];
    worst = std::max(worst, ex * ex + ey * ey + ez * ez);
    extent = std::max({extent, std::abs(a[0]), std::abs(a[1]), std::abs(a[2]), std::abs(c[0]),
                       std::abs(c[1]), std::abs(c[2])});
  }
  const double absolute = 2.0 * std::sqrt(worst) + kRoundingSlack * (1.0 + extent);
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
                                              const std::vector<int32_t>& source_origin, int k,
                                              const ObjectIndex* queries) {
  NeighborList out;
  out.index = IndexMatrix::Constant(query.rows(), k, -1);
  out.mask = MaskMatrix::Zero(query.rows(), k);
  if (slot >= static_cast<int>(slots_.size())) slots_.resize(static_cast<size_t>(slot) + 1);
  std::vector<Entry>& previous = slots_[static_cast<size_t>(slot)];

  // First, object by object: which rows can be reused, and which entry each object keeps.
  enum class Mode {
    kSearch,  // new points: plain search, the points remembered
    kAnchor,  // search with one more neighbour and anchor the entry
    kReuse,   // certified rows from the entry, the others searched
  };
  struct Plan {
    const ObjectIndex::Object* object;
    // With every row searched and the queries indexed: the queries' object (its local indices
    // ascend with the rows, as `rows` do), answered a leaf at a time; else nullptr.
    const ObjectIndex::Object* query_object;
    std::vector<Eigen::Index> rows;
    Points current;  // query points, then source points
    Mode mode;
    size_t entry;                    // index into `next`
    std::vector<uint8_t> certified;  // kReuse only
  };
  std::vector<Plan> plans;
  std::vector<Entry> next;
  for (auto& [id, rows] : rows_by_object(query_ids)) {
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
    Entry* cached = nullptr;
    for (Entry& e : previous) {
      if (e.id == id && e.k == k && e.query_origin == q_origin && e.source_origin == s_origin) {
        cached = &e;
      }
    }
    Plan plan{object, nullptr, std::move(rows), {}, Mode::kSearch, next.size(), {}};
    if (cached == nullptr) {
      // Points that were not there at the last step (a new object, or the voxel grid kept other
      // points of a moving one): a plain search, remembering the points. Only a list whose points
      // come back at the next step is anchored, so objects that keep moving pay no more than a
      // fresh search.
      next.emplace_back(id, k, std::move(q_origin), std::move(s_origin), current);
      searched_rows_ += static_cast<int64_t>(nq);
    } else {
      // A row is certified when its stored neighbours' consecutive distances are more than twice
      // the bound apart: then no two of them, nor the last stored one and any farther source,
      // can have changed places.
      size_t uncertified = nq;
      if (cached->anchored) {
        const auto [absolute, relative] = motion_bound(cached->anchor, current);
        plan.certified.assign(nq, 0);
        uncertified = 0;
        for (size_t i = 0; i < nq; ++i) {
          const double bound = absolute + relative * cached->farthest[i];
          plan.certified[i] = cached->gap[i] > 2.0 * bound ? 1 : 0;
          uncertified += plan.certified[i] ? 0 : 1;
        }
      }
      if (!cached->anchored ||
          static_cast<double>(uncertified) > kMaxUncertifiedFraction * static_cast<double>(nq)) {
        plan.mode = Mode::kAnchor;
        Entry e(id, k, std::move(q_origin), std::move(s_origin), current);
        e.anchored = true;
        e.width = static_cast<int>(std::min(static_cast<size_t>(k) + 1, ns));
        e.nearest.assign(nq * static_cast<size_t>(e.width), 0);
        e.farthest.assign(nq, 0.0);
        e.gap.assign(nq, kInf);
        next.push_back(std::move(e));
        searched_rows_ += static_cast<int64_t>(nq);
      } else {
        plan.mode = Mode::kReuse;
        next.push_back(std::move(*cached));
        reused_rows_ += static_cast<int64_t>(nq - uncertified);
        searched_rows_ += static_cast<int64_t>(uncertified);
      }
    }
    if (queries != nullptr && plan.mode != Mode::kReuse) {
      const ObjectIndex::Object* own = queries->find(id);
      if (own != nullptr && own->global.size() == nq) plan.query_object = own;
    }
    plan.current = std::move(current);
    plans.push_back(std::move(plan));
  }

  // Then every row of every object in one parallel loop over runs (objects are often too small for
  // a parallel loop of their own): of an object with indexed queries, one leaf of its queries
  // (KdIndex::knn_other); of the others, up to KdIndex::kBatchRows rows, whose searches go to the
  // object's index together (KdIndex::knn_rows).
  constexpr size_t kRun = KdIndex::kBatchRows;
  std::vector<int64_t> offset(plans.size() + 1, 0);  // each plan's first run
  int64_t total = 0;
  for (size_t p = 0; p < plans.size(); ++p) {
    const size_t runs = plans[p].query_object != nullptr ? plans[p].query_object->tree.self_groups()
                                                         : (plans[p].rows.size() + kRun - 1) / kRun;
    offset[p + 1] = offset[p] + static_cast<int64_t>(runs);
    total += static_cast<int64_t>(plans[p].rows.size());
  }
  const int64_t runs = offset.back();
  parallel_chunks(runs, kRunChunk, total >= kMinParallelRows, [&](int64_t first, int64_t end_run) {
    thread_local std::vector<Neighbor> found;  // a chunk runs on one thread without pause
    std::array<double, 3 * kRun> queries;
    std::array<size_t, kRun> searched;  // the run's rows that are searched
    for (int64_t r = first; r < end_run; ++r) {
      const auto p = static_cast<size_t>(std::upper_bound(offset.begin(), offset.end(), r) -
                                         offset.begin() - 1);
      const Plan& plan = plans[p];
      Entry& entry = next[plan.entry];
      const std::vector<int32_t>& global = plan.object->global;
      const bool anchor = plan.mode == Mode::kAnchor;
      const int width = anchor ? entry.width : k;
      // Writes row i's found neighbours (`stride` of them) and, when anchoring, its entry.
      auto store = [&](size_t i, const Neighbor* nearest, size_t stride) {
        const Eigen::Index row = plan.rows[i];
        const size_t kept = std::min(stride, static_cast<size_t>(k));
        int32_t* index = out.index.data() + row * k;  // row-major rows of k
        for (size_t j = 0; j < kept; ++j) index[j] = global[static_cast<size_t>(nearest[j].index)];
        std::fill_n(out.mask.data() + row * k, kept, uint8_t{1});
        if (!anchor) return;
        int32_t* stored = &entry.nearest[i * static_cast<size_t>(entry.width)];
        double last = 0.0;
        for (size_t j = 0; j < stride; ++j) {
          stored[j] = nearest[j].index;
          const double d = std::sqrt(nearest[j].sq_dist);
          if (j > 0) entry.gap[i] = std::min(entry.gap[i], d - last);
          last = d;
        }
        entry.farthest[i] = last;
      };
      if (plan.query_object != nullptr) {
        plan.query_object->tree.knn_other(
            static_cast<size_t>(r - offset[p]), plan.object->tree, width, found,
            [&](Eigen::Index local, const Neighbor* nearest, size_t count) {
              store(static_cast<size_t>(local), nearest, count);
            });
        continue;
      }
      const size_t begin = static_cast<size_t>(r - offset[p]) * kRun;
      const size_t end = std::min(begin + kRun, plan.rows.size());
      size_t count = 0;
      for (size_t i = begin; i < end; ++i) {
        const Eigen::Index row = plan.rows[i];
        if (plan.mode == Mode::kReuse && plan.certified[i]) {
          const int32_t* stored = &entry.nearest[i * static_cast<size_t>(entry.width)];
          int32_t* index = out.index.data() + row * k;  // row-major rows of k
          const int count = std::min(k, entry.width);
          for (int j = 0; j < count; ++j) index[j] = global[static_cast<size_t>(stored[j])];
          std::fill_n(out.mask.data() + row * k, count, uint8_t{1});
          continue;
        }
        for (int c = 0; c < 3; ++c) {
          queries[3 * count + static_cast<size_t>(c)] =
              plan.current(static_cast<Eigen::Index>(i), c);
        }
        searched[count++] = i;
      }
      if (count == 0) continue;
      found.resize(count * static_cast<size_t>(width));
      const size_t stride = plan.object->tree.knn_rows(queries.data(), count, width, found.data());
      for (size_t c = 0; c < count; ++c) store(searched[c], found.data() + c * stride, stride);
    }
  });
  previous = std::move(next);
  return out;
}

}  // namespace dynscope
