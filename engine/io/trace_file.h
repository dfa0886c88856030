// Debug traces of one forward pass (plain data) and their HDF5 files, read by viewer and renderer.
//
// Layout (format "dynscope-trace", version 1; z up):
//   /                          attributes: format, format_version, up_axis "z", scene_path,
//                              checkpoint_path, model_config (JSON), frame, num_levels
//   /levels/L/                 one group per U-Net level L = 0..num_levels−1 (finest first);
//                              attributes voxel, radius
//     points       float64 [N_L,3]  world positions
//     object_ids   int32   [N_L]
//     kept         int32   [N_L]    index of each point in level L−1 (level 0: absent)
//     lists/NAME/  index int32 [M,K] (−1 where masked), mask uint8 [M,K]; attributes query_level,
//                  source_level. NAME ∈ same (same-object kNN; flat: plain kNN), relational
//                  (other objects within radius), down (queries L, sources L−1), up (queries
//                  L−1, sources L); empty lists are omitted
//   /mesh/                     mesh input only: faces int32 [F,3] over level-0 points,
//                              points float64 [I,3] interaction points, face int32 [I],
//                              object_ids int32 [I], lists/{face_vertices,senders,vertex_points}
//   /features/NAME             float64 [N_level] per-point L2 norm of the features after block
//                              NAME ("input", "stem.i", "encoder.i", "bottleneck.i",
//                              "decoder.i"); the group attribute NAME.level holds its level
//   /queries/Q/                one group per (query point, PointConv) pair, Q = 0,1,...;
//                              attributes point (level-0 index), conv (module path), level
//                              (query level), list (level/list name), query_index (row at
//                              that level); datasets neighbors int32 [K], mask uint8 [K],
//                              weights float64 [K,c_mid] = h(p_k − p_0) (zero where masked)
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/types.h"
#include "engine/scene/scene.h"

namespace dynscope {

/// A neighbour list of a trace: `[M,K]` indices (−1 masked) and mask, plus which levels it links.
struct TraceList {
  std::string name;  ///< level_list_name or mesh_list_name (engine/model/hierarchy.h).
  int query_level = 0;
  int source_level = 0;
  IndexMatrix index;
  MaskMatrix mask;
};

/// One U-Net level of a trace.
struct TraceLevel {
  Points points = Points(0, 3);     ///< `[N_L,3]` world positions.
  std::vector<int32_t> object_ids;  ///< `[N_L]`.
  std::vector<int32_t> kept;        ///< `[N_L]` index in level L−1 (empty at level 0).
  double voxel = 0.0;               ///< Voxel edge that produced the level (0 at level 0).
  double radius = 0.0;              ///< Relational radius.
  std::vector<TraceList> lists;     ///< Non-empty neighbour lists of the level.
};

/// Mesh input: faces over the level-0 points and the interaction-point lists.
struct TraceMesh {
  Faces faces = Faces(0, 3);
  Points points = Points(0, 3);  ///< `[I,3]` interaction points.
  std::vector<int32_t> face;     ///< `[I]` face of each interaction point.
  std::vector<int32_t> object_ids;
  std::vector<TraceList> lists;  ///< face_vertices, senders, vertex_points.
};

/// Per-point feature norms after one U-Net stage.
struct TraceFeatures {
  std::string block;  ///< Stage name (see BlockRecord).
  int level = 0;
  std::vector<double> norms;  ///< `[N_level]`.
};

/// Learned filter weights of one PointConv at one query point.
struct TraceQuery {
  int point = 0;        ///< Level-0 index of the requested point.
  std::string conv;     ///< Module path of the PointConv, e.g. "unet.encoder.0.object.conv".
  int level = 0;        ///< Level of the conv's query points.
  std::string list;     ///< "L/name" of the neighbour list used.
  int query_index = 0;  ///< Row of that list: the point itself or its representative at `level`.
  std::vector<int32_t> neighbors;  ///< `[K]` source indices (−1 masked).
  std::vector<uint8_t> mask;       ///< `[K]`.
  Eigen::MatrixXd weights;         ///< `[K,c_mid]` h(p_k − p_0).
};

/// What a traced forward pass read (the trace file's "source" attribute).
inline constexpr const char* kTraceSourceScene = "scene";      ///< Ground-truth frames t−2..t.
inline constexpr const char* kTraceSourceRollout = "rollout";  ///< A rollout's own predicted
                                                               ///< frames t−2..t.

/// Everything recorded about one forward pass of a model at one frame.
struct ModelTrace {
  std::string scene_path;
  std::string checkpoint_path;
  /// kTraceSourceScene or kTraceSourceRollout: a rollout-state trace records the pass that
  /// produced frame t+1 of the rollout at `rollout_path` from its own predicted frames.
  std::string source = kTraceSourceScene;
  std::string rollout_path;
  std::string model_config;  ///< ModelConfig JSON.
  int frame = 0;             ///< Scene frame t the model read (predicting t+1).
  std::vector<TraceLevel> levels;
  bool has_mesh = false;
  TraceMesh mesh;
  std::vector<TraceFeatures> features;
  std::vector<TraceQuery> queries;
};

/// The level-0 point that level `level`'s point `index` is (levels keep points of the level below:
/// follows `kept` down). Throws ValueError for a level or index the trace does not have.
int trace_level0_point(const ModelTrace& trace, int level, int index);

/// Name stored in the root "format" attribute of trace files.
constexpr const char* kTraceFormatName = "dynscope-trace";
/// Current trace file version.
constexpr int64_t kTraceFormatVersion = 1;

/// Writes `trace` to `path` atomically. Throws ValueError for inconsistent sizes (naming the
/// level or list), IoError if the file cannot be written.
void write_trace(const ModelTrace& trace, const std::string& path);

/// True if `path` is an HDF5 file whose root "format" attribute names a trace file.
bool is_trace_file(const std::string& path);

/// Reads a trace file. Throws IoError if missing or not HDF5, FormatError naming the field for a
/// wrong format, a missing dataset, a shape that disagrees (e.g. feature norms that are not one
/// per point of their level), an index outside its level or a non-finite value.
ModelTrace read_trace(const std::string& path);

/// Throws FormatError naming `trace_path` unless `trace` was recorded on `scene`: its frame is a
/// frame of the scene and every level-0 point belongs to an object of the scene and, for a trace
/// of the scene's own frames, lies on that object (within a quarter of its bounding-box
/// diagonal) at that frame (a rollout-state trace's points are predictions: they may drift).
void check_trace_matches_scene(const ModelTrace& trace, const Scene& scene,
                               const std::string& trace_path);

}  // namespace dynscope
