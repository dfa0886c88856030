// The U-Net's multi-level point hierarchy and its neighbour lists (plain data, no torch).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/types.h"
#include "engine/geometry/neighbors.h"
#include "engine/model/hierarchy_cache.h"
#include "engine/model/mesh_interaction.h"
#include "engine/model/model_config.h"

namespace dynscope {

/// How the hierarchy is built; from_config() takes the model's values.
struct HierarchyOptions {
  int levels = 4;                ///< Levels including level 0 (the input points).
  double voxel = 0.075;          ///< Voxel edge of level 1; level l uses voxel·growth^(l−1).
  double radius = 0.1;           ///< Relational radius of level 0; level l uses radius·growth^l.
  double growth = 1.5;           ///< Per-level factor of voxel and radius.
  int k = 16;                    ///< Neighbours of object / resampling / flat lists.
  int k_relational = 16;         ///< Neighbours of relational lists before the radius filter.
  bool object_centric = true;    ///< false: flat baseline (knn_all lists, no relational lists,
                                 ///< downsampling ignores object ids).
  bool point_relational = true;  ///< Build the point relational lists (false for mesh input,
                                 ///< whose relational path runs through interaction points).
  bool relational_top_only = false;    ///< Point relational lists at level 0 only (the model has
                                       ///< no relational units below it).
  double interaction_threshold = 0.1;  ///< Mesh input: interaction distance.
  int interaction_lattice = 3;         ///< Mesh input: lattice samples per face edge.
  double interaction_spacing = 0.0;    ///< Mesh input: > 0 samples longer faces more densely.

  /// Options matching a model configuration (object_centric is false for ModelKind::kFlat).
  static HierarchyOptions from_config(const ModelConfig& config);
  /// Whether `level` gets a point relational list: point input at a level that relates objects
  /// (relates_objects_at, the rule ModelConfig::has_relational follows).
  bool point_relational_at(int level) const;
};

/// One level: its points and every neighbour list a forward pass uses there.
/// Lists index points of the level named in their comment; see NeighborList for the layout.
struct HierarchyLevel {
  Points points = Points(0, 3);     ///< `[N_l,3]` world positions.
  std::vector<int32_t> object_ids;  ///< `[N_l]` object id of each point.
  std::vector<int32_t> kept;  ///< `[N_l]` index of each point in level l−1 (empty at level 0).
  double voxel = 0.0;         ///< Voxel edge that produced this level (0 at level 0).
  double radius = 0.0;        ///< Relational radius at this level.
  NeighborList same;          ///< Queries and sources: this level; same object (flat: any object).
  NeighborList relational;    ///< Queries and sources: this level; other objects within `radius`
                              ///< (empty for the flat baseline and for mesh input).
  NeighborList down;  ///< Queries: this level; sources: level l−1 (downsampling; empty at 0).
  NeighborList up;    ///< Queries: level l−1; sources: this level (upsampling; empty at 0).
};

/// Levels 0..L−1, finest first. Level l+1 keeps one point of level l per occupied voxel.
struct Hierarchy {
  std::vector<HierarchyLevel> levels;
  /// The voxel grids are anchored at (min x, min y, 0) of the level-0 points, so translating a
  /// scene in x and y selects the same points (z stays anchored at the floor, z = 0).
  Vec3 grid_anchor = Vec3::Zero();
  /// Mesh input only: interaction points between faces of level 0 (see MeshInteraction).
  bool has_mesh = false;
  MeshInteraction mesh;

  int num_levels() const { return static_cast<int>(levels.size()); }
};

/// The neighbour lists of a level, by the names traces, trace files, views and the inspector use
/// (one definition; a trace query's list is "<level>/<name>").
enum class LevelList { kSame, kRelational, kDown, kUp };
inline constexpr LevelList kLevelLists[] = {LevelList::kSame, LevelList::kRelational,
                                            LevelList::kDown, LevelList::kUp};
/// "same", "relational", "down", "up".
const char* level_list_name(LevelList list);
/// The list `list` of `level`.
const NeighborList& level_list(const HierarchyLevel& level, LevelList list);
/// Level of the queries and of the sources of `list` at level `l` (down: l, l−1; up: l−1, l).
int list_query_level(LevelList list, int l);
int list_source_level(LevelList list, int l);
/// "<l>/<name>": how a trace query names the list it read.
std::string level_list_path(int l, LevelList list);

/// The interaction-point lists of mesh input (MeshInteraction), by their trace names; levels
/// −1 (interaction points) and 0 (vertices).
enum class MeshList { kFaceVertices, kSenders, kVertexPoints };
inline constexpr MeshList kMeshLists[] = {MeshList::kFaceVertices, MeshList::kSenders,
                                          MeshList::kVertexPoints};
/// "face_vertices", "senders", "vertex_points".
const char* mesh_list_name(MeshList list);
const NeighborList& mesh_list(const MeshInteraction& mesh, MeshList list);
int mesh_list_query_level(MeshList list);   ///< −1, −1, 0
int mesh_list_source_level(MeshList list);  ///< 0, −1, −1

/// Builds the hierarchy of `points` `[N,3]` with `object_ids` `[N]`. Throws ValueError on size
/// mismatch, no points, non-finite values or options out of range. With a `cache` (one per
/// rollout) the searched same-object lists of objects that moved rigidly since they were searched
/// over the same points are reused where certified (HierarchyCache); the result is the same as
/// without it. Level l's down list is level l−1's same list at the kept rows, and its same list
/// its up list at the kept rows (each level-l point is a level-(l−1) point): searched once.
Hierarchy build_hierarchy(const Points& points, const std::vector<int32_t>& object_ids,
                          const HierarchyOptions& options, HierarchyCache* cache = nullptr);

/// The same over mesh vertices `[V,3]`, plus the interaction-point lists of `faces` `[F,3]` at
/// level 0 (options.interaction_threshold, options.interaction_lattice, options.k_relational).
/// Throws ValueError as build_hierarchy and for face indices out of range.
Hierarchy build_mesh_hierarchy(const Points& vertices, const std::vector<int32_t>& object_ids,
                               const Faces& faces, const HierarchyOptions& options,
                               HierarchyCache* cache = nullptr);

/// The hierarchy a model of `config` builds (one rule for the model, traces and level views):
/// build_mesh_hierarchy over `faces` for mesh input (ValueError "faces" when there are none),
/// else build_hierarchy; options from HierarchyOptions::from_config.
Hierarchy build_model_hierarchy(const Points& points, const std::vector<int32_t>& object_ids,
                                const Faces& faces, const ModelConfig& config,
                                HierarchyCache* cache = nullptr);

}  // namespace dynscope
