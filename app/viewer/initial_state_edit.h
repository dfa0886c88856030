// What-if edits of a scene's initial state: one object's position, orientation and velocity at
// the last observed frame, carried back over the observed frames as a rigid motion.
#pragma once

#include "engine/core/types.h"
#include "engine/scene/scene.h"

namespace dynscope::app::viewer {

/// The state of one object at the edit frame (the last observed frame, from which the model
/// starts predicting): rigid objects by their pose, deformable ones by their particle centroid.
struct ObjectEdit {
  int object = -1;                ///< Index into Scene::objects.
  Vec3 position = Vec3::Zero();   ///< World position (scene units).
  Vec3 euler_deg = Vec3::Zero();  ///< Rotation about world x, then y, then z (degrees).
  Vec3 velocity = Vec3::Zero();   ///< World velocity (units/s), backward difference.
};

/// Object `object`'s state at `edit_frame` (>= 1). Throws ValueError for a bad object or frame.
ObjectEdit object_initial_state(const Scene& scene, int object, int edit_frame);

/// `scene` with `edit` applied at `edit_frame` (>= 1, usually observed_frames - 1): frames
/// 0..edit_frame of the object are moved by the rigid transform that takes its old pose at the
/// edit frame to the new one (rotation about its position there), and a velocity change
/// (new − rotated old) × (f − edit_frame) × dt_s is added to frame f, so the state the model reads
/// has exactly the edited position, orientation and velocity and the observed history keeps its
/// shape. Later frames keep the recorded truth (no longer consistent with the edit). Throws
/// ValueError for a bad object, frame or non-finite value.
Scene apply_initial_state_edit(const Scene& scene, const ObjectEdit& edit, int edit_frame);

}  // namespace dynscope::app::viewer
