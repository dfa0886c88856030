// Debug-trace capture: one forward pass of a checkpoint's model with every level, neighbour list,
// feature norm and the learned filter weights at chosen points (torch stays in the source).
#pragma once

#include <string>
#include <vector>

#include "engine/io/trace_file.h"
#include "engine/rollout/model_points.h"
#include "engine/scene/rollout.h"
#include "engine/scene/scene.h"

namespace dynscope {

/// Loads `checkpoint_path`, builds the state of `scene` at `frame` (p(t), v(t), v(t−1) from the
/// ground truth, so frame >= 2) on `points`, runs the model once and records the hierarchy,
/// neighbour lists, mesh interaction lists (mesh input), per-point feature norms after every
/// U-Net stage and, for each level-0 index in `queries`, h(p_k − p_0) of every PointConv whose
/// query level holds the point or its representative (the nearest coarser point along the
/// upsampling lists). GNN layers and the mesh relational path have no filter weights and are
/// skipped. Throws ValueError for a frame outside [2, T−1] or a query outside [0, N), IoError /
/// FormatError / Error as load_model.
ModelTrace capture_trace(const std::string& checkpoint_path, const Scene& scene,
                         const ModelPoints& points, int frame, const std::vector<int>& queries);

/// The forward pass that produced frame `frame`+1 of `rollout`, recorded from the rollout's own
/// predicted frames t−2..t (its object ids and, for mesh input, faces) as capture_trace records
/// a scene's: source kTraceSourceRollout, scene_path the rollout's scene. `queries` index the
/// rollout's points. Throws ValueError for a frame outside [first_rollout_trace_frame,
/// T−2] (state_history.h) or a query outside the points, and as capture_trace.
ModelTrace capture_rollout_trace(const std::string& checkpoint_path, const Rollout& rollout,
                                 int frame, const std::vector<int>& queries);

}  // namespace dynscope
