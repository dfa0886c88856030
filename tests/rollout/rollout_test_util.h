// Hand-made scenes for the rollout tests: boxes moving and spinning along known poses.
#pragma once

#include <cmath>

#include "engine/rollout/rollout_runner.h"
#include "engine/scene/scene.h"

namespace dynscope::testing {

/// Two rigid boxes (target id 1, zone id 2) over `frames` frames: the target slides along +x and
/// spins about z; the zone stays at x = 3. dt 0.1 s.
inline Scene make_moving_boxes(int frames, double speed = 0.2) {
  Scene s;
  s.scenario = "drop";
  s.dt_s = 0.1;
  Object a;
  a.id = 1;
  a.name = "target";
  a.role = Role::kTarget;
  a.mesh = make_box_mesh(Vec3(0.4, 0.3, 0.2));
  Object b;
  b.id = 2;
  b.name = "zone";
  b.role = Role::kZone;
  b.mesh = make_box_mesh(Vec3(0.5, 0.5, 0.1));
  s.objects = {a, b};
  s.trajectories.resize(2);
  for (int f = 0; f < frames; ++f) {
    Pose pa;
    pa.position = Vec3(speed * f, 0.1, 0.5);
    pa.rotation = Quat(Eigen::AngleAxisd(0.15 * f, Vec3::UnitZ()));
    s.trajectories[0].poses.push_back(pa);
    Pose pb;
    pb.position = Vec3(3.0, 0.0, 0.05);
    s.trajectories[1].poses.push_back(pb);
  }
  return s;
}

/// A predictor that returns the ground truth of the frame after the one whose positions match
/// the state (an oracle; rigid projection must then reproduce the truth).
inline StepPredictor oracle_predictor(const Scene& scene, const ModelPoints& points) {
  return [&scene, &points](const PointState& state) {
    for (int f = 0; f + 1 < scene.num_frames(); ++f) {
      if ((points.positions(scene, f) - state.position).cwiseAbs().maxCoeff() < 1e-9) {
        return points.positions(scene, f + 1);
      }
    }
    return Points(state.position);
  };
}

}  // namespace dynscope::testing
