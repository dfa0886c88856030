// Hierarchy construction: per-object grid downsampling and the neighbour lists of every level.
#include "engine/model/hierarchy.h"

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "engine/core/error.h"
#include "engine/core/parallel.h"
#include "engine/geometry/grid_downsample.h"

namespace dynscope {

HierarchyOptions HierarchyOptions::from_config(const ModelConfig& config) {
  HierarchyOptions o;
  o.levels = config.levels;
  o.voxel = config.voxel;
  o.radius = config.radius;
  o.growth = config.growth;
  o.k = config.k;
  o.k_relational = config.k_relational;
  o.object_centric = config.kind != ModelKind::kFlat;
  o.point_relational = config.input == InputMode::kPoints;
  o.relational_top_only = config.relational_top_only;
  o.interaction_threshold = config.interaction_threshold;
  o.interaction_lattice = config.interaction_lattice;
  o.interaction_spacing = config.interaction_spacing;
  return o;
}

bool HierarchyOptions::point_relational_at(int level) const {
  return point_relational &&
         relates_objects_at(level, object_centric, point_relational, relational_top_only);
}

namespace {

void check_options(const HierarchyOptions& o) {
  if (o.levels < 1) throw ValueError("levels", "must be >= 1, got " + std::to_string(o.levels));
  if (!(o.voxel > 0) || !std::isfinite(o.voxel)) throw ValueError("voxel", "must be > 0");
  if (!(o.radius > 0) || !std::isfinite(o.radius)) throw ValueError("radius", "must be > 0");
  if (!(o.growth >= 1.0) || !std::isfinite(o.growth)) throw ValueError("growth", "must be >= 1");
  if (o.k < 1) throw ValueError("k", "must be >= 1, got " + std::to_string(o.k));
  if (o.k_relational < 1) throw ValueError("k_relational", "must be >= 1");
}

Points select_rows(const Points& points, const std::vector<int32_t>& rows) {
  Points out(static_cast<Eigen::Index>(rows.size()), 3);
  for (size_t i = 0; i < rows.size(); ++i)
    out.row(static_cast<Eigen::Index>(i)) = points.row(rows[i]);
  return out;
}

std::vector<int32_t> select_ids(const std::vector<int32_t>& ids, const std::vector<int32_t>& rows) {
  std::vector<int32_t> out(rows.size());
  for (size_t i = 0; i < rows.size(); ++i) out[i] = ids[static_cast<size_t>(rows[i])];
  return out;
}

// The rows `rows` of `list`, in that order.
NeighborList select_list_rows(const NeighborList& list, const std::vector<int32_t>& rows) {
  NeighborList out;
  out.index.resize(static_cast<Eigen::Index>(rows.size()), list.k());
  out.mask.resize(static_cast<Eigen::Index>(rows.size()), list.k());
  for (size_t i = 0; i < rows.size(); ++i) {
    out.index.row(static_cast<Eigen::Index>(i)) = list.index.row(rows[i]);
    out.mask.row(static_cast<Eigen::Index>(i)) = list.mask.row(rows[i]);
  }
  return out;
}

// The source trees of one level, built once and read by every list searched over that level's
// points (its up and relational lists, and level 0's same list).
class LevelIndex {
 public:
  LevelIndex(const HierarchyOptions& o, const HierarchyLevel& level) {
    if (o.object_centric) {
      objects_ = std::make_unique<ObjectIndex>(level.points, level.object_ids);
    } else {
      all_ = std::make_unique<KdIndex>(level.points, "source");
    }
  }

  // Same-object kNN for the paper's model, plain kNN for the flat baseline.
  NeighborList object_list(const HierarchyOptions& o, const HierarchyLevel& query) const {
    if (objects_) return knn_same_object(query.points, query.object_ids, *objects_, o.k);
    return knn_all(query.points, *all_, o.k);
  }

  // This level's points' same-object kNN from the finer level's points (its up list), the finer
  // level's trees grouping the queries; plain kNN for the flat baseline.
  NeighborList up_list(const HierarchyOptions& o, const LevelIndex& finer,
                       const HierarchyLevel& finer_level) const {
    if (objects_) return knn_same_object(*finer.objects_, *objects_, o.k);
    return knn_all(finer_level.points, *all_, o.k);
  }

