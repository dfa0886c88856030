// Rollout metrics: per-frame point error (Kubric) and target–zone contact (Physion).
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/types.h"

namespace dynscope {

/// Default contact threshold as a fraction of the point-sampling voxel. Surface points sit about
/// one voxel apart, so two touching surfaces have a nearest pair closer than one voxel; the
/// threshold is reported together with the voxel.
constexpr double kContactThresholdFraction = 1.0;

/// Mean Euclidean distance between matching rows of `a` and `b` `[N,3]`; throws ValueError if the
/// sizes differ or there are no rows.
double mean_point_error(const Points& a, const Points& b);

/// Smallest Euclidean distance between any row of `a` and any row of `b` (exact, brute force);
/// throws ValueError if either is empty.
double min_distance(const Points& a, const Points& b);

/// Rows of `points` whose id equals `id`.
Points select_rows(const Points& points, const std::vector<int32_t>& ids, int32_t id);

/// First frame whose distance is below `threshold` (strictly), or -1: the one contact rule of
/// rollouts, evaluation and the viewer.
int first_contact_frame(const std::vector<double>& distances, double threshold);

/// True if any of the per-frame distances is below `threshold` (first_contact_frame >= 0).
bool contact_predicted(const std::vector<double>& distances, double threshold);

}  // namespace dynscope
