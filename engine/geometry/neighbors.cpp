// Same-object, other-object and plain kNN built on one exact kd-tree per object, queried in
// parallel.
#include "engine/geometry/neighbors.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <optional>
#include <string>
#include <utility>

#include "engine/core/error.h"
#include "engine/core/parallel.h"

namespace dynscope {
namespace {

// Below this many queries a parallel region costs more than it saves.
constexpr Eigen::Index kMinParallelQueries = 256;
// Queries per scheduling chunk: large enough to amortise scheduling, small enough that a thread
// slowed down by a busy core does not hold the others up.
constexpr int kQueryChunk = 64;
// Groups of queries (or trees) per scheduling chunk.
constexpr int kGroupChunk = 4;

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

void check_radius(double radius) {
  if (!std::isfinite(radius) || radius < 0.0) {
    throw ValueError("radius", "must be finite and >= 0, got " + std::to_string(radius));
  }
}

NeighborList empty_list(Eigen::Index rows, int k) {
  NeighborList out;
  out.index = IndexMatrix::Constant(rows, k, -1);
  out.mask = MaskMatrix::Zero(rows, k);
  return out;
}

void write_row(NeighborList& out, Eigen::Index row, const Neighbor* found, size_t count,
               const std::vector<int32_t>* global) {
  // Through plain pointers into the row-major rows: the stores then cannot alias the matrices'
  // own data pointers and sizes, which the element accessors would reload after every store.
  int32_t* index = out.index.data() + row * out.index.cols();
  if (global != nullptr) {
    for (size_t j = 0; j < count; ++j) index[j] = (*global)[static_cast<size_t>(found[j].index)];
  } else {
    for (size_t j = 0; j < count; ++j) index[j] = found[j].index;
  }
  std::fill_n(out.mask.data() + row * out.mask.cols(), count, uint8_t{1});
}

void write_row(NeighborList& out, Eigen::Index row, const std::vector<Neighbor>& found,
               const std::vector<int32_t>* global) {
  write_row(out, row, found.data(), found.size(), global);
}

double squared_distance_to_box(const Vec3& p, const Aabb& box) {
  return squared_box_distance(p.data(), p.data(), box.min.data(), box.max.data());
}

// Calls answer(row, found, merged) for every query row, in parallel over chunks of rows on the
// compute threads (parallel_chunks). Each row is answered on its own with its chunk's scratch,
// so the result does not depend on the thread count or the schedule. `answer` must not throw
// (inputs are checked first).
template <typename Answer>
void for_each_query(Eigen::Index rows, const Answer& answer) {
  parallel_chunks(rows, kQueryChunk, rows >= kMinParallelQueries, [&](int64_t begin, int64_t end) {
    std::vector<Neighbor> found, merged;
    for (int64_t i = begin; i < end; ++i) answer(i, found, merged);
  });
}

// Calls task(i, scratch) for i in 0 .. tasks - 1 (groups of queries answered together by
// KdIndex::knn_self, or an ObjectIndex's trees), in parallel on the compute threads when there are
// `rows` >= kMinParallelQueries queries in all. Each group writes only its own rows.
template <typename Task>
void for_each_group(size_t tasks, Eigen::Index rows, const Task& task) {
  parallel_chunks(static_cast<int64_t>(tasks), kGroupChunk, rows >= kMinParallelQueries,
                  [&](int64_t begin, int64_t end) {
                    thread_local std::vector<Neighbor> scratch;
                    for (int64_t i = begin; i < end; ++i) task(static_cast<size_t>(i), scratch);
                  });
}

// The runs of `order` (rows_by_id(ids)) that share an id: [begin, end) positions, by id.
std::vector<std::pair<size_t, size_t>> id_runs(const std::vector<int32_t>& order,
                                               const std::vector<int32_t>& ids) {
  std::vector<std::pair<size_t, size_t>> runs;
  for (size_t begin = 0; begin < order.size();) {
    const int32_t id = ids[static_cast<size_t>(order[begin])];
    size_t end = begin;
    while (end < order.size() && ids[static_cast<size_t>(order[end])] == id) ++end;
    runs.emplace_back(begin, end);
    begin = end;
  }
  return runs;
}

// True when the queries are the tree's own points, in its order (a same-level list).
bool queries_are_indexed(const Points& query, const KdIndex& source) {
  if (query.rows() != source.size()) return false;
  for (Eigen::Index i = 0; i < query.rows(); ++i) {
    if (query.row(i).transpose() != source.point(i)) return false;
  }
  return true;
}

// True when the queries are exactly the indexed points, each with its object's id.
bool queries_are_indexed(const Points& query, const std::vector<int32_t>& query_ids,
                         const ObjectIndex& source) {
  if (query.rows() != source.size()) return false;
  for (const ObjectIndex::Object& object : source.objects()) {
    for (size_t j = 0; j < object.global.size(); ++j) {
      const int32_t row = object.global[j];
      if (query_ids[static_cast<size_t>(row)] != object.id ||
          query.row(row).transpose() != object.tree.point(static_cast<Eigen::Index>(j))) {
        return false;
      }
    }
  }
  return true;
}

// knn_same_object when the queries are the indexed points: each object's tree answers its own
// points a leaf at a time (KdIndex::knn_self), the same lists as one search per query.
NeighborList same_object_self_rows(const ObjectIndex& source, int k) {
  NeighborList out = empty_list(source.size(), k);
  std::vector<std::pair<const ObjectIndex::Object*, size_t>> groups;
  for (const ObjectIndex::Object& object : source.objects()) {
    for (size_t g = 0; g < object.tree.self_groups(); ++g) groups.emplace_back(&object, g);
  }
  for_each_group(groups.size(), source.size(), [&](size_t i, std::vector<Neighbor>& scratch) {
    const ObjectIndex::Object& object = *groups[i].first;
    object.tree.knn_self(
        groups[i].second, k, scratch, [&](Eigen::Index local, const Neighbor* found, size_t count) {
          write_row(out, object.global[static_cast<size_t>(local)], found, count, &object.global);
        });
  });
  return out;
}

// The rows of knn_same_object; inputs already checked.
NeighborList same_object_rows(const Points& query, const std::vector<int32_t>& query_ids,
                              const ObjectIndex& source, int k) {
  if (queries_are_indexed(query, query_ids, source)) return same_object_self_rows(source, k);
  NeighborList out = empty_list(query.rows(), k);
  // Runs of up to KdIndex::kBatchRows queries of one object, each run's searches given to its
  // object's index together (KdIndex::knn_rows).
  const std::vector<int32_t> order = rows_by_id(query_ids);
  std::vector<size_t> run_begin;
  for (const auto& [begin, end] : id_runs(order, query_ids)) {
    for (size_t at = begin; at < end; at += KdIndex::kBatchRows) run_begin.push_back(at);
  }
  run_begin.push_back(order.size());
  for_each_group(run_begin.size() - 1, query.rows(), [&](size_t r, std::vector<Neighbor>& found) {
    const size_t begin = run_begin[r], count = run_begin[r + 1] - begin;
    const ObjectIndex::Object* object = source.find(query_ids[static_cast<size_t>(order[begin])]);
    if (object == nullptr) return;
    std::array<double, 3 * KdIndex::kBatchRows> queries;
    for (size_t c = 0; c < count; ++c) {
      for (int d = 0; d < 3; ++d) {
        queries[3 * c + static_cast<size_t>(d)] = query(order[begin + c], d);
      }
    }
    found.resize(count * static_cast<size_t>(k));
    const size_t stride = object->tree.knn_rows(queries.data(), count, k, found.data());
    for (size_t c = 0; c < count; ++c) {
      write_row(out, order[begin + c], found.data() + c * stride, stride, &object->global);
    }
  });
  return out;
}

double squared_distance_between_boxes(const Aabb& a, const Aabb& b) {
  return squared_box_distance(a.min.data(), a.max.data(), b.min.data(), b.max.data());
}

// The rows of knn_other_objects; inputs already checked.
NeighborList other_object_rows(const Points& query, const std::vector<int32_t>& query_ids,
                               const ObjectIndex& source, int k, double radius) {
  NeighborList out = empty_list(query.rows(), k);
  const double sq_radius = radius * radius;
  // Per query object, the other objects whose box is within the radius of its queries' box: the
  // only ones any of its queries can reach (a scene's objects mostly touch one or two others).
  const std::vector<int32_t> order = rows_by_id(query_ids);
  std::vector<std::vector<const ObjectIndex::Object*>> reach;
  std::vector<uint32_t> reach_of(order.size());  // each query row's entry of `reach`
  for (const auto& [begin, end] : id_runs(order, query_ids)) {
    const int32_t own = query_ids[static_cast<size_t>(order[begin])];
    Aabb box;
    for (size_t at = begin; at < end; ++at) {
      box.extend(Vec3(query.row(order[at]).transpose()));
      reach_of[static_cast<size_t>(order[at])] = static_cast<uint32_t>(reach.size());
    }
    reach.emplace_back();
    for (const ObjectIndex::Object& object : source.objects()) {
      if (object.id != own && squared_distance_between_boxes(box, object.box) <= sq_radius) {
        reach.back().push_back(&object);
      }
    }
  }
  for_each_query(query.rows(), [&](Eigen::Index i, std::vector<Neighbor>& found,
                                   std::vector<Neighbor>& merged) {
    const std::vector<const ObjectIndex::Object*>& near = reach[reach_of[static_cast<size_t>(i)]];
    if (near.empty()) return;
    const Vec3 q = query.row(i).transpose();
    merged.clear();
    size_t answering = 0;  // objects that contributed
    for (const ObjectIndex::Object* object : near) {
      // Rounding is monotone, so a point's computed squared distance is never below its box's:
      // skipping boxes beyond the radius cannot lose a neighbour.
      if (squared_distance_to_box(q, object->box) > sq_radius) continue;
      // The exact k nearest of each other object within the radius contain the exact k nearest
      // of their union.
      object->tree.knn(q, k, found, sq_radius);
      answering += found.empty() ? 0 : 1;
      for (const Neighbor& n : found) {
        merged.push_back({n.sq_dist, object->global[static_cast<size_t>(n.index)]});
      }
    }
    // One object's answer is already in order (its local indices ascend with the source index).
    if (answering > 1) {
      std::sort(merged.begin(), merged.end(), [](const Neighbor& a, const Neighbor& b) {
        return a.sq_dist < b.sq_dist || (a.sq_dist == b.sq_dist && a.index < b.index);
      });
      if (merged.size() > static_cast<size_t>(k)) merged.resize(static_cast<size_t>(k));
    }
    write_row(out, i, merged, nullptr);
  });
  return out;
}

// The rows of knn_all; inputs already checked.
NeighborList all_rows(const Points& query, const KdIndex& source, int k) {
  NeighborList out = empty_list(query.rows(), k);
  if (queries_are_indexed(query, source)) {
    for_each_group(
        source.self_groups(), query.rows(), [&](size_t g, std::vector<Neighbor>& scratch) {
          source.knn_self(g, k, scratch, [&](Eigen::Index i, const Neighbor* found, size_t count) {
            write_row(out, i, found, count, nullptr);
          });
        });
    return out;
  }
  for_each_query(query.rows(),
                 [&](Eigen::Index i, std::vector<Neighbor>& found, std::vector<Neighbor>&) {
                   source.knn(query.row(i).transpose(), k, found);
                   write_row(out, i, found, nullptr);
                 });
  return out;
}

}  // namespace

std::vector<int32_t> rows_by_id(const std::vector<int32_t>& ids) {
  std::vector<int32_t> order(ids.size());
  if (ids.empty()) return order;
  const auto [lo, hi] = std::minmax_element(ids.begin(), ids.end());
  const int64_t span = static_cast<int64_t>(*hi) - static_cast<int64_t>(*lo) + 1;
  if (span > 2 * static_cast<int64_t>(ids.size()) + 1024) {
    for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int32_t>(i);
    std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) {
      return ids[static_cast<size_t>(a)] < ids[static_cast<size_t>(b)];
    });
    return order;
  }
  // Ids of a small range (an object's id is its index in the scene): a counting sort, stable.
  std::vector<int32_t> first(static_cast<size_t>(span) + 1, 0);
  for (const int32_t id : ids) ++first[static_cast<size_t>(id - *lo) + 1];
  for (size_t b = 1; b < first.size(); ++b) first[b] += first[b - 1];
  for (size_t i = 0; i < ids.size(); ++i) {
    int32_t& next = first[static_cast<size_t>(ids[i] - *lo)];
    order[static_cast<size_t>(next++)] = static_cast<int32_t>(i);
  }
  return order;
}