  // The level's per-object trees (object-centric levels only).
  const ObjectIndex* objects() const { return objects_.get(); }

  // Other-object kNN within `radius` (object-centric levels only).
  NeighborList relational_list(const HierarchyOptions& o, const HierarchyLevel& query) const {
    return knn_other_objects(query.points, query.object_ids, *objects_, o.k_relational,
                             query.radius);
  }

 private:
  std::unique_ptr<ObjectIndex> objects_;
  std::unique_ptr<KdIndex> all_;
};

// The levels of `h`, from the finest up. Each level depends on the one before, but a level's
// relational list only on its points and trees: it is started as a task (its error kept in
// `errors`) that runs beside the rest of the chain when the compute threads are shared
// (on_compute_threads); the caller waits for the tasks. `indices` receives each level's trees.
void build_levels(const Points& points, const std::vector<int32_t>& object_ids,
                  const HierarchyOptions& options, HierarchyCache* cache,
                  std::vector<std::unique_ptr<LevelIndex>>& indices, TaskErrors& errors,
                  Hierarchy& h) {
  // With a cache: the level-0 point each point of the current and the previous level is.
  const bool cached = cache != nullptr && options.object_centric;
  std::vector<int32_t> origin, prev_origin;
  auto slot = [](int l, LevelList list) { return 4 * l + static_cast<int>(list); };
  for (int l = 0; l < options.levels; ++l) {
    HierarchyLevel& level = h.levels[static_cast<size_t>(l)];
    level.radius = options.radius * std::pow(options.growth, l);
    if (l == 0) {
      level.points = points;
      level.object_ids = object_ids;
    } else {
      const HierarchyLevel& prev = h.levels[static_cast<size_t>(l - 1)];
      level.voxel = options.voxel * std::pow(options.growth, l - 1);
      // Shift into the anchored frame so the selection is invariant to x/y translation.
      Points shifted = prev.points;
      shifted.rowwise() -= h.grid_anchor.transpose();
      level.kept = options.object_centric
                       ? grid_downsample_per_object(shifted, prev.object_ids, level.voxel)
                       : grid_downsample(shifted, level.voxel);
      level.points = select_rows(prev.points, level.kept);
      level.object_ids = select_ids(prev.object_ids, level.kept);
    }
    indices[static_cast<size_t>(l)] = std::make_unique<LevelIndex>(options, level);
    const LevelIndex* index = indices[static_cast<size_t>(l)].get();
    if (options.point_relational_at(l)) {
      // The task reads the level's points, ids and radius, which the chain no longer writes, and
      // writes only the level's relational list.
      HierarchyLevel* out = &level;
      TaskErrors* task_errors = &errors;
      const HierarchyOptions* o = &options;
#pragma omp task firstprivate(out, task_errors, o, index)
      task_errors->run([&] { out->relational = index->relational_list(*o, *out); });
    }
    if (cached) {
      prev_origin = std::move(origin);
      origin.resize(level.object_ids.size());
      for (size_t i = 0; i < origin.size(); ++i) {
        origin[i] =
            l == 0 ? static_cast<int32_t>(i) : prev_origin[static_cast<size_t>(level.kept[i])];
      }
    }
    if (l == 0) {
      level.same =
          cached ? cache->same_object_list(slot(l, LevelList::kSame), level.points,
                                           level.object_ids, origin, level.points,
                                           *index->objects(), origin, options.k, index->objects())
                 : index->object_list(options, level);
    } else {
      // Every point of this level is point kept[i] of the previous one, with its object id, and
      // the down, up and same lists share K and their sources' indexing. So two of the three are
      // rows of lists searched anyway: this level's down list is the previous level's same list
      // at the kept rows (same queries, same sources), and its same list is its up list at the
      // kept rows (queries among the previous level's points, sources this level's).
      const HierarchyLevel& prev = h.levels[static_cast<size_t>(l - 1)];
      level.down = select_list_rows(prev.same, level.kept);
      const LevelIndex& finer = *indices[static_cast<size_t>(l - 1)];
      level.up = cached ? cache->same_object_list(
                              slot(l, LevelList::kUp), prev.points, prev.object_ids, prev_origin,
                              level.points, *index->objects(), origin, options.k, finer.objects())
                        : index->up_list(options, finer, prev);
      level.same = select_list_rows(level.up, level.kept);
    }
  }
}

}  // namespace

Hierarchy build_hierarchy(const Points& points, const std::vector<int32_t>& object_ids,
                          const HierarchyOptions& options, HierarchyCache* cache) {
  check_options(options);
  if (points.rows() == 0) throw ValueError("points", "no points");
  if (static_cast<Eigen::Index>(object_ids.size()) != points.rows()) {
    throw ValueError("object_ids", "has " + std::to_string(object_ids.size()) + " entries for " +
                                       std::to_string(points.rows()) + " points");
  }
  if (!points.allFinite()) throw ValueError("points", "non-finite position");

  Hierarchy h;
  h.grid_anchor = Vec3(points.col(0).minCoeff(), points.col(1).minCoeff(), 0.0);
  h.levels.resize(static_cast<size_t>(options.levels));
  // The levels' trees, which the relational tasks read until they have all finished.
  std::vector<std::unique_ptr<LevelIndex>> indices(static_cast<size_t>(options.levels));
  TaskErrors errors;
  on_compute_threads([&] {
    errors.run([&] { build_levels(points, object_ids, options, cache, indices, errors, h); });
    // Also after an error: the tasks read the levels and trees, which must outlive them.
#pragma omp taskwait
  });
  errors.rethrow();
  return h;
}

Hierarchy build_mesh_hierarchy(const Points& vertices, const std::vector<int32_t>& object_ids,
                               const Faces& faces, const HierarchyOptions& options,
                               HierarchyCache* cache) {
  Hierarchy h = build_hierarchy(vertices, object_ids, options, cache);
  h.mesh = build_mesh_interaction(vertices, object_ids, faces, options.interaction_threshold,
                                  options.interaction_lattice, options.k_relational,
                                  options.interaction_spacing);
  h.has_mesh = true;
  return h;
}

const char* level_list_name(LevelList list) {
  switch (list) {
    case LevelList::kSame:
      return "same";
    case LevelList::kRelational:
      return "relational";
    case LevelList::kDown:
      return "down";
    case LevelList::kUp:
      return "up";
  }
  return "";
}

const NeighborList& level_list(const HierarchyLevel& level, LevelList list) {
  switch (list) {
    case LevelList::kSame:
      return level.same;
    case LevelList::kRelational:
      return level.relational;
    case LevelList::kDown:
      return level.down;
    case LevelList::kUp:
      break;
  }
  return level.up;
}

int list_query_level(LevelList list, int l) { return list == LevelList::kUp ? l - 1 : l; }
int list_source_level(LevelList list, int l) { return list == LevelList::kDown ? l - 1 : l; }

std::string level_list_path(int l, LevelList list) {
  return std::to_string(l) + "/" + level_list_name(list);
}

const char* mesh_list_name(MeshList list) {
  switch (list) {
    case MeshList::kFaceVertices:
      return "face_vertices";
    case MeshList::kSenders:
      return "senders";
    case MeshList::kVertexPoints:
      return "vertex_points";
  }
  return "";
}

const NeighborList& mesh_list(const MeshInteraction& mesh, MeshList list) {
  switch (list) {
    case MeshList::kFaceVertices:
      return mesh.face_vertices;
    case MeshList::kSenders:
      return mesh.senders;
    case MeshList::kVertexPoints:
      break;
  }
  return mesh.vertex_points;
}

int mesh_list_query_level(MeshList list) { return list == MeshList::kVertexPoints ? 0 : -1; }
int mesh_list_source_level(MeshList list) { return list == MeshList::kFaceVertices ? 0 : -1; }

Hierarchy build_model_hierarchy(const Points& points, const std::vector<int32_t>& object_ids,
                                const Faces& faces, const ModelConfig& config,
                                HierarchyCache* cache) {
  const HierarchyOptions options = HierarchyOptions::from_config(config);
  if (config.input == InputMode::kMesh) {
    if (faces.rows() == 0) throw ValueError("faces", "mesh input needs faces");
    return build_mesh_hierarchy(points, object_ids, faces, options, cache);
  }
  return build_hierarchy(points, object_ids, options, cache);
}

}  // namespace dynscope
