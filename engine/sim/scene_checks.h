// Physical sanity checks of recorded scenes, measured with Bullet on the stored meshes.
#pragma once

#include "engine/scene/scene.h"

namespace dynscope {

/// Deepest interpenetration (scene units, >= 0) at `frame` between two rigid objects of `scene`,
/// or between an object and the floor plane z = 0 when `floor` is true. Each object is the
/// union of the convex hulls of its mesh's connected components, posed as stored, so concave
/// bodies made of separate convex parts (containers) are measured exactly. Deformable objects
/// are ignored. Throws ValueError if `frame` is out of range.
double max_penetration(const Scene& scene, int frame, bool floor = true);

}  // namespace dynscope