int NeighborList::valid_count(Eigen::Index row) const {
  int n = 0;
  for (Eigen::Index j = 0; j < mask.cols(); ++j) n += mask(row, j) != 0 ? 1 : 0;
  return n;
}

ObjectIndex::ObjectIndex(const Points& points, const std::vector<int32_t>& ids)
    : size_(points.rows()) {
  check_points(points, &ids, "source");
  // Group by id with one sort instead of a map: local indices follow ascending global order, so
  // tie-breaking by local index equals tie-breaking by global index.
  const std::vector<int32_t> order = rows_by_id(ids);
  const std::vector<std::pair<size_t, size_t>> ranges = id_runs(order, ids);  // per object
  // The objects' trees are independent: built on the compute threads like the queries
  // (for_each_group), each into its own slot, so the result does not depend on the thread count.
  // A tree's error (a coordinate beyond 1e18) is rethrown here, not inside the parallel region.
  std::vector<std::optional<Object>> built(ranges.size());
  std::vector<std::exception_ptr> failed(ranges.size());
  for_each_group(ranges.size(), size_, [&](size_t r, std::vector<Neighbor>&) {
    try {
      const auto [begin, end] = ranges[r];
      std::vector<int32_t> global(order.begin() + static_cast<std::ptrdiff_t>(begin),
                                  order.begin() + static_cast<std::ptrdiff_t>(end));
      Points local(static_cast<Eigen::Index>(global.size()), 3);
      for (size_t j = 0; j < global.size(); ++j) {
        local.row(static_cast<Eigen::Index>(j)) = points.row(global[j]);
      }
      const Aabb box = Aabb::of(local);
      const int32_t id = ids[static_cast<size_t>(order[begin])];
      built[r].emplace(Object{id, std::move(global), KdIndex(local, "source"), box});
    } catch (...) {
      failed[r] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : failed) {
    if (e) std::rethrow_exception(e);
  }
  objects_.reserve(built.size());
  for (std::optional<Object>& o : built) objects_.push_back(std::move(*o));
}

const ObjectIndex::Object* ObjectIndex::find(int32_t id) const {
  const auto it = std::lower_bound(objects_.begin(), objects_.end(), id,
                                   [](const Object& o, int32_t v) { return o.id < v; });
  return it != objects_.end() && it->id == id ? &*it : nullptr;
}

NeighborList knn_same_object(const Points& query, const std::vector<int32_t>& query_ids,
                             const Points& source, const std::vector<int32_t>& source_ids, int k) {
  check_k(k);
  check_points(query, &query_ids, "query");
  return same_object_rows(query, query_ids, ObjectIndex(source, source_ids), k);
}

NeighborList knn_same_object(const ObjectIndex& queries, const ObjectIndex& sources, int k) {
  check_k(k);
  NeighborList out = empty_list(queries.size(), k);
  // Every group of every query object that has source points (the others' rows stay masked).
  std::vector<std::pair<const ObjectIndex::Object*, size_t>> groups;
  std::vector<const ObjectIndex::Object*> source_of;  // per entry of `groups`
  for (const ObjectIndex::Object& object : queries.objects()) {
    const ObjectIndex::Object* source = sources.find(object.id);
    if (source == nullptr) continue;
    for (size_t g = 0; g < object.tree.self_groups(); ++g) {
      groups.emplace_back(&object, g);
      source_of.push_back(source);
    }
  }
  for_each_group(groups.size(), queries.size(), [&](size_t i, std::vector<Neighbor>& scratch) {
    const ObjectIndex::Object& object = *groups[i].first;
    const ObjectIndex::Object& source = *source_of[i];
    object.tree.knn_other(groups[i].second, source.tree, k, scratch,
                          [&](Eigen::Index local, const Neighbor* found, size_t count) {
                            write_row(out, object.global[static_cast<size_t>(local)], found, count,
                                      &source.global);
                          });
  });
  return out;
}

NeighborList knn_same_object(const Points& query, const std::vector<int32_t>& query_ids,
                             const ObjectIndex& source, int k) {
  check_k(k);
  check_points(query, &query_ids, "query");
  return same_object_rows(query, query_ids, source, k);
}

NeighborList knn_other_objects(const Points& query, const std::vector<int32_t>& query_ids,
                               const Points& source, const std::vector<int32_t>& source_ids, int k,
                               double radius) {
  check_k(k);
  check_radius(radius);
  check_points(query, &query_ids, "query");
  return other_object_rows(query, query_ids, ObjectIndex(source, source_ids), k, radius);
}

NeighborList knn_other_objects(const Points& query, const std::vector<int32_t>& query_ids,
                               const ObjectIndex& source, int k, double radius) {
  check_k(k);
  check_radius(radius);
  check_points(query, &query_ids, "query");
  return other_object_rows(query, query_ids, source, k, radius);
}

NeighborList knn_all(const Points& query, const Points& source, int k) {
  check_k(k);
  check_points(query, nullptr, "query");
  check_points(source, nullptr, "source");
  return all_rows(query, KdIndex(source, "source"), k);
}

NeighborList knn_all(const Points& query, const KdIndex& source, int k) {
  check_k(k);
  check_points(query, nullptr, "query");
  return all_rows(query, source, k);
}

}  // namespace dynscope
