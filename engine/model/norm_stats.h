// Normalisation statistics of model inputs and targets, and their accumulation (no torch).
#pragma once

#include <cstdint>

#include "engine/core/types.h"
#include "engine/model/model_config.h"

namespace dynscope {

/// Per-component mean and standard deviation of input velocities (scene units per frame), of the
/// regression target (acceleration or velocity, per the model's TargetMode) and of the height z.
struct NormStats {
  Vec3 velocity_mean = Vec3::Zero();
  Vec3 velocity_std = Vec3::Ones();
  Vec3 target_mean = Vec3::Zero();
  Vec3 target_std = Vec3::Ones();
  double z_mean = 0.0;
  double z_std = 1.0;
};

/// Accumulates NormStats over transitions (sums in double; order-independent up to rounding).
class NormStatsAccumulator {
 public:
  explicit NormStatsAccumulator(TargetMode target) : target_(target) {}

  /// Adds one transition given positions `[N,3]` at t−1, t and t+1: velocity v(t), target
  /// (a = v(t+1) − v(t) or v(t+1)) and height z(t) of every point. Throws ValueError on size
  /// mismatch.
  void add(const Points& p_tm1, const Points& p_t, const Points& p_tp1);
  /// Number of points added so far.
  int64_t count() const { return count_; }
  /// Means and standard deviations; a std below `min_std` is raised to it so that constant
  /// components do not divide by zero. Throws ValueError if nothing was added.
  NormStats finish(double min_std = 1e-6) const;

 private:
  TargetMode target_;
  int64_t count_ = 0;
  Vec3 v_sum_ = Vec3::Zero(), v_sq_ = Vec3::Zero();
  Vec3 t_sum_ = Vec3::Zero(), t_sq_ = Vec3::Zero();
  double z_sum_ = 0.0, z_sq_ = 0.0;
};

}  // namespace dynscope
