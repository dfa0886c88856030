// Area-weighted surface sampling: binary search over cumulative face areas, sqrt barycentrics.
#include "engine/geometry/surface_sampling.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "engine/core/error.h"

namespace dynscope {

SurfaceSamples sample_surface(const Mesh& mesh, int64_t count, Rng& rng) {
  if (count < 0) throw ValueError("count", "must be >= 0, got " + std::to_string(count));
  if (mesh.empty()) throw ValueError("mesh", "has no faces to sample");
  mesh.validate("mesh");
  const Eigen::VectorXd areas = mesh.face_areas();
  std::vector<double> cumulative(static_cast<size_t>(areas.size()));
  double total = 0.0;
  int32_t last_positive = -1;
  for (Eigen::Index f = 0; f < areas.size(); ++f) {
    total += areas[f];
    cumulative[static_cast<size_t>(f)] = total;
    if (areas[f] > 0.0) last_positive = static_cast<int32_t>(f);
  }
  if (!(total > 0.0) || !std::isfinite(total)) {
    throw ValueError("mesh", "surface area is zero or not finite");
  }

  SurfaceSamples out;
  out.points.resize(count, 3);
  out.face.resize(static_cast<size_t>(count));
  for (int64_t s = 0; s < count; ++s) {
    // upper_bound skips zero-area faces (their cumulative value equals the previous one).
    const double u = rng.uniform() * total;
    auto f = static_cast<int32_t>(std::upper_bound(cumulative.begin(), cumulative.end(), u) -
                                  cumulative.begin());
    // u can round up to `total`; the last face with area then takes it.
    if (f >= static_cast<int32_t>(cumulative.size())) f = last_positive;
    // sqrt(r1) makes (1 - s, s(1 - r2), s r2) uniform over the triangle.
    const double root = std::sqrt(rng.uniform());
    const double r2 = rng.uniform();
    const Eigen::RowVector3d a = mesh.vertices.row(mesh.faces(f, 0));
    const Eigen::RowVector3d b = mesh.vertices.row(mesh.faces(f, 1));
    const Eigen::RowVector3d c = mesh.vertices.row(mesh.faces(f, 2));
    out.points.row(s) = (1.0 - root) * a + root * (1.0 - r2) * b + root * r2 * c;
    out.face[static_cast<size_t>(s)] = f;
  }
  return out;
}

}  // namespace dynscope
