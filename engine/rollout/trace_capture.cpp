// Debug-trace capture through the model's BlockRecords and PointConv::filter_weights.
#include "engine/rollout/trace_capture.h"

#include <c10/util/Exception.h>
#include <torch/torch.h>

#include <algorithm>

#include "engine/core/error.h"
#include "engine/model/checkpoint.h"
#include "engine/rollout/level_view.h"
#include "engine/rollout/state_history.h"

namespace dynscope {

namespace {

// One PointConv of the U-Net and where it reads: its query level, the list level/name, and the
// tensors of its query points, source points and neighbour list.
struct ConvSite {
  std::string path;
  PointConv conv{nullptr};
  int level = 0;
  std::string list;
  torch::Tensor query, source;
  NeighborTensors neighbors;
};

void add_site(std::vector<ConvSite>& sites, const std::string& path, const ConvUnit& unit,
              int level, const std::string& list, const torch::Tensor& query,
              const torch::Tensor& source, const NeighborTensors& neighbors) {
  if (!unit || !unit->point_conv || neighbors.rows() == 0) return;
  sites.push_back({path, unit->point_conv, level, list, query, source, neighbors});
}

std::vector<ConvSite> conv_sites(UNetImpl& unet, const HierarchyTensors& h) {
  std::vector<ConvSite> sites;
  const auto& lv = h.levels;
  const int levels = h.num_levels();
  auto block = [](const torch::nn::ModuleList& list, size_t i) {
    return list->ptr(i)->as<InteractionBlockImpl>();
  };
  auto rel = [&](std::vector<ConvSite>& s, const std::string& prefix, InteractionBlockImpl* b,
                 int l) {
    add_site(s, prefix + ".relational.conv", b->relational, l,
             level_list_path(l, LevelList::kRelational), lv[l].points, lv[l].points,
             lv[l].relational);
  };
  for (size_t i = 0; i < unet.stem_list->size(); ++i) {
    InteractionBlockImpl* b = block(unet.stem_list, i);
    const std::string p = "unet.stem." + std::to_string(i);
    add_site(sites, p + ".object.conv", b->object, 0, level_list_path(0, LevelList::kSame),
             lv[0].points, lv[0].points, lv[0].same);
    rel(sites, p, b, 0);
  }
  for (int l = 0; l + 1 < levels; ++l) {
    InteractionBlockImpl* b = block(unet.encoder_list, static_cast<size_t>(l));
    const std::string p = "unet.encoder." + std::to_string(l);
    add_site(sites, p + ".object.conv", b->object, l + 1, std::to_string(l + 1) + "/down",
             lv[l + 1].points, lv[l].points, lv[l + 1].down);
    rel(sites, p, b, l + 1);
  }
  for (size_t i = 0; i < unet.bottleneck_list->size(); ++i) {
    InteractionBlockImpl* b = block(unet.bottleneck_list, i);
    const int l = levels - 1;
    const std::string p = "unet.bottleneck." + std::to_string(i);
    add_site(sites, p + ".object.conv", b->object, l, level_list_path(l, LevelList::kSame),
             lv[l].points, lv[l].points, lv[l].same);
    rel(sites, p, b, l);
  }
  for (int l = levels - 2, j = 0; l >= 0; --l, ++j) {
    InteractionBlockImpl* b = block(unet.decoder_list, static_cast<size_t>(j));
    const std::string p = "unet.decoder." + std::to_string(j);
    add_site(sites, p + ".object.conv", b->object, l, std::to_string(l + 1) + "/up", lv[l].points,
             lv[l + 1].points, lv[l + 1].up);
    rel(sites, p, b, l);
  }
  return sites;
}

// One forward pass on `state` (the model's input at `frame`), recorded.
ModelTrace capture(DynamicsModel& model, const PointState& state, int frame,
                   const std::vector<int>& queries) {
  for (int q : queries) {
    if (q < 0 || q >= state.size()) {
      throw ValueError("query", "point " + std::to_string(q) + " outside [0, " +
                                    std::to_string(state.size()) + ")");
    }
  }
  torch::NoGradGuard no_grad;
  const Hierarchy h = model->build_hierarchy(state);
  const ModelInput input = make_model_input(state, h);
  std::vector<BlockRecord> records;
  model->forward(input, &records);

  ModelTrace t = hierarchy_trace(h, state.faces, frame, model->config());
  for (const BlockRecord& r : records) {
    const torch::Tensor n = r.features.pow(2).sum(1).sqrt().to(torch::kDouble).contiguous();
    t.features.push_back(
        {r.name, r.level,
         std::vector<double>(n.data_ptr<double>(), n.data_ptr<double>() + n.numel())});
  }
  std::vector<ConvSite> sites = conv_sites(*model->unet, input.hierarchy);
  for (int q : queries) {
    // Representative of the query point at each level: column 0 of the upsampling list is the
    // nearest coarser point of the same object.
    std::vector<int> rep{q};
    for (int l = 1; l < h.num_levels(); ++l) {
      const NeighborList& up = h.levels[static_cast<size_t>(l)].up;
      const int prev = rep.back();
      rep.push_back(prev >= 0 && up.rows() > prev && up.mask(prev, 0) ? up.index(prev, 0) : -1);
    }
    for (ConvSite& s : sites) {
      const int row = rep[static_cast<size_t>(s.level)];
      if (row < 0 || row >= s.neighbors.rows()) continue;
      NeighborTensors one;
      one.index = s.neighbors.index.narrow(0, row, 1);
      one.mask = s.neighbors.mask.narrow(0, row, 1);
      const torch::Tensor w = s.conv->filter_weights(s.query.narrow(0, row, 1), s.source, one)
                                  .squeeze(0)
                                  .to(torch::kDouble)
                                  .contiguous();
      TraceQuery tq;
      tq.point = q;
      tq.conv = s.path;
      tq.level = s.level;
      tq.list = s.list;
      tq.query_index = row;
      const torch::Tensor idx = one.index.squeeze(0).to(torch::kInt).contiguous();
      const torch::Tensor mask = one.mask.squeeze(0).to(torch::kUInt8).contiguous();
      tq.neighbors.assign(idx.data_ptr<int32_t>(), idx.data_ptr<int32_t>() + idx.numel());
      tq.mask.assign(mask.data_ptr<uint8_t>(), mask.data_ptr<uint8_t>() + mask.numel());
      tq.weights =
          Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
              w.data_ptr<double>(), w.size(0), w.size(1));
      t.queries.push_back(std::move(tq));
    }
  }
  return t;
}

// Loads the checkpoint and records one pass on `state`; LibTorch errors name the checkpoint.
ModelTrace capture_with(const std::string& checkpoint_path, const PointState& state, int frame,
                        const std::vector<int>& queries) {
  try {
    DynamicsModel model = load_checkpoint(checkpoint_path);
    model->eval();
    ModelTrace t = capture(model, state, frame, queries);
    t.checkpoint_path = checkpoint_path;
    return t;
  } catch (const c10::Error& e) {
    throw Error(checkpoint_path + ": trace failed: " + e.what_without_backtrace());
  }
}

}  // namespace

