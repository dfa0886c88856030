// DynamicsModel: permutation equivariance, x/y translation invariance, position update,
// statistics, small objects, and overfitting one transition.
#include "engine/model/dynamics_model.h"

#include <gtest/gtest.h>
#include <torch/nn/functional/loss.h>
#include <torch/optim/adam.h>
#include <torch/types.h>
#include <torch/utils.h>

#include "engine/core/error.h"
#include "engine/core/threads.h"
#include "engine/model/torch_runtime.h"
#include "tests/model/model_test_util.h"

namespace dynscope {
namespace {

using testing::make_scene;
using testing::make_state;
using testing::tiny_config;

NormStats some_stats() {
  NormStats s;
  s.velocity_mean = Vec3(0.001, -0.02, -0.04);
  s.velocity_std = Vec3(0.01, 0.005, 0.02);
  s.target_mean = Vec3(0.0, 0.0, -0.01);
  s.target_std = Vec3(0.003, 0.003, 0.004);
  s.z_mean = 0.2;
  s.z_std = 0.1;
  return s;
}

TEST(DynamicsModelTest, PermutingInputPointsPermutesPredictions) {
  torch::manual_seed(1);
  for (ModelKind kind : {ModelKind::kPointConv, ModelKind::kGnn, ModelKind::kFlat}) {
    DynamicsModel model(tiny_config(kind));
    model->set_stats(some_stats());
    const auto scene = make_scene(3, 60, 1);
    const PointState st = make_state(scene, 2);
    const Points p = model->predict_next(st);

    std::vector<int> perm(static_cast<size_t>(st.size()));
    for (size_t i = 0; i < perm.size(); ++i)
      perm[i] = static_cast<int>((i * 37 + 11) % perm.size());
    PointState ps = st;
    for (size_t i = 0; i < perm.size(); ++i) {
      ps.position.row(i) = st.position.row(perm[i]);
      ps.velocity.row(i) = st.velocity.row(perm[i]);
      ps.prev_velocity.row(i) = st.prev_velocity.row(perm[i]);
      ps.object_ids[i] = st.object_ids[static_cast<size_t>(perm[i])];
    }
    const Points q = model->predict_next(ps);
    double worst = 0.0;
    for (size_t i = 0; i < perm.size(); ++i) {
      worst = std::max(worst, (q.row(i) - p.row(perm[i])).norm());
    }
    EXPECT_LT(worst, 1e-6) << to_string(kind);
  }
}

TEST(DynamicsModelTest, TranslationInXYLeavesDisplacementUnchanged) {
  torch::manual_seed(2);
  for (ModelKind kind : {ModelKind::kPointConv, ModelKind::kGnn, ModelKind::kFlat}) {
    DynamicsModel model(tiny_config(kind));
    model->set_stats(some_stats());
    const auto scene = make_scene(3, 60, 3);
    const PointState st = make_state(scene, 4);
    PointState moved = st;
    moved.position.col(0).array() += 3.7;
    moved.position.col(1).array() -= 12.25;
    const Points d1 = model->predict_next(st) - st.position;
    const Points d2 = model->predict_next(moved) - moved.position;
    EXPECT_LT((d1 - d2).cwiseAbs().maxCoeff(), 1e-6) << to_string(kind);
    // Height is an input: moving in z changes the prediction.
    PointState lifted = st;
    lifted.position.col(2).array() += 0.5;
    const Points d3 = model->predict_next(lifted) - lifted.position;
    EXPECT_GT((d1 - d3).cwiseAbs().maxCoeff(), 1e-7) << to_string(kind);
  }
}

TEST(DynamicsModelTest, PositionUpdateFollowsTargetMode) {
  torch::manual_seed(3);
  const auto scene = make_scene(2, 40, 5);
  const PointState st = make_state(scene, 6);
  for (TargetMode mode : {TargetMode::kAcceleration, TargetMode::kVelocity}) {
    ModelConfig c = tiny_config();
    c.target = mode;
    DynamicsModel model(c);
    model->set_stats(some_stats());
    torch::NoGradGuard no_grad;
    const ModelInput in = make_model_input(st, model->build_hierarchy(st));
    const torch::Tensor raw = model->forward(in);
    const torch::Tensor target =
        raw * torch::tensor({0.003f, 0.003f, 0.004f}) + torch::tensor({0.0f, 0.0f, -0.01f});
    const torch::Tensor expected =
        mode == TargetMode::kAcceleration ? in.velocity + target : target;
    EXPECT_TRUE(torch::allclose(model->predict_delta(in), expected, 1e-5, 1e-7));
    EXPECT_TRUE(torch::allclose(model->predict_positions(in),
                                in.position + expected.to(torch::kDouble), 1e-6, 1e-8));
    EXPECT_TRUE(torch::allclose(model->normalize_target(target), raw, 1e-4, 1e-5));
  }
}

TEST(DynamicsModelTest, StatsRoundTripAndValidation) {
  DynamicsModel model(tiny_config());
  model->set_stats(some_stats());
  const NormStats s = model->stats();
  EXPECT_NEAR(s.velocity_std.y(), 0.005, 1e-9);
  EXPECT_NEAR(s.z_mean, 0.2, 1e-7);
  NormStats bad = some_stats();
  bad.target_std.x() = 0.0;
  EXPECT_THROW(model->set_stats(bad), ValueError);
}

TEST(DynamicsModelTest, ObjectWithFewerThanKPointsWorks) {
  auto scene = make_scene(2, 50, 7);
  scene.points.conservativeResize(102, 3);
  scene.points.bottomRows(2) << 0.6, 0.1, 0.2, 0.62, 0.1, 0.21;
  scene.ids.insert(scene.ids.end(), {77, 77});
  DynamicsModel model(tiny_config());
  const Points p = model->predict_next(make_state(scene, 8));
  EXPECT_TRUE(p.allFinite());
  EXPECT_EQ(p.rows(), 102);
}

// A step's prediction does not depend on the compute threads: on more than one the hierarchy,
// the input and the pass share one region, the kernels' rows as tasks. Boxes 0.05 apart, so the
// relational lists hold rows with and without neighbours; the model's own kernel sizes (the
// Physion preset, C = 16) and the generic ones (tiny_config).
TEST(DynamicsModelTest, PredictionsDoNotDependOnTheThreadCount) {
  const int saved = compute_threads();
  const auto scene = make_scene(4, 300, 21);
  const PointState st = make_state(scene, 3);
  ModelConfig physion = ModelConfig::preset("physion");
  physion.width = 16;
  physion.levels = 3;
  physion.bottleneck_blocks = 1;
  for (const ModelConfig& config :
       {tiny_config(ModelKind::kPointConv), tiny_config(ModelKind::kGnn),
        tiny_config(ModelKind::kFlat), physion}) {
    torch::manual_seed(3);
    DynamicsModel model(config);
    model->set_stats(some_stats());
    model->eval();
    set_torch_threads(1);
    const Points one = model->predict_next(st);
    for (int threads : {2, 3}) {
      set_torch_threads(threads);
      const Points many = model->predict_next(st);
      EXPECT_LT((many - one).cwiseAbs().maxCoeff(), 1e-9)
          << to_string(config.kind) << " C = " << config.width << ", " << threads << " threads";
    }
  }
  set_torch_threads(saved);
}

TEST(DynamicsModelTest, RejectsMismatchedState) {
  const auto scene = make_scene(2, 20, 9);
  DynamicsModel model(tiny_config());
  PointState st = make_state(scene, 1);
  st.object_ids.pop_back();
  EXPECT_THROW(model->predict_next(st), ValueError);
  PointState wrong_mask = make_state(scene, 1);
  wrong_mask.static_points.assign(39, 0);
  EXPECT_THROW(model->predict_next(wrong_mask), ValueError);
  // Found inside the step's region of two threads, the error still reaches the caller.
  const int saved = compute_threads();
  set_torch_threads(2);
  EXPECT_THROW(model->predict_next(wrong_mask), ValueError);
  set_torch_threads(saved);
}

// hold_static: the state's static points keep p(t) exactly, every other point gets the
// prediction of the same network without it; a state that marks nothing is predicted whole.
TEST(DynamicsModelTest, HeldStaticPointsKeepTheirPositionExactly) {
  const auto scene = make_scene(3, 20, 4);
  ModelConfig held_config = tiny_config();
  held_config.hold_static = true;
  torch::manual_seed(5);
  DynamicsModel plain(tiny_config());
  plain->set_stats(some_stats());
  DynamicsModel held(held_config);
  {
    torch::NoGradGuard no_grad;
    const auto source = plain->named_parameters();
    for (auto& item : held->named_parameters()) item.value().copy_(source[item.key()]);
  }
  held->set_stats(some_stats());
  PointState st = make_state(scene, 2);
  st.static_points.assign(60, 0);
  for (int i = 20; i < 40; ++i) st.static_points[static_cast<size_t>(i)] = 1;  // the middle box
  const Points p = plain->predict_next(st);
  const Points h = held->predict_next(st);
  for (Eigen::Index i = 0; i < 60; ++i) {
    if (st.static_points[static_cast<size_t>(i)] != 0) {
      EXPECT_TRUE(h.row(i) == st.position.row(i)) << i;
      EXPECT_GT((p.row(i) - st.position.row(i)).norm(), 1e-6) << i;  // it would have moved
    } else {
      EXPECT_TRUE(h.row(i) == p.row(i)) << i;
    }
  }
  st.static_points.clear();
  EXPECT_TRUE(held->predict_next(st) == plain->predict_next(st));
}

// Huber loss on p̂(t+1) for one rigid-ish transition must drop 100× under Adam.
TEST(DynamicsModelTest, OverfitsOneTransition) {
  torch::manual_seed(4);
  // Tensors here are tiny: one thread avoids scheduling overhead on a shared 2-core machine.
  const int threads = torch::get_num_threads();
  torch::set_num_threads(1);
  ModelConfig c = tiny_config();
  c.width = 16;
  const auto scene = make_scene(3, 60, 10);
  const PointState st = make_state(scene, 11);
  // Next positions: each object accelerates differently, plus a position-dependent swirl.
  Points next = st.position + st.velocity;
  for (Eigen::Index i = 0; i < st.size(); ++i) {
    const double o = st.object_ids[static_cast<size_t>(i)] - 10;
    next.row(i) += Eigen::RowVector3d(0.004 * o, -0.003 * (o - 1),
                                      -0.01 + 0.02 * (st.position(i, 0) - 0.3 * o));
  }
  DynamicsModel model(c);
  NormStatsAccumulator acc(c.target);
  acc.add(st.position - st.velocity, st.position, next);
  model->set_stats(acc.finish());
  const ModelInput in = make_model_input(st, model->build_hierarchy(st));
  const torch::Tensor truth = points_to_tensor(next);
  torch::optim::Adam adam(model->parameters(), torch::optim::AdamOptions(1e-2));
  auto loss_fn = [&] {
    return torch::nn::functional::huber_loss(model->predict_positions(in), truth);
  };
  const double initial = loss_fn().item<double>();
  double final_loss = initial;
  int steps = 0;
  for (; steps < 400 && final_loss > initial / 100.0; ++steps) {
    adam.zero_grad();
    const torch::Tensor loss = loss_fn();
    loss.backward();
    adam.step();
    final_loss = loss.item<double>();
  }
  EXPECT_LT(final_loss, initial / 100.0) << "initial " << initial;
  RecordProperty("adam_steps", steps);
  torch::set_num_threads(threads);
}

}  // namespace
}  // namespace dynscope

