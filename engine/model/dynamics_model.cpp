// DynamicsModel: input features, normalisation and the position update.
#include "engine/model/dynamics_model.h"

#include <torch/autograd.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "engine/core/error.h"
#include "engine/core/parallel.h"

namespace dynscope {

namespace {

constexpr int64_t kInputFeatures = 7;  // v(t), v(t−1), z(t)

torch::Tensor vec3_tensor(const Vec3& v) {
  return torch::tensor(
      {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())});
}

Vec3 tensor_vec3(const torch::Tensor& t) {
  const torch::Tensor c = t.to(torch::kCPU, torch::kDouble).contiguous();
  return Vec3(c[0].item<double>(), c[1].item<double>(), c[2].item<double>());
}

}  // namespace

ModelInput make_model_input(const PointState& state, const Hierarchy& hierarchy,
                            const torch::Device& device) {
  state.validate();
  if (hierarchy.levels.empty() || hierarchy.levels[0].points.rows() != state.size()) {
    throw ValueError("hierarchy", "level 0 does not hold the state's " +
                                      std::to_string(state.size()) + " points");
  }
  ModelInput in;
  in.position = points_to_tensor(state.position, device);
  in.velocity = points_to_tensor(state.velocity, device).to(torch::kFloat);
  in.prev_velocity = points_to_tensor(state.prev_velocity, device).to(torch::kFloat);
  in.hierarchy = to_tensors(hierarchy, device);
  return in;
}

namespace {

// Lists of several inputs stacked row-wise; the sources of list b are shifted by offsets[b].
NeighborTensors concat_lists(const std::vector<const NeighborTensors*>& lists,
                             const std::vector<int64_t>& offsets) {
  int64_t k = 0;
  bool prepared = true;
  for (const NeighborTensors* l : lists) {
    k = std::max<int64_t>(k, l->index.size(1));
    prepared = prepared && (l->rows() == 0 || l->rel.defined());
  }
  std::vector<torch::Tensor> index, mask, rel, count, has_any, inv_count;
  for (size_t b = 0; b < lists.size(); ++b) {
    const NeighborTensors& l = *lists[b];
    const int64_t pad = k - l.index.size(1);
    torch::Tensor i = torch::where(l.mask, l.index + offsets[b], l.index);
    index.push_back(torch::constant_pad_nd(i, {0, pad}, -1));
    mask.push_back(torch::constant_pad_nd(l.mask, {0, pad}, 0));
    if (prepared && l.rows() > 0) {
      rel.push_back(torch::constant_pad_nd(l.rel, {0, 0, 0, pad}, 0));
      count.push_back(l.count);
      has_any.push_back(l.has_any);
      inv_count.push_back(l.inv_count);
    }
  }
  NeighborTensors out;
  out.index = torch::cat(index);
  out.mask = torch::cat(mask);
  if (prepared && !rel.empty()) {
    out.rel = torch::cat(rel);
    out.count = torch::cat(count);
    out.has_any = torch::cat(has_any);
    out.inv_count = torch::cat(inv_count);
  }
  return out;
}

}  // namespace