ModelTrace capture_trace(const std::string& checkpoint_path, const Scene& scene,
                         const ModelPoints& points, int frame, const std::vector<int>& queries) {
  if (frame < 2 || frame >= scene.num_frames()) {
    throw ValueError("frame", std::to_string(frame) + " outside [2, " +
                                  std::to_string(scene.num_frames() - 1) +
                                  "] (the state needs frames t−2 and t−1)");
  }
  PointState state =
      PointState::from_positions(points.positions(scene, frame), points.positions(scene, frame - 1),
                                 points.positions(scene, frame - 2), points.cloud.object_id);
  state.faces = points.faces;
  ModelTrace t = capture_with(checkpoint_path, state, frame, queries);
  t.source = kTraceSourceScene;
  return t;
}

ModelTrace capture_rollout_trace(const std::string& checkpoint_path, const Rollout& rollout,
                                 int frame, const std::vector<int>& queries) {
  const int first = first_rollout_trace_frame(rollout.observed_frames);
  const int last = rollout.num_frames() - 2;
  if (frame < first || frame > last) {
    throw ValueError("frame", std::to_string(frame) + " outside [" + std::to_string(first) + ", " +
                                  std::to_string(last) +
                                  "]: the rollout's predicted frame t+1 must come from the "
                                  "model's pass at t, which reads frames t-2..t");
  }
  const auto f = static_cast<size_t>(frame);
  PointState state = PointState::from_positions(rollout.predicted[f], rollout.predicted[f - 1],
                                                rollout.predicted[f - 2], rollout.object_ids);
  state.faces = rollout.faces;
  ModelTrace t = capture_with(checkpoint_path, state, frame, queries);
  t.source = kTraceSourceRollout;
  t.scene_path = rollout.scene_path;
  return t;
}

}  // namespace dynscope
