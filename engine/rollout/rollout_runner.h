// Autoregressive rollouts driven by any one-step predictor (a model, a baseline, an oracle).
#pragma once

#include <functional>
#include <string>

#include "engine/core/progress.h"
#include "engine/model/point_state.h"
#include "engine/rollout/model_points.h"
#include "engine/scene/rollout.h"
#include "engine/scene/scene.h"

namespace dynscope {

/// One step of dynamics: p̂(t+1) `[N,3]` from the state at t (positions p(t), v(t), v(t−1)).
using StepPredictor = std::function<Points(const PointState&)>;

/// How a rollout runs.
struct RolloutOptions {
  int observed_frames = 3;    ///< Leading ground-truth frames (>= 3: the state needs p(t−2)).
  int frames = 0;             ///< Frames in the rollout (0: all frames of the scene).
  bool project_rigid = true;  ///< Kabsch-project each rigid object every step.
  bool floor_clamp = false;   ///< Lift rigid objects that sink below z = 0 (baselines).
};

/// Runs `predict` autoregressively on the scene's model points: frames < observed_frames copy the
/// ground truth, every later frame is predict(state of the previous three frames, with the scene's
/// static points marked in PointState::static_points), then each
/// rigid object is projected to one rigid transform (RigidProjector). Fills positions, poses
/// (fitted to the truth for observed frames), the per-frame point error and, when the scene has a
/// target and a zone, the per-frame target–zone distances. Reports each predicted frame to
/// `progress`. Throws ValueError for observed_frames < 3 or >= frames, frames beyond the scene,
/// or a predictor returning the wrong number of rows or non-finite positions.
Rollout run_rollout(const Scene& scene, const ModelPoints& points, const StepPredictor& predict,
                    const RolloutOptions& options, Progress* progress = nullptr);

/// The physics-free floor: p(t+1) = p(t) + v(t) + g·dt² (constant velocity plus gravity along
/// −z, per-frame units). Use with RolloutOptions::floor_clamp to keep objects above the floor.
StepPredictor constant_velocity_predictor(double gravity, double dt_s);

}  // namespace dynscope
