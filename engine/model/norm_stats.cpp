// NormStatsAccumulator: running sums of velocities, targets and heights.
#include "engine/model/norm_stats.h"

#include <cmath>
#include <string>

#include "engine/core/error.h"

namespace dynscope {

void NormStatsAccumulator::add(const Points& p_tm1, const Points& p_t, const Points& p_tp1) {
  if (p_tm1.rows() != p_t.rows() || p_tp1.rows() != p_t.rows()) {
    throw ValueError("norm_stats",
                     "frames have different point counts: " + std::to_string(p_tm1.rows()) + ", " +
                         std::to_string(p_t.rows()) + ", " + std::to_string(p_tp1.rows()));
  }
  const Points v = p_t - p_tm1;
  const Points v_next = p_tp1 - p_t;
  const Points target = target_ == TargetMode::kAcceleration ? Points(v_next - v) : v_next;
  v_sum_ += v.colwise().sum().transpose();
  v_sq_ += v.array().square().matrix().colwise().sum().transpose();
  t_sum_ += target.colwise().sum().transpose();
  t_sq_ += target.array().square().matrix().colwise().sum().transpose();
  z_sum_ += p_t.col(2).sum();
  z_sq_ += p_t.col(2).squaredNorm();
  count_ += p_t.rows();
}

NormStats NormStatsAccumulator::finish(double min_std) const {
  if (count_ == 0) throw ValueError("norm_stats", "no transitions were added");
  const double n = static_cast<double>(count_);
  auto std_of = [&](double sum, double sq) {
    const double mean = sum / n;
    return std::max(std::sqrt(std::max(sq / n - mean * mean, 0.0)), min_std);
  };
  NormStats s;
  s.velocity_mean = v_sum_ / n;
  s.target_mean = t_sum_ / n;
  for (int c = 0; c < 3; ++c) {
    s.velocity_std[c] = std_of(v_sum_[c], v_sq_[c]);
    s.target_std[c] = std_of(t_sum_[c], t_sq_[c]);
  }
  s.z_mean = z_sum_ / n;
  s.z_std = std_of(z_sum_, z_sq_);
  return s;
}

}  // namespace dynscope
