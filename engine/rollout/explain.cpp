// Gradient × input attribution of a rollout pass over the edges of the model's neighbour lists.
#include "engine/rollout/explain.h"

#include <c10/util/Exception.h>
#include <torch/torch.h>

#include <algorithm>
#include <map>
#include <mutex>
#include <tuple>

#include "engine/core/error.h"
#include "engine/model/checkpoint.h"
#include "engine/model/hierarchy.h"
#include "engine/rollout/divergence.h"

namespace dynscope {

struct RolloutExplainer::Impl {
  std::string path;
  DynamicsModel model{nullptr};
  ModelConfig config;
  std::mutex mutex;
};

RolloutExplainer::RolloutExplainer(const std::string& checkpoint_path)
    : impl_(std::make_unique<Impl>()) {
  impl_->path = checkpoint_path;
  try {
    impl_->model = load_checkpoint(checkpoint_path);
  } catch (const c10::Error& e) {
    throw Error(checkpoint_path + ": " + e.what_without_backtrace());
  }
  impl_->model->eval();
  // Only the edge gates need gradients.
  for (torch::Tensor& p : impl_->model->parameters()) p.set_requires_grad(false);
  impl_->config = impl_->model->config();
}

RolloutExplainer::~RolloutExplainer() = default;

const std::string& RolloutExplainer::checkpoint_path() const { return impl_->path; }
const ModelConfig& RolloutExplainer::config() const { return impl_->config; }

namespace {

NeighborTensors& level_tensors(LevelTensors& level, LevelList list) {
  switch (list) {
    case LevelList::kSame:
      return level.same;
    case LevelList::kRelational:
      return level.relational;
    case LevelList::kDown:
      return level.down;
    case LevelList::kUp:
      break;
  }
  return level.up;
}

NeighborTensors& mesh_tensors(MeshTensors& mesh, MeshList list) {
  switch (list) {
    case MeshList::kFaceVertices:
      return mesh.face_vertices;
    case MeshList::kSenders:
      return mesh.senders;
    case MeshList::kVertexPoints:
      break;
  }
  return mesh.vertex_points;
}

// One gated list: its name, level, tensors and the level its sources live on (−1: interaction
// points).
struct GatedList {
  std::string list;
  int level = 0;
  int source_level = 0;
  NeighborTensors* tensors = nullptr;
};

// Where the sources of every level lie at level 0, and their objects.
class SourceMap {
 public:
  explicit SourceMap(const Hierarchy& h) : h_(h) {
    rep_.resize(h.levels.size());
    for (size_t l = 0; l < h.levels.size(); ++l) {
      const HierarchyLevel& level = h.levels[l];
      rep_[l].resize(static_cast<size_t>(level.points.rows()));
      for (size_t j = 0; j < rep_[l].size(); ++j) {
        rep_[l][j] = l == 0 ? static_cast<int>(j) : rep_[l - 1][static_cast<size_t>(level.kept[j])];
      }
    }
  }

  int32_t object(int level, int j) const {
    return level < 0 ? h_.mesh.object_ids[static_cast<size_t>(j)]
                     : h_.levels[static_cast<size_t>(level)].object_ids[static_cast<size_t>(j)];
  }

  // Calls add(point, fraction) for the level-0 points source j of `level` stands for.
  template <class Add>
  void spread(int level, int j, Add&& add) const {
    if (level >= 0) {
      add(rep_[static_cast<size_t>(level)][static_cast<size_t>(j)], 1.0);
      return;
    }
    const NeighborList& corners = h_.mesh.face_vertices;
    int valid = 0;
    for (Eigen::Index k = 0; k < corners.k(); ++k) valid += corners.mask(j, k) ? 1 : 0;
    for (Eigen::Index k = 0; k < corners.k(); ++k) {
      if (corners.mask(j, k)) add(corners.index(j, k), 1.0 / valid);
    }
  }

