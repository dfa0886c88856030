// A predicted rollout next to its ground truth: positions, fitted poses and metrics (plain data).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/types.h"

namespace dynscope {

/// One autoregressive rollout of a scene. Frames 0..observed_frames−1 are copied from the ground
/// truth; later frames are model predictions. Positions are world coordinates (z up), one row per
/// model point; point i keeps its identity (object and rest coordinate) over all frames.
struct Rollout {
  std::string scene_path;       ///< Scene file the rollout started from.
  std::string checkpoint_path;  ///< Checkpoint of the model ("" for a baseline).
  std::string model_config;     ///< The model's ModelConfig JSON (or a baseline description).
  std::string scenario;         ///< Scenario name of the scene.
  double dt_s = 0.0;            ///< Seconds between frames.
  int observed_frames = 0;      ///< Leading frames taken from ground truth.
  double sampling_voxel = 0.0;  ///< Grid voxel the model points were sampled with.

  Points rest = Points(0, 3);       ///< `[N,3]` rest coordinates (object frame, scale applied).
  std::vector<int32_t> object_ids;  ///< `[N]` Object::id of each point.
  Faces faces = Faces(0, 3);        ///< `[F,3]` triangles over the points (mesh input; else empty).
  /// `[N]` 1 for the points of static bodies (ScenePointCloud::static_mask), which a model that
  /// holds static bodies (ModelConfig::hold_static) keeps in place; empty in older files.
  std::vector<uint8_t> static_points;

  std::vector<Points> predicted;  ///< `[T]` of `[N,3]` predicted positions.
  std::vector<Points> truth;      ///< `[T]` of `[N,3]` ground-truth positions.

  std::vector<int32_t> pose_object_ids;  ///< `[O]` ids of the objects that have poses.
  std::vector<uint8_t> pose_rigid;       ///< `[O]` 1 if the object is rigid (poses fitted).
  /// `[T]` of `[O]` fitted poses (rest → world); identity for non-rigid objects.
  std::vector<std::vector<Pose>> poses;

  std::vector<double> point_error;  ///< `[T]` mean |predicted − truth| per frame.
  /// `[T]` minimum target–zone point distance in the truth / the prediction; empty when the scene
  /// has no target and zone.
  std::vector<double> contact_distance_truth;
  std::vector<double> contact_distance_predicted;

  int num_frames() const { return static_cast<int>(predicted.size()); }
  Eigen::Index num_points() const { return rest.rows(); }
  int num_objects() const { return static_cast<int>(pose_object_ids.size()); }
  bool has_contact() const { return !contact_distance_truth.empty(); }

  /// Throws ValueError naming the first field whose size disagrees with the others, a non-finite
  /// position, or observed_frames outside [0, T].
  void validate() const;
};

}  // namespace dynscope
