// Builds the model's per-object point state and poses it at any frame.
#include "engine/geometry/point_cloud.h"

#include <cmath>
#include <string>

#include "engine/core/error.h"
#include "engine/core/rng.h"
#include "engine/geometry/grid_downsample.h"
#include "engine/geometry/surface_sampling.h"

namespace dynscope {
namespace {

// Guards against a voxel so small that sampling would exhaust memory.
constexpr double kMaxSamplesPerObject = 5.0e7;

std::string describe(const Object& o) {
  return "object " + std::to_string(o.id) + " (" + o.name + ")";
}

void append(ScenePointCloud& cloud, const Points& points, const std::vector<int32_t>& kept,
            int32_t object, int32_t object_id, bool keep_particle) {
  const Eigen::Index start = cloud.rest.rows();
  cloud.rest.conservativeResize(start + static_cast<Eigen::Index>(kept.size()), 3);
  for (size_t j = 0; j < kept.size(); ++j) {
    cloud.rest.row(start + static_cast<Eigen::Index>(j)) = points.row(kept[j]);
    cloud.object.push_back(object);
    cloud.object_id.push_back(object_id);
    cloud.particle.push_back(keep_particle ? kept[j] : -1);
  }
}

}  // namespace

Points ScenePointCloud::positions(const Scene& scene, int frame) const {
  if (frame < 0 || frame >= scene.num_frames()) {
    throw ValueError("frame", std::to_string(frame) + " is outside [0, " +
                                  std::to_string(scene.num_frames()) + ")");
  }
  const auto objects = static_cast<int32_t>(scene.objects.size());
  if (scene.trajectories.size() != scene.objects.size()) {
    throw ValueError("trajectories", std::to_string(scene.trajectories.size()) +
                                         " trajectories for " + std::to_string(objects) +
                                         " objects");
  }
  // One rotation matrix per object and frame instead of one quaternion product per point.
  std::vector<Mat3> rotation(scene.objects.size());
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    if (scene.objects[i].rigid) {
      rotation[i] = scene.trajectories[i]
                        .poses.at(static_cast<size_t>(frame))
                        .rotation.normalized()
                        .toRotationMatrix();
    }
  }
  Points out(rest.rows(), 3);
  for (Eigen::Index p = 0; p < rest.rows(); ++p) {
    const int32_t i = object[static_cast<size_t>(p)];
    if (i < 0 || i >= objects) {
      throw ValueError("object", "point " + std::to_string(p) + " refers to object index " +
                                     std::to_string(i) + " of " + std::to_string(objects));
    }
    const Trajectory& t = scene.trajectories[static_cast<size_t>(i)];
    if (scene.objects[static_cast<size_t>(i)].rigid) {
      const Vec3& position = t.poses[static_cast<size_t>(frame)].position;
      out.row(p) =
          (rotation[static_cast<size_t>(i)] * rest.row(p).transpose() + position).transpose();
    } else {
      const Points& particles = t.particles.at(static_cast<size_t>(frame));
      const int32_t k = particle[static_cast<size_t>(p)];
      if (k < 0 || k >= particles.rows()) {
        throw ValueError("particle", "point " + std::to_string(p) + " refers to particle " +
                                         std::to_string(k) + " of " +
                                         std::to_string(particles.rows()));
      }
      out.row(p) = particles.row(k);
    }
  }
  return out;
}

int64_t ScenePointCloud::count_of(int i) const {
  int64_t n = 0;
  for (const int32_t o : object) n += o == i ? 1 : 0;
  return n;
}

std::vector<uint8_t> ScenePointCloud::static_mask(const Scene& scene) const {
  std::vector<uint8_t> mask(object.size(), 0);
  for (size_t i = 0; i < object.size(); ++i) {
    if (object[i] < 0 || static_cast<size_t>(object[i]) >= scene.objects.size()) {
      throw ValueError("points", "point " + std::to_string(i) + " refers to object index " +
                                     std::to_string(object[i]) + " of a scene with " +
                                     std::to_string(scene.objects.size()) + " objects");
    }
    mask[i] = scene.objects[static_cast<size_t>(object[i])].is_static() ? 1 : 0;
  }
  return mask;
}

ScenePointCloud build_point_cloud(const Scene& scene, const PointCloudOptions& options) {
  if (!std::isfinite(options.voxel) || options.voxel <= 0.0) {
    throw ValueError("voxel", "must be finite and positive, got " + std::to_string(options.voxel));
  }
  if (!std::isfinite(options.oversample) || options.oversample <= 0.0) {
    throw ValueError("oversample",
                     "must be finite and positive, got " + std::to_string(options.oversample));
  }
  scene.validate();
  ScenePointCloud cloud;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Object& o = scene.objects[i];
    const auto index = static_cast<int32_t>(i);
    if (!o.rigid) {
      // Deformable points are particles: their frame-0 world positions serve as the rest state.
      const std::vector<Points>& particles = scene.trajectories[i].particles;
      if (particles.empty()) throw ValueError(describe(o), "deformable object has no frames");
      append(cloud, particles.front(), grid_downsample(particles.front(), options.voxel), index,
             o.id, true);
      continue;
    }
    const Mesh mesh = o.scaled_mesh();
    const double area = mesh.area();
    if (mesh.empty() || !(area > 0.0)) {
      throw ValueError(describe(o), "mesh has no surface area to sample");
    }
    const double count = std::ceil(options.oversample * area / (options.voxel * options.voxel));
    if (!(count <= kMaxSamplesPerObject)) {
      throw ValueError("voxel", std::to_string(options.voxel) + " would need " +
                                    std::to_string(count) + " samples for " + describe(o));
    }
    Rng rng(derive_seed(options.seed, i));
    const SurfaceSamples samples = sample_surface(mesh, static_cast<int64_t>(count), rng);
    append(cloud, samples.points, grid_downsample(samples.points, options.voxel), index, o.id,
           false);
  }
  return cloud;
}

}  // namespace dynscope
