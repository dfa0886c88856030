// Rigid pose fitting (Kabsch with the reflection fix).
#pragma once

#include "engine/core/types.h"

namespace dynscope {

/// Least-squares rigid transform (rotation with det +1, translation) mapping `source` rows onto
/// `target` rows: minimises Σ|R s_i + t − d_i|². Reflected targets yield the best proper rotation.
/// Throws ValueError if the sizes differ, there are no points, or a value is not finite.
Pose fit_rigid_transform(const Points& source, const Points& target);

}  // namespace dynscope
