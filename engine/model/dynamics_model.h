// The dynamics model front: normalised inputs [v_t; v_{t−1}; z_t] → U-Net → next positions.
#pragma once

#include <torch/nn/module.h>
#include <torch/nn/pimpl.h>

#include <vector>

#include "engine/model/hierarchy.h"
#include "engine/model/model_config.h"
#include "engine/model/neighbor_tensors.h"
#include "engine/model/norm_stats.h"
#include "engine/model/point_state.h"
#include "engine/model/unet.h"

namespace dynscope {

/// One model input as tensors: p(t) float64 `[N,3]`, v(t) and v(t−1) float32 `[N,3]` (scene units
/// per frame), and the hierarchy built from p(t).
struct ModelInput {
  torch::Tensor position;
  torch::Tensor velocity;
  torch::Tensor prev_velocity;
  HierarchyTensors hierarchy;
};

/// Converts a state and its hierarchy; throws ValueError if the state is invalid or the
/// hierarchy's level 0 does not have the state's points.
ModelInput make_model_input(const PointState& state, const Hierarchy& hierarchy,
                            const torch::Device& device = torch::kCPU);

/// Concatenates inputs into one: the points of input b follow those of input b−1 on every level
/// and every neighbour list is offset to match (lists are padded to the widest K with masked
/// entries), so no list crosses inputs and one forward pass of the result equals separate passes
/// of each (the network is per point: LayerNorm, never BatchNorm). Throws ValueError for no
/// inputs or inputs whose level counts or mesh mode differ.
ModelInput concatenate_inputs(const std::vector<ModelInput>& inputs);

/// Predicts p̂(t+1) from a PointState. The network sees only normalised velocities, the normalised
/// height z and relative positions, so a translation in x and y leaves its output unchanged.
/// Target acc: p̂(t+1) = p(t) + v(t) + â; vel: p̂(t+1) = p(t) + v̂. Normalisation statistics are
/// buffers ("velocity_mean", "velocity_std", "target_mean", "target_std", "z_mean", "z_std") so
/// they travel with the weights. Submodule "unet".
class DynamicsModelImpl : public torch::nn::Module {
 public:
  /// Throws ValueError for an invalid configuration.
  explicit DynamicsModelImpl(const ModelConfig& config);

  /// Raw network output `[N,3]`: the target (acceleration or velocity) in normalised units.
  torch::Tensor forward(const ModelInput& input, std::vector<BlockRecord>* record = nullptr);
  /// p̂(t+1) − p(t) `[N,3]` float32 (scene units per frame).
  torch::Tensor predict_delta(const ModelInput& input);
  /// `delta` (predict_delta on `state`) with the rows of the state's static points set to 0 where
  /// the model holds static bodies (ModelConfig::hold_static); else `delta` itself. Differentiable.
  torch::Tensor hold_static_points(const torch::Tensor& delta, const PointState& state) const;
  /// p̂(t+1) `[N,3]` float64 (differentiable with respect to the weights).
  torch::Tensor predict_positions(const ModelInput& input);
  /// (target − mean) / std for a target `[N,3]` in scene units per frame (for normalised losses).
  torch::Tensor normalize_target(const torch::Tensor& target) const;

  /// The hierarchy this model's configuration builds on the state's positions (and, for mesh
  /// input, its faces). Throws ValueError for a bad state or mesh input without faces. A `cache`
  /// (one per rollout) reuses what it can certify (HierarchyCache); the result is the same.
  Hierarchy build_hierarchy(const PointState& state, HierarchyCache* cache = nullptr) const;
  /// Builds the hierarchy (with `cache` when given), runs the model without gradients and returns
  /// p̂(t+1) `[N,3]` (double; the prediction is added to p(t) in double precision); with
  /// hold_static, the state's static points keep p(t) exactly. Throws ValueError on a bad state.
  Points predict_next(const PointState& state, HierarchyCache* cache = nullptr);

  const ModelConfig& config() const { return config_; }
  NormStats stats() const;
  /// Copies statistics into the buffers; throws ValueError if a std is not positive and finite.
  void set_stats(const NormStats& stats);

  UNet unet{nullptr};

 private:
  ModelConfig config_;
  torch::Tensor velocity_mean_, velocity_std_, target_mean_, target_std_, z_mean_, z_std_;
};
TORCH_MODULE(DynamicsModel);

/// Number of trainable scalars of a model.
int64_t parameter_count(const torch::nn::Module& module);

}  // namespace dynscope