ModelInput concatenate_inputs(const std::vector<ModelInput>& inputs) {
  if (inputs.empty()) throw ValueError("batch", "no inputs to concatenate");
  if (inputs.size() == 1) return inputs.front();
  const int levels = inputs.front().hierarchy.num_levels();
  const bool mesh = levels > 0 && inputs.front().hierarchy.levels[0].has_mesh;
  for (const ModelInput& in : inputs) {
    if (in.hierarchy.num_levels() != levels ||
        (levels > 0 && in.hierarchy.levels[0].has_mesh != mesh)) {
      throw ValueError("batch", "inputs have different hierarchies (level count or mesh mode)");
    }
  }
  auto gather = [&](auto&& field) {
    std::vector<torch::Tensor> parts;
    for (const ModelInput& in : inputs) parts.push_back(field(in));
    return torch::cat(parts);
  };
  ModelInput out;
  out.position = gather([](const ModelInput& in) { return in.position; });
  out.velocity = gather([](const ModelInput& in) { return in.velocity; });
  out.prev_velocity = gather([](const ModelInput& in) { return in.prev_velocity; });
  // offsets[l][b]: first row of input b at level l.
  const size_t n = inputs.size();
  std::vector<std::vector<int64_t>> offsets(static_cast<size_t>(levels), std::vector<int64_t>(n));
  std::vector<int64_t> mesh_offsets(n);
  for (int l = 0; l < levels; ++l) {
    int64_t at = 0;
    for (size_t b = 0; b < n; ++b) {
      offsets[static_cast<size_t>(l)][b] = at;
      at += inputs[b].hierarchy.levels[static_cast<size_t>(l)].points.size(0);
    }
  }
  for (size_t b = 0, at = 0; b < n && mesh; ++b) {
    mesh_offsets[b] = static_cast<int64_t>(at);
    at += static_cast<size_t>(inputs[b].hierarchy.levels[0].mesh.points.size(0));
  }
  out.hierarchy.levels.resize(static_cast<size_t>(levels));
  for (int l = 0; l < levels; ++l) {
    const auto li = static_cast<size_t>(l);
    auto lists = [&](auto&& member) {
      std::vector<const NeighborTensors*> v;
      for (const ModelInput& in : inputs) v.push_back(&member(in.hierarchy.levels[li]));
      return v;
    };
    LevelTensors& t = out.hierarchy.levels[li];
    t.points = gather([&](const ModelInput& in) { return in.hierarchy.levels[li].points; });
    t.radius = inputs.front().hierarchy.levels[li].radius;
    t.same = concat_lists(
        lists([](const LevelTensors& x) -> const NeighborTensors& { return x.same; }), offsets[li]);
    t.relational = concat_lists(
        lists([](const LevelTensors& x) -> const NeighborTensors& { return x.relational; }),
        offsets[li]);
    t.relational.compact();
    if (l > 0) {
      t.down = concat_lists(
          lists([](const LevelTensors& x) -> const NeighborTensors& { return x.down; }),
          offsets[li - 1]);
      t.up = concat_lists(
          lists([](const LevelTensors& x) -> const NeighborTensors& { return x.up; }), offsets[li]);
    }
  }
  if (mesh) {
    LevelTensors& l0 = out.hierarchy.levels[0];
    l0.has_mesh = true;
    auto lists = [&](auto&& member) {
      std::vector<const NeighborTensors*> v;
      for (const ModelInput& in : inputs) v.push_back(&member(in.hierarchy.levels[0].mesh));
      return v;
    };
    l0.mesh.points =
        gather([](const ModelInput& in) { return in.hierarchy.levels[0].mesh.points; });
    l0.mesh.face_vertices = concat_lists(
        lists([](const MeshTensors& x) -> const NeighborTensors& { return x.face_vertices; }),
        offsets[0]);
    l0.mesh.senders = concat_lists(
        lists([](const MeshTensors& x) -> const NeighborTensors& { return x.senders; }),
        mesh_offsets);
    l0.mesh.vertex_points = concat_lists(
        lists([](const MeshTensors& x) -> const NeighborTensors& { return x.vertex_points; }),
        mesh_offsets);
  }
  return out;
}

DynamicsModelImpl::DynamicsModelImpl(const ModelConfig& config) : config_(config) {
  config.validate();
  unet = register_module("unet", UNet(config, kInputFeatures, 3));
  velocity_mean_ = register_buffer("velocity_mean", torch::zeros({3}));
  velocity_std_ = register_buffer("velocity_std", torch::ones({3}));
  target_mean_ = register_buffer("target_mean", torch::zeros({3}));
  target_std_ = register_buffer("target_std", torch::ones({3}));
  z_mean_ = register_buffer("z_mean", torch::zeros({1}));
  z_std_ = register_buffer("z_std", torch::ones({1}));
}

torch::Tensor DynamicsModelImpl::forward(const ModelInput& input,
                                         std::vector<BlockRecord>* record) {
  const torch::Tensor v = (input.velocity - velocity_mean_) / velocity_std_;
  const torch::Tensor v_prev = (input.prev_velocity - velocity_mean_) / velocity_std_;
  const torch::Tensor z =
      (input.position.narrow(1, 2, 1).to(torch::kFloat) - z_mean_) / z_std_;  // [N,1]
  return unet->forward(torch::cat({v, v_prev, z}, 1), input.hierarchy, record);
}

