// Autoregressive rollout loop, rigid projection and per-frame metrics.
#include "engine/rollout/rollout_runner.h"

#include <string>

#include "engine/core/error.h"
#include "engine/rollout/metrics.h"
#include "engine/rollout/pose_fitting.h"

namespace dynscope {

Rollout run_rollout(const Scene& scene, const ModelPoints& points, const StepPredictor& predict,
                    const RolloutOptions& options, Progress* progress) {
  scene.validate();
  const int frames = options.frames > 0 ? options.frames : scene.num_frames();
  if (frames > scene.num_frames()) {
    throw ValueError("frames", std::to_string(frames) + " exceeds the scene's " +
                                   std::to_string(scene.num_frames()) + " frames");
  }
  if (options.observed_frames < 3 || options.observed_frames >= frames) {
    throw ValueError("observed", "observed frames must be in [3, " + std::to_string(frames - 1) +
                                     "], got " + std::to_string(options.observed_frames));
  }
  const ScenePointCloud& cloud = points.cloud;
  const RigidProjector projector(cloud, scene);
  Rollout r;
  for (const Object& o : scene.objects) r.pose_object_ids.push_back(o.id);
  r.pose_rigid = projector.rigid();
  const std::vector<uint8_t> static_points = cloud.static_mask(scene);

  r.scenario = scene.scenario;
  r.dt_s = scene.dt_s;
  r.observed_frames = options.observed_frames;
  r.sampling_voxel = points.voxel;
  r.rest = cloud.rest;
  r.object_ids = cloud.object_id;
  r.faces = points.faces;
  r.static_points = static_points;

  const int target = scene.find_role(Role::kTarget);
  const int zone = scene.find_role(Role::kZone);
  const bool contact =
      target >= 0 && zone >= 0 && cloud.count_of(target) > 0 && cloud.count_of(zone) > 0;
  const int32_t target_id = contact ? scene.objects[static_cast<size_t>(target)].id : 0;
  const int32_t zone_id = contact ? scene.objects[static_cast<size_t>(zone)].id : 0;
  auto contact_distance = [&](const Points& p) {
    return min_distance(select_rows(p, cloud.object_id, target_id),
                        select_rows(p, cloud.object_id, zone_id));
  };

  for (int f = 0; f < frames; ++f) {
    const Points truth = cloud.positions(scene, f);
    std::vector<Pose> poses;
    Points predicted;
    if (f < options.observed_frames) {
      projector.project(truth, &poses);
      predicted = truth;
    } else {
      const size_t t = static_cast<size_t>(f - 1);
      const PointState state = [&] {
        PointState s = PointState::from_positions(r.predicted[t], r.predicted[t - 1],
                                                  r.predicted[t - 2], cloud.object_id);
        s.faces = points.faces;
        s.static_points = static_points;
        return s;
      }();
      const Points raw = predict(state);
      if (raw.rows() != cloud.size() || !raw.allFinite()) {
        throw ValueError("prediction", "frame " + std::to_string(f) + ": predictor returned " +
                                           std::to_string(raw.rows()) + " rows for " +
                                           std::to_string(cloud.size()) +
                                           " points or non-finite positions");
      }
      predicted = options.project_rigid ? projector.project(raw, &poses) : raw;
      if (!options.project_rigid) poses.assign(projector.rigid().size(), Pose{});
      if (options.floor_clamp) projector.clamp_to_floor(predicted, poses);
      if (progress) progress->advance();
    }
    r.point_error.push_back(mean_point_error(predicted, truth));
    if (contact) {
      r.contact_distance_truth.push_back(contact_distance(truth));
      r.contact_distance_predicted.push_back(contact_distance(predicted));
    }
    r.truth.push_back(truth);
    r.predicted.push_back(std::move(predicted));
    r.poses.push_back(std::move(poses));
  }
  return r;
}

StepPredictor constant_velocity_predictor(double gravity, double dt_s) {
  const double drop = gravity * dt_s * dt_s;
  return [drop](const PointState& s) {
    Points next = s.position + s.velocity;
    next.col(2).array() -= drop;
    return next;
  };
}

}  // namespace dynscope
