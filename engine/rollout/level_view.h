// The U-Net's hierarchy at one frame exactly as the model builds it, as plain data: a trace
// without feature norms or filter weights. The renderer, the viewer's level browser and its
// inspector show this when no trace of a forward pass is loaded, so every level, voxel and
// neighbour list they draw is one the model would use.
#pragma once

#include <memory>
#include <mutex>

#include "engine/io/trace_file.h"
#include "engine/model/hierarchy.h"
#include "engine/model/model_config.h"
#include "engine/rollout/model_points.h"
#include "engine/scene/scene.h"

namespace dynscope {

/// The trace form of `h` at `frame` for a model of `config`: every level (points, object ids,
/// kept indices, voxel, radius) with its non-empty neighbour lists, and for mesh input the
/// interaction points and their lists over `faces`. No feature norms or filter weights.
ModelTrace hierarchy_trace(const Hierarchy& h, const Faces& faces, int frame,
                           const ModelConfig& config);

/// The hierarchy a model of `config` builds over `points` of `scene` at `frame`
/// (build_model_hierarchy), as hierarchy_trace. Throws ValueError for a frame outside the scene,
/// mesh input without faces, and what build_model_hierarchy throws.
ModelTrace level_view(const Scene& scene, const ModelPoints& points, int frame,
                      const ModelConfig& config);

/// True for a trace that holds only the hierarchy (level_view), not a forward pass.
bool is_level_view(const ModelTrace& trace);

/// The model whose hierarchy is shown for `scene` when no checkpoint is: the scale preset of its
/// scenario (default_scale_preset) with `input`.
ModelConfig level_view_config(const Scene& scene, InputMode input = InputMode::kPoints);

/// Level views of one scene at any frame: the model points are drawn once (`sampling`, its input
/// taken from `config`), the hierarchy of the last frame asked for is kept. Thread-safe.
class LevelViews {
 public:
  /// Copies `scene`; throws what build_model_points throws.
  LevelViews(const Scene& scene, const ModelConfig& config, SamplingOptions sampling = {});

  /// The level view at `frame` (throws ValueError for a frame outside the scene).
  std::shared_ptr<const ModelTrace> at(int frame);
  /// The level view at `frame` if it is the one kept (no building), else null.
  std::shared_ptr<const ModelTrace> cached(int frame);

  const ModelConfig& config() const { return config_; }
  const ModelPoints& points() const { return points_; }

 private:
  Scene scene_;
  ModelConfig config_;
  ModelPoints points_;
  std::mutex mutex_;
  std::shared_ptr<const ModelTrace> last_;
};

}  // namespace dynscope
