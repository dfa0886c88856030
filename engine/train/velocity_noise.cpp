#include "engine/train/velocity_noise.h"

#include <cmath>
#include <map>
#include <tuple>
#include <utility>

#include "engine/core/error.h"
#include "engine/core/rng.h"

namespace dynscope {

NoiseMode parse_noise_mode(const std::string& name) {
  if (name == "point") return NoiseMode::kPoint;
  if (name == "object") return NoiseMode::kObject;
  if (name == "centred") return NoiseMode::kCentred;
  throw ValueError("noise-mode", "must be point, object or centred, got '" + name + "'");
}

void add_velocity_noise(double noise_std, NoiseMode mode, const std::vector<int32_t>& object_ids,
                        Points* v_prev, Points* v, Rng* rng) {
  if (v_prev->rows() != v->rows() || static_cast<size_t>(v->rows()) != object_ids.size()) {
    throw ValueError("velocity noise", "velocities and object ids differ in length");
  }
  // GNS random walk: the older velocity gets one increment, the newer one two, each with
  // variance σ²/2, so the noise on v(t) has std σ.
  const double step_std = noise_std / std::sqrt(2.0);
  auto increment = [&] {
    return Vec3(rng->normal(0.0, step_std), rng->normal(0.0, step_std), rng->normal(0.0, step_std));
  };
  if (mode != NoiseMode::kObject) {
    Points n1(v->rows(), 3), n2(v->rows(), 3);
    for (Eigen::Index i = 0; i < n1.size(); ++i) n1.data()[i] = rng->normal(0.0, step_std);
    for (Eigen::Index i = 0; i < n2.size(); ++i) n2.data()[i] = rng->normal(0.0, step_std);
    n2 += n1;
    if (mode == NoiseMode::kCentred) {
      std::map<int32_t, std::tuple<Vec3, Vec3, int64_t>> mean;  // sums of n1, n2 and the count
      for (Eigen::Index i = 0; i < n1.rows(); ++i) {
        auto& [s1, s2, count] =
            mean.try_emplace(object_ids[static_cast<size_t>(i)], Vec3::Zero(), Vec3::Zero(), 0)
                .first->second;
        s1 += n1.row(i).transpose();
        s2 += n2.row(i).transpose();
        ++count;
      }
      for (Eigen::Index i = 0; i < n1.rows(); ++i) {
        const auto& [s1, s2, count] = mean.at(object_ids[static_cast<size_t>(i)]);
        n1.row(i) -= s1.transpose() / static_cast<double>(count);
        n2.row(i) -= s2.transpose() / static_cast<double>(count);
      }
    }
    *v_prev += n1;
    *v += n2;
    return;
  }
  // One draw per object id, in ascending id order (deterministic whatever the point order).
  std::map<int32_t, std::pair<Vec3, Vec3>> draws;
  for (int32_t id : object_ids) draws.emplace(id, std::pair<Vec3, Vec3>());
  for (auto& [id, d] : draws) {
    d.first = increment();
    d.second = d.first + increment();
  }
  for (Eigen::Index i = 0; i < v->rows(); ++i) {
    const auto& d = draws.at(object_ids[static_cast<size_t>(i)]);
    v_prev->row(i) += d.first.transpose();
    v->row(i) += d.second.transpose();
  }
}

}  // namespace dynscope