 private:
  const Hierarchy& h_;
  std::vector<std::vector<int>> rep_;
};

std::vector<int> chosen_points(const Rollout& rollout, const ExplainSelection& s) {
  if ((s.object >= 0) == (s.point >= 0)) {
    throw ValueError("selection", "choose an object or a point, not both or neither");
  }
  const auto n = static_cast<int>(rollout.num_points());
  if (s.point >= 0) {
    if (s.point >= n) {
      throw ValueError("point", std::to_string(s.point) + " outside [0, " + std::to_string(n) +
                                    ") (the rollout's points)");
    }
    return {s.point};
  }
  std::vector<int> points;
  for (int i = 0; i < n; ++i) {
    if (rollout.object_ids[static_cast<size_t>(i)] == s.object) points.push_back(i);
  }
  if (points.empty()) {
    throw ValueError("object",
                     "object " + std::to_string(s.object) + " has no points in the rollout");
  }
  return points;
}

struct GroupSum {
  double magnitude = 0.0, effect = 0.0;
  int edges = 0;
  std::map<int, double> points;  // level-0 point -> Σ|∂E/∂g|
};

}  // namespace

Explanation RolloutExplainer::explain(const Rollout& rollout,
                                      const ExplainSelection& selection) const {
  rollout.validate();
  const PassRange passes = rollout_passes(rollout);
  const int t = selection.frame;
  if (t < passes.first || t > passes.last) {
    throw ValueError("frame", std::to_string(t) + " outside [" + std::to_string(passes.first) +
                                  ", " + std::to_string(passes.last) +
                                  "]: a pass at t reads the rollout's predicted frames t-2..t and "
                                  "produces t+1");
  }
  Explanation out;
  out.frame = t;
  out.target = selection.target;
  out.point = selection.point;
  out.points = chosen_points(rollout, selection);
  out.object = rollout.object_ids[static_cast<size_t>(out.points.front())];
  out.error = mean_error_of(rollout, out.points, t + 1);
  out.error_growth = out.error - mean_error_of(rollout, out.points, t);

  const auto f = static_cast<size_t>(t);
  PointState state = PointState::from_positions(rollout.predicted[f], rollout.predicted[f - 1],
                                                rollout.predicted[f - 2], rollout.object_ids);
  state.faces = rollout.faces;
  state.static_points = rollout.static_points;

  std::lock_guard<std::mutex> lock(impl_->mutex);
  DynamicsModel& model = impl_->model;
  std::map<std::tuple<std::string, int, int32_t>, GroupSum> groups;
  try {
    torch::AutoGradMode grad_mode(true);
    const Hierarchy h = model->build_hierarchy(state);
    ModelInput input = make_model_input(state, h);
    std::vector<GatedList> gated;
    std::vector<torch::Tensor> gates;
    auto gate = [&](NeighborTensors& nt, const std::string& list, int level, int source_level) {
      if (nt.rows() == 0 || nt.index.size(1) == 0) return;
      nt.gate = torch::ones({nt.rows(), nt.index.size(1)}, torch::kFloat).requires_grad_(true);
      gated.push_back({list, level, source_level, &nt});
      gates.push_back(nt.gate);
    };
    for (int l = 0; l < input.hierarchy.num_levels(); ++l) {
      LevelTensors& level = input.hierarchy.levels[static_cast<size_t>(l)];
      for (LevelList list : kLevelLists) {
        gate(level_tensors(level, list), level_list_name(list), l, list_source_level(list, l));
      }
    }
    if (h.has_mesh) {
      MeshTensors& mesh = input.hierarchy.levels[0].mesh;
      for (MeshList list : kMeshLists) {
        gate(mesh_tensors(mesh, list), mesh_list_name(list), 0, mesh_list_source_level(list));
      }
    }

    // [N,3] float32; static points held where the model holds them, as in its rollouts.
    const torch::Tensor delta = model->hold_static_points(model->predict_delta(input), state);
    const torch::Tensor chosen =
        torch::tensor(std::vector<int64_t>(out.points.begin(), out.points.end()), torch::kInt64);
    torch::Tensor per_point;  // [S,3]
    if (selection.target == ExplainTarget::kError) {
      const torch::Tensor truth = points_to_tensor(rollout.truth[f + 1]).index_select(0, chosen);
      per_point = (input.position + delta.to(torch::kDouble)).index_select(0, chosen) - truth;
    } else {
      per_point = (delta - input.velocity).index_select(0, chosen).to(torch::kDouble);
    }
    // The tiny offset keeps the norm differentiable where a prediction is exact.
    const torch::Tensor e = (per_point.pow(2).sum(1) + 1e-24).sqrt().mean();
    out.value = e.item<double>();
    if (gates.empty()) return out;
    const std::vector<torch::Tensor> grads =
        torch::autograd::grad({e}, gates, {}, /*retain_graph=*/false, /*create_graph=*/false,
                              /*allow_unused=*/true);

    const SourceMap sources(h);
    for (size_t i = 0; i < gated.size(); ++i) {
      if (!grads[i].defined()) continue;
      const GatedList& g = gated[i];
      const torch::Tensor grad = grads[i].to(torch::kDouble).contiguous();
      const torch::Tensor index = g.tensors->index.contiguous();
      const torch::Tensor mask = g.tensors->mask.to(torch::kUInt8).contiguous();
      const double* gp = grad.data_ptr<double>();
      const int64_t* ip = index.data_ptr<int64_t>();
      const uint8_t* mp = mask.data_ptr<uint8_t>();
      for (int64_t a = 0; a < grad.numel(); ++a) {
        if (!mp[a] || gp[a] == 0.0) continue;
        const int j = static_cast<int>(ip[a]);
        GroupSum& sum = groups[{g.list, g.level, sources.object(g.source_level, j)}];
        const double magnitude = std::abs(gp[a]);
        sum.magnitude += magnitude;
        sum.effect += gp[a];
        ++sum.edges;
        sources.spread(g.source_level, j, [&](int point, double fraction) {
          sum.points[point] += fraction * magnitude;
        });
      }
    }
  } catch (const c10::Error& e) {
    throw Error(impl_->path + ": explanation failed: " + e.what_without_backtrace());
  }

  double total = 0.0;
  for (const auto& [key, sum] : groups) total += sum.magnitude;
  out.edge_total = total;
  out.point_shares.assign(static_cast<size_t>(rollout.num_points()), 0.0);
  if (total <= 0.0) return out;
  for (const auto& [key, sum] : groups) {
    Contributor c;
    std::tie(c.list, c.level, c.object) = key;
    c.share = sum.magnitude / total;
    c.magnitude = sum.magnitude;
    c.effect = sum.effect;
    c.edges = sum.edges;
    for (const auto& [point, magnitude] : sum.points) {
      c.points.push_back(point);
      c.point_shares.push_back(magnitude / total);
      out.point_shares[static_cast<size_t>(point)] += magnitude / total;
    }
    out.contributors.push_back(std::move(c));
  }
  // std::map already orders ties by (list, level, object); the stable sort keeps that.
  std::stable_sort(out.contributors.begin(), out.contributors.end(),
                   [](const Contributor& a, const Contributor& b) { return a.share > b.share; });
  return out;
}

}  // namespace dynscope