torch::Tensor DynamicsModelImpl::predict_delta(const ModelInput& input) {
  torch::Tensor target;
  // Without gradients the pass runs in one region of the compute threads (on_compute_threads):
  // the kernels' rows are tasks any of them takes, LibTorch's own ops and the BLAS run on this
  // thread, so a core that another process keeps busy slows the pass instead of stalling it at
  // every op's barrier. With gradients (training, explanations) the ops open their own loops.
  const auto run = [&] { target = forward(input); };
  if (torch::GradMode::is_enabled()) {
    run();
  } else {
    on_compute_threads(run);
  }
  target = target * target_std_ + target_mean_;
  return config_.target == TargetMode::kAcceleration ? input.velocity + target : target;
}

torch::Tensor DynamicsModelImpl::predict_positions(const ModelInput& input) {
  return input.position + predict_delta(input).to(torch::kDouble);
}

torch::Tensor DynamicsModelImpl::normalize_target(const torch::Tensor& target) const {
  return (target - target_mean_) / target_std_;
}

Hierarchy DynamicsModelImpl::build_hierarchy(const PointState& state, HierarchyCache* cache) const {
  state.validate();
  return build_model_hierarchy(state.position, state.object_ids, state.faces, config_, cache);
}

Points DynamicsModelImpl::predict_next(const PointState& state, HierarchyCache* cache) {
  state.validate();
  // No autograd bookkeeping on any op of the step (no tensor of it leaves the function).
  c10::InferenceMode inference;
  const torch::Device device = velocity_mean_.device();
  torch::Tensor delta;
  on_compute_threads([&] {  // the hierarchy, the input and the pass in one region (predict_delta)
    const ModelInput input = make_model_input(state, build_hierarchy(state, cache), device);
    delta = hold_static_points(predict_delta(input), state)
                .to(torch::kCPU, torch::kDouble)
                .contiguous();
  });
  Points out = state.position;
  out += Eigen::Map<const Points>(delta.data_ptr<double>(), state.size(), 3);  // + 0 keeps p(t)
  return out;
}

torch::Tensor DynamicsModelImpl::hold_static_points(const torch::Tensor& delta,
                                                    const PointState& state) const {
  if (!config_.hold_static || state.static_points.empty()) return delta;
  if (static_cast<int64_t>(state.static_points.size()) != delta.size(0)) {
    throw ValueError("static_points", std::to_string(state.static_points.size()) +
                                          " flags for a prediction of " +
                                          std::to_string(delta.size(0)) + " points");
  }
  const torch::Tensor held =
      torch::from_blob(const_cast<uint8_t*>(state.static_points.data()),
                       {static_cast<int64_t>(state.static_points.size()), 1}, torch::kUInt8)
          .to(delta.device(), torch::kBool);
  return delta.masked_fill(held, 0.0);
}

NormStats DynamicsModelImpl::stats() const {
  NormStats s;
  s.velocity_mean = tensor_vec3(velocity_mean_);
  s.velocity_std = tensor_vec3(velocity_std_);
  s.target_mean = tensor_vec3(target_mean_);
  s.target_std = tensor_vec3(target_std_);
  s.z_mean = z_mean_.item<double>();
  s.z_std = z_std_.item<double>();
  return s;
}

void DynamicsModelImpl::set_stats(const NormStats& s) {
  auto check_std = [](const char* name, double v) {
    if (!(v > 0) || !std::isfinite(v)) {
      throw ValueError(name,
                       "standard deviation must be positive and finite, got " + std::to_string(v));
    }
  };
  for (int c = 0; c < 3; ++c) {
    check_std("velocity_std", s.velocity_std[c]);
    check_std("target_std", s.target_std[c]);
  }
  check_std("z_std", s.z_std);
  if (!s.velocity_mean.allFinite() || !s.target_mean.allFinite() || !std::isfinite(s.z_mean)) {
    throw ValueError("norm_stats", "mean is not finite");
  }
  torch::NoGradGuard no_grad;
  velocity_mean_.copy_(vec3_tensor(s.velocity_mean));
  velocity_std_.copy_(vec3_tensor(s.velocity_std));
  target_mean_.copy_(vec3_tensor(s.target_mean));
  target_std_.copy_(vec3_tensor(s.target_std));
  z_mean_.fill_(s.z_mean);
  z_std_.fill_(s.z_std);
}

int64_t parameter_count(const torch::nn::Module& module) {
  int64_t n = 0;
  for (const auto& p : module.parameters()) n += p.numel();
  return n;
}

}  // namespace dynscope
