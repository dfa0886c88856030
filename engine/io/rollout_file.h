// HDF5 rollout files: predicted and ground-truth points, fitted poses and per-frame metrics.
//
// Layout (format "dynscope-rollout", version 1; z up, quaternions wxyz; h5py reads it directly):
//   /                      attributes: format, format_version, up_axis "z", quaternion_order
//                          "wxyz", scene_path, checkpoint_path, model_config (JSON text),
//                          scenario, dt (s), observed_frames, sampling_voxel, num_frames,
//                          num_points
//   /points/rest           float64 [N,3]  rest coordinates (object frame, scale applied)
//   /points/object_ids     int32   [N]    Object::id of each point
//   /points/faces          int32   [F,3]  triangles over the points (mesh input only)
//   /points/static         uint8   [N]    1 for points of static bodies (absent in older files)
//   /positions/predicted   float64 [T,N,3] world positions; frames < observed_frames = truth
//   /positions/truth       float64 [T,N,3]
//   /poses/object_ids      int32   [O]
//   /poses/rigid           uint8   [O]    1 if the object's poses were fitted
//   /poses/fitted          float64 [T,O,7] position xyz then quaternion wxyz (rest → world)
//   /metrics/point_error   float64 [T]    mean |predicted − truth| per frame
//   /metrics/contact_distance_truth      float64 [T]  min target–zone point distance
//   /metrics/contact_distance_predicted  float64 [T]  (both only when target and zone exist)
#pragma once

#include <string>

#include "engine/scene/rollout.h"

namespace dynscope {

/// Name stored in the root "format" attribute of rollout files.
constexpr const char* kRolloutFormatName = "dynscope-rollout";
/// Current rollout file version.
constexpr int64_t kRolloutFormatVersion = 1;

/// Writes `rollout` to `path` atomically (temporary file, then rename). Throws ValueError if the
/// rollout is inconsistent (Rollout::validate), IoError if the file cannot be written.
void write_rollout(const Rollout& rollout, const std::string& path);

/// Reads a rollout file. Throws IoError if it is missing or not HDF5, FormatError naming the
/// field for a wrong format name or version, a missing dataset or a shape that disagrees.
Rollout read_rollout(const std::string& path);

/// True if `path` is an HDF5 file whose root "format" attribute is "dynscope-rollout".
bool is_rollout_file(const std::string& path);

/// The scene file `rollout` started from: its stored scene_path when that file exists, else the
/// file of that name next to `rollout_path`; "" when neither exists (or no path is stored).
std::string find_rollout_scene(const Rollout& rollout, const std::string& rollout_path);

}  // namespace dynscope