namespace dynscope {
namespace {

// A batch of inputs through one forward pass equals the inputs one by one, for every model kind
// (the lists are offset per input and padded to the widest K).
TEST(DynamicsModelBatchTest, ConcatenatedInputsGiveTheSeparatePredictions) {
  torch::manual_seed(3);
  for (ModelKind kind : {ModelKind::kPointConv, ModelKind::kGnn, ModelKind::kFlat}) {
    DynamicsModel model(testing::tiny_config(kind));
    model->set_stats(some_stats());
    std::vector<ModelInput> inputs;
    std::vector<torch::Tensor> separate;
    for (int b = 0; b < 3; ++b) {
      const PointState st = testing::make_state(testing::make_scene(2 + b, 30 + 7 * b, 5 + b), b);
      inputs.push_back(make_model_input(st, model->build_hierarchy(st)));
      separate.push_back(model->predict_positions(inputs.back()));
    }
    const ModelInput batch = concatenate_inputs(inputs);
    const torch::Tensor together = model->predict_positions(batch);
    EXPECT_TRUE(torch::allclose(together, torch::cat(separate), 1e-6, 1e-7)) << to_string(kind);
    // The same batch on the unprepared lists (no cached relative positions): same numbers.
    ModelInput plain = batch;
    for (LevelTensors& level : plain.hierarchy.levels) {
      for (NeighborTensors* list : {&level.same, &level.relational, &level.down, &level.up}) {
        list->rel = list->count = list->has_any = torch::Tensor();
      }
    }
    EXPECT_TRUE(torch::allclose(model->predict_positions(plain), together, 1e-6, 1e-7));
  }
  EXPECT_THROW(concatenate_inputs({}), ValueError);
}

// The same for mesh input, whose interaction-point lists differ in width between inputs.
TEST(DynamicsModelBatchTest, ConcatenatedMeshInputsGiveTheSeparatePredictions) {
  torch::manual_seed(4);
  ModelConfig config = testing::tiny_config(ModelKind::kPointConv);
  config.input = InputMode::kMesh;
  config.interaction_threshold = 0.1;
  DynamicsModel model(config);
  std::vector<ModelInput> inputs;
  std::vector<torch::Tensor> separate;
  for (double gap : {0.03, 0.08}) {
    const testing::TestMesh m = testing::make_two_boxes(gap);
    PointState st;
    st.position = m.vertices;
    st.velocity = Points::Constant(m.vertices.rows(), 3, 0.01);
    st.prev_velocity = Points::Constant(m.vertices.rows(), 3, 0.005);
    st.object_ids = m.ids;
    st.faces = m.faces;
    inputs.push_back(make_model_input(st, model->build_hierarchy(st)));
    ASSERT_GT(inputs.back().hierarchy.levels[0].mesh.points.size(0), 0) << "gap " << gap;
    separate.push_back(model->predict_positions(inputs.back()));
  }
  const torch::Tensor together = model->predict_positions(concatenate_inputs(inputs));
  EXPECT_TRUE(torch::allclose(together, torch::cat(separate), 1e-6, 1e-7));
}

}  // namespace
}  // namespace dynscope
