// Training: recipes round-trip, a resumed run equals an uninterrupted one, clear errors.
#include "engine/train/trainer.h"

#include <gtest/gtest.h>
#include <torch/torch.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "engine/core/error.h"
#include "engine/core/rng.h"
#include "engine/io/scene_file.h"
#include "engine/model/checkpoint.h"
#include "engine/rollout/pose_fitting.h"
#include "engine/rollout/rollout_runner.h"
#include "engine/sim/dataset.h"
#include "engine/train/point_loss.h"
#include "tests/train/train_fixtures.h"

namespace dynscope {
namespace {

namespace fs = std::filesystem;

// A tiny drop dataset shared by the tests of this file (10 scenes: 8 train, 1 val, 1 test).
const std::string& dataset_dir() {
  static const std::string dir = testing::generate_tiny_dataset("train_test", "drop", 10, 5);
  return dir;
}

TrainOptions tiny_options(const std::string& out) {
  TrainOptions o = testing::tiny_train_options(dataset_dir(), out);
  o.seed = 11;
  return o;
}

using testing::expect_same_weights;

std::string read_text_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(TrainerTest, ResumedRunEqualsUninterruptedRun) {
  const fs::path dir =
      fs::temp_directory_path() / ("dynscope_train_test_resume_" + std::to_string(getpid()));
  fs::create_directories(dir);
  TrainOptions straight = tiny_options((dir / "straight.pt").string());
  straight.max_steps = 4;
  const TrainResult r4 = train_model(straight);
  EXPECT_EQ(r4.steps, 4);

  TrainOptions first = tiny_options((dir / "resumed.pt").string());
  first.max_steps = 2;
  EXPECT_EQ(train_model(first).steps, 2);
  TrainOptions second = first;
  second.max_steps = 4;
  second.resume = true;
  const TrainResult r = train_model(second);
  EXPECT_EQ(r.start_step, 2);
  EXPECT_EQ(r.steps, 4);
  expect_same_weights(straight.out, second.out);
  EXPECT_TRUE(fs::exists(recipe_path(second.out)));
}

// A run in sittings (the way a long budget is spent): the cosine learning rate, the data and the
// optimiser continue exactly, the recipe sums steps, wall time and sittings, and the checkpoint of
// the best validation epoch is kept with its own recipe.
TEST(TrainerTest, ACosineRunInChunksEqualsOneSittingAndKeepsItsBestEpoch) {
  const fs::path dir =
      fs::temp_directory_path() / ("dynscope_train_test_chunks_" + std::to_string(getpid()));
  fs::create_directories(dir);
  auto options = [&](const std::string& name) {
    TrainOptions o = tiny_options((dir / name).string());
    o.lr_schedule = "cosine";
    o.lr = 3e-3;
    o.epochs = 2;
    o.samples_per_scene = 1;  // 8 training scenes: 8 steps per epoch, 16 in all
    return o;
  };
  const TrainOptions straight = options("straight.pt");
  const TrainResult whole = train_model(straight);
  ASSERT_EQ(whole.steps, 16);
  EXPECT_EQ(whole.chunks, 1);

  TrainOptions chunk = options("chunks.pt");
  chunk.keep_epochs = true;
  chunk.max_steps = 5;
  EXPECT_EQ(train_model(chunk).steps, 5);
  // A sitting cut short by max_steps still records the whole run as planned (run.sh reads
  // steps == total_steps as finished).
  const nlohmann::json first_sitting = nlohmann::json::parse(
      TrainOptions::from_json(read_text_file(recipe_path(chunk.out)), "recipe").progress_json);
  EXPECT_EQ(first_sitting.at("steps"), 5);
  EXPECT_EQ(first_sitting.at("total_steps"), 16);
  chunk.max_steps = 11;
  chunk.resume = true;
  EXPECT_EQ(train_model(chunk).steps, 11);
  chunk.max_steps = 0;
  const TrainResult last = train_model(chunk);
  EXPECT_EQ(last.start_step, 11);
  EXPECT_EQ(last.steps, 16);
  EXPECT_EQ(last.chunks, 3);
  EXPECT_GE(last.wall_seconds, last.train_seconds);
  expect_same_weights(straight.out, chunk.out);

  const TrainOptions recorded =
      TrainOptions::from_json(read_text_file(recipe_path(chunk.out)), "recipe");
  const nlohmann::json progress = nlohmann::json::parse(recorded.progress_json);
  EXPECT_EQ(progress.at("steps"), 16);
  EXPECT_EQ(progress.at("total_steps"), 16);
  EXPECT_EQ(progress.at("chunks"), 3);
  // The recipe keeps wall time to 0.1 s: a run this small may round to zero, so the record is
  // checked against the run's own sum rather than against zero.
  EXPECT_GT(last.wall_seconds, 0.0);
  EXPECT_NEAR(progress.at("wall_time_s").get<double>(), last.wall_seconds, 0.05 + 1e-9);
  EXPECT_EQ(recorded.lr_schedule, "cosine");

  // The best of the two validated epochs (steps 8 and 16), chosen on validation alone.
  const int64_t best = progress.at("best").at("step").get<int64_t>();
  ASSERT_TRUE(best == 8 || best == 16) << best;
  EXPECT_EQ(best, whole.best_step);
  const std::string best_path = best_checkpoint_path(chunk.out);
  EXPECT_EQ(best_path, (dir / "chunks.best.pt").string());
  ASSERT_TRUE(fs::exists(best_path));
  EXPECT_TRUE(fs::exists(recipe_path(best_path)));
  const double first_error = whole.epochs.at(0).val_rollout_error;
  const double second_error = whole.epochs.at(1).val_rollout_error;
  EXPECT_EQ(best, second_error < first_error ? 16 : 8);
  TrainOptions at_best = options("at_best.pt");
  at_best.max_steps = best;
  train_model(at_best);
  expect_same_weights(at_best.out, best_path);

  // keep_epochs keeps each epoch's checkpoint, whichever sitting ended the epoch (the second
  // sitting ended the first epoch at step 8); off by default.
  EXPECT_EQ(epoch_checkpoint_path(chunk.out, 1), (dir / "chunks.epoch01.pt").string());
  EXPECT_EQ(epoch_checkpoint_path("run", 12), "run.epoch12.pt");
  TrainOptions first_epoch = options("first_epoch.pt");
  first_epoch.max_steps = 8;
  train_model(first_epoch);
  expect_same_weights(first_epoch.out, epoch_checkpoint_path(chunk.out, 1));
  expect_same_weights(straight.out, epoch_checkpoint_path(chunk.out, 2));
  EXPECT_TRUE(fs::exists(recipe_path(epoch_checkpoint_path(chunk.out, 1))));
  EXPECT_FALSE(fs::exists(epoch_checkpoint_path(chunk.out, 3)));
  EXPECT_FALSE(fs::exists(epoch_checkpoint_path(straight.out, 1)));
  fs::remove_all(dir);
}

// init_seed sets the initial weights alone and seed the data draws (scene order, frames, noise):
// with a learning rate too small to move the weights, runs sharing init_seed keep equal weights
// whatever their seed, yet see different first examples; init_seed equal to seed is the plain run.
TEST(TrainerTest, TheInitSeedSetsTheWeightsAndTheSeedTheDataDraws) {
  const fs::path dir =
      fs::temp_directory_path() / ("dynscope_train_test_init_seed_" + std::to_string(getpid()));
  fs::create_directories(dir);
  auto run = [&](const std::string& name, uint64_t seed, std::optional<uint64_t> init_seed) {
    TrainOptions o = tiny_options((dir / name).string());
    o.seed = seed;
    o.init_seed = init_seed;
    o.lr = 1e-12;
    o.max_steps = 2;
    return std::make_pair(o.out, train_model(o));
  };
  const auto [x_path, x] = run("x.pt", 11, 5);
  const auto [y_path, y] = run("y.pt", 5, std::nullopt);
  const auto [z_path, z] = run("z.pt", 11, std::nullopt);
  const auto [z2_path, z2] = run("z2.pt", 11, 11);
  auto max_difference = [](const std::string& a, const std::string& b) {
    DynamicsModel ma = load_checkpoint(a);
    DynamicsModel mb = load_checkpoint(b);
    const auto pb = mb->named_parameters();
    double most = 0.0;
    for (const auto& item : ma->named_parameters()) {
      most = std::max(most, (item.value() - pb[item.key()]).abs().max().item<double>());
    }
    return most;
  };
  EXPECT_LT(max_difference(x_path, y_path), 1e-9) << "init_seed 5 initialises as seed 5 does";
  EXPECT_GT(max_difference(x_path, z_path), 1e-3) << "seed 11 no longer sets the weights";
  ASSERT_FALSE(x.losses.empty());
  ASSERT_FALSE(y.losses.empty());
  EXPECT_NE(x.losses.front(), y.losses.front()) << "same weights, seed 11's examples, not 5's";
  expect_same_weights(z_path, z2_path);
  EXPECT_EQ(z.losses, z2.losses);
  // The recipe beside the checkpoint records the field when set, so a resume or a rerun repeats it.
  const TrainOptions recorded = TrainOptions::from_json(read_text_file(recipe_path(x_path)), "r");
  EXPECT_EQ(recorded.init_seed, std::optional<uint64_t>(5));
  EXPECT_FALSE(TrainOptions::from_json(read_text_file(recipe_path(y_path)), "r").init_seed);
  fs::remove_all(dir);
}

TEST(TrainerTest, ResumeWithAnotherArchitectureIsAClearError) {
  const fs::path dir =
      fs::temp_directory_path() / ("dynscope_train_test_mismatch_" + std::to_string(getpid()));
  fs::create_directories(dir);
  TrainOptions o = tiny_options((dir / "m.pt").string());
  o.max_steps = 1;
  train_model(o);
  o.model.width = 12;
  o.resume = true;
  o.max_steps = 2;
  EXPECT_THROW(train_model(o), Error);
}

TEST(TrainerTest, TrainsOnSeveralDatasetsOfOneScaleAndRejectsMixedScales) {
  const fs::path dir =
      fs::temp_directory_path() / ("dynscope_train_test_multi_" + std::to_string(getpid()));
  fs::remove_all(dir);
  DatasetOptions g;
  g.scenario = "collide";
  g.count = 10;
  g.seed = 6;
  g.out_dir = (dir / "collide").string();
  generate_dataset(g);
  TrainOptions o = tiny_options((dir / "multi.pt").string());
  o.data_dirs.push_back(g.out_dir);
  o.val_scenes = 2;
  o.samples_per_scene = 1;
  o.epochs = 1;
  const TrainResult r = train_model(o);
  EXPECT_EQ(r.steps_per_epoch, 16) << "8 training scenes from each of the two datasets";
  ASSERT_EQ(r.epochs.size(), 1u);
  EXPECT_TRUE(std::isfinite(r.epochs[0].val_loss));

  g.scenario = "movi-a";
  g.count = 10;
  g.out_dir = (dir / "movi-a").string();
  generate_dataset(g);
  TrainOptions mixed = tiny_options((dir / "mixed.pt").string());
  mixed.data_dirs.push_back(g.out_dir);
  try {
    train_model(mixed);
    FAIL() << "drop and movi-a have different scales";
  } catch (const ValueError& e) {
    EXPECT_EQ(e.name(), "data");
  }
  fs::remove_all(dir);
}

// Per-point noise: independent per point with the GNS random walk's stds (σ/√2 on v_prev, σ on
// v). Per-object noise: the same stds, one draw shared by every point of an object, so a rigid
// object's points keep their true relative velocities; objects differ and the draw does not
// depend on the order of the points. Centred: per point, each object's mean removed.
// The loss leaves held static rows out: their error, however large, adds nothing and gets no
// gradient; the other rows give the Huber loss of their error in target stds.
TEST(PointLossTest, RowsMarkedStaticAddNothingAndGetNoGradient) {
  const Vec3 target_std(0.5, 1.0, 2.0);
  const torch::Tensor truth = torch::zeros({3, 3}, torch::kDouble);
  torch::Tensor predicted =
      torch::tensor({0.25, -1.0, 4.0, 100.0, 100.0, 100.0, 1.0, 0.0, 0.0}, torch::kDouble)
          .view({3, 3})
          .requires_grad_(true);
  const torch::Tensor moving = torch::tensor({1.0f, 0.0f, 1.0f}).view({3, 1});
  const torch::Tensor loss = point_loss_sum(predicted, truth, target_std, 1.0, moving);
  // In stds, row 0 is (0.5, -1, 2) and row 2 (2, 0, 0); Huber with delta 1: 0.125 + 0.5 + 1.5
  // + 1.5.
  EXPECT_NEAR(loss.item<double>(), 3.625, 1e-6);
  loss.backward();
  EXPECT_EQ(predicted.grad()[1].abs().sum().item<double>(), 0.0);
  EXPECT_GT(predicted.grad()[0].abs().sum().item<double>(), 0.0);
  // Without the mask row 1 counts: (200, 100, 50) stds, each |x| - 0.5.
  const torch::Tensor all =
      point_loss_sum(predicted.detach(), truth, target_std, 1.0, torch::Tensor());
  EXPECT_NEAR(all.item<double>(), 3.625 + 348.5, 1e-4);
}

// hold_static end to end: the checkpoint and its recipe carry it, and the model's rollouts keep
// the static bodies (the drop scenes' zone) exactly where they were observed while the target
// falls; the same run without it moves them.
TEST(TrainerTest, AHoldStaticRunKeepsStaticBodiesPutInItsRollouts) {
  const fs::path dir =
      fs::temp_directory_path() / ("dynscope_train_test_hold_" + std::to_string(getpid()));
  fs::create_directories(dir);
  TrainOptions held = tiny_options((dir / "held.pt").string());
  held.max_steps = 3;
  held.model.hold_static = true;
  const TrainResult r = train_model(held);
  ASSERT_EQ(r.steps, 3);
  for (const double loss : r.losses) EXPECT_TRUE(std::isfinite(loss));
  TrainOptions plain = tiny_options((dir / "plain.pt").string());
  plain.max_steps = 3;
  train_model(plain);
  EXPECT_TRUE(
      TrainOptions::from_json(read_text_file(recipe_path(held.out)), held.out).model.hold_static);

  std::string scene_path;
  for (const auto& entry : fs::directory_iterator(dataset_dir())) {
    if (entry.path().extension() == ".h5") scene_path = entry.path().string();
  }
  ASSERT_FALSE(scene_path.empty());
  const Scene scene = read_scene(scene_path);
  auto roll = [&](const std::string& checkpoint) {
    DynamicsModel model = load_checkpoint(checkpoint);
    const ModelPoints points =
        build_model_points(scene, checkpoint_sampling(checkpoint, model->config()));
    RolloutOptions ro;
    ro.frames = 10;
    const Rollout rollout = run_rollout(
        scene, points, [&](const PointState& s) { return model->predict_next(s); }, ro);
    return std::make_pair(rollout, points.cloud.static_mask(scene));
  };
  const auto [held_rollout, mask] = roll(held.out);
  ASSERT_GT(std::count(mask.begin(), mask.end(), 1), 0);
  ASSERT_GT(std::count(mask.begin(), mask.end(), 0), 0);
  double held_static_move = 0.0, held_moving_move = 0.0;
  const Points& observed = held_rollout.predicted[2];
  for (int f = 3; f < 10; ++f) {
    for (Eigen::Index i = 0; i < observed.rows(); ++i) {
      const double d =
          (held_rollout.predicted[static_cast<size_t>(f)].row(i) - observed.row(i)).norm();
      double& largest = mask[static_cast<size_t>(i)] != 0 ? held_static_move : held_moving_move;
      largest = std::max(largest, d);
    }
  }
  EXPECT_LT(held_static_move, 1e-12);
  EXPECT_GT(held_moving_move, 1e-4);
  const auto [plain_rollout, plain_mask] = roll(plain.out);
  double plain_static_move = 0.0;
  for (Eigen::Index i = 0; i < observed.rows(); ++i) {
    if (plain_mask[static_cast<size_t>(i)] != 0) {
      plain_static_move =
          std::max(plain_static_move,
                   (plain_rollout.predicted[9].row(i) - plain_rollout.predicted[2].row(i)).norm());
    }
  }
  EXPECT_GT(plain_static_move, 1e-9);
  fs::remove_all(dir);
}

// Pushing forward (TrainOptions::pushforward_steps = N): the loss of a step is taken at the state
// the model reached itself, n rollout steps from the drawn one, n drawn from 0 to N. One training
// scene of five frames with N = 1 leaves a single loss frame to draw (t = 3), and a learning rate
// far below float precision leaves the saved weights at their initial values, so the first step's
// loss can be recomputed: for n = 1 the checkpoint's prediction from frames 0-2, rigidly
// projected as in a rollout, then its prediction against the true frame 4; for n = 0 its
// prediction from the true frames 1-3. Over eight seeds both must occur.
TEST(TrainerTest, PushingForwardTakesTheLossAtTheModelsOwnNextState) {
  const fs::path dir =
      fs::temp_directory_path() / ("dynscope_train_test_push_" + std::to_string(getpid()));
  fs::create_directories(dir / "data");
  std::string source;
  for (const auto& entry : fs::directory_iterator(dataset_dir())) {
    if (entry.path().extension() == ".h5") source = entry.path().string();
  }
  ASSERT_FALSE(source.empty());
  Scene scene = read_scene(source);
  for (Trajectory& t : scene.trajectories) t.poses.resize(5);
  for (auto& [name, label] : scene.labels) label.resize(5);
  write_scene(scene, (dir / "data" / "short.h5").string());
  {
    std::ofstream manifest(dir / "data" / "manifest.json");
    manifest << R"({"scenario":"drop","split":{"train":["short.h5"],"val":[],"test":[]}})";
  }
  auto options = [&](const std::string& name, int push, uint64_t seed) {
    TrainOptions o = testing::tiny_train_options((dir / "data").string(), (dir / name).string());
    o.seed = seed;
    o.noise_std = 0;
    o.lr = 1e-30;
    o.max_steps = 1;
    o.pushforward_steps = push;
    return o;
  };
  const TrainOptions reference = options("x.pt", 1, 1);
  const ModelPoints points = build_model_points(scene, reference.sampling);
  std::vector<Points> frames;
  for (int f = 0; f < 5; ++f) frames.push_back(points.positions(scene, f));
  auto loss_at = [&](DynamicsModel& model, const PointState& state, const Points& truth) {
    torch::NoGradGuard no_grad;
    const ModelInput input = make_model_input(state, model->build_hierarchy(state));
    return point_loss_sum(model->predict_positions(input), points_to_tensor(truth),
                          model->stats().target_std, reference.huber_delta, torch::Tensor())
               .item<double>() /
           static_cast<double>(state.size() * 3);
  };
  auto state_of = [&](const Points& p0, const Points& p1, const Points& p2) {
    PointState s = PointState::from_positions(p0, p1, p2, points.cloud.object_id);
    s.static_points = points.cloud.static_mask(scene);
    return s;
  };
  int pushed_steps = 0, plain_steps = 0;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    const TrainOptions o = options("pushed" + std::to_string(seed) + ".pt", 1, seed);
    const TrainResult r = train_model(o);
    ASSERT_EQ(r.losses.size(), 1u);
    DynamicsModel model = load_checkpoint(o.out);
    const PointState start = state_of(frames[2], frames[1], frames[0]);
    const Points reached = RigidProjector(points.cloud, scene).project(model->predict_next(start));
    const double own = loss_at(model, state_of(reached, frames[2], frames[1]), frames[4]);
    const double truth = loss_at(model, state_of(frames[3], frames[2], frames[1]), frames[4]);
    EXPECT_GT(std::abs(truth - own), 1e-3 * own) << "the model's own state differs from the truth";
    if (std::abs(r.losses[0] - own) < 1e-6 * own) {
      ++pushed_steps;
    } else {
      EXPECT_NEAR(r.losses[0], truth, 1e-6 * truth) << "seed " << seed;
      ++plain_steps;
    }
  }
  EXPECT_GT(pushed_steps, 0);
  EXPECT_GT(plain_steps, 0);

  // Without pushing forward the step is taken at a true state (t = 2 or 3).
  const TrainOptions plain = options("plain.pt", 0, 3);
  const TrainResult r = train_model(plain);
  DynamicsModel model = load_checkpoint(plain.out);
  const double at3 = loss_at(model, state_of(frames[3], frames[2], frames[1]), frames[4]);
  const double at2 = loss_at(model, state_of(frames[2], frames[1], frames[0]), frames[3]);
  EXPECT_TRUE(std::abs(r.losses[0] - at3) < 1e-6 * at3 || std::abs(r.losses[0] - at2) < 1e-6 * at2);

  // A scene too short to push forward is named.
  try {
    train_model(options("long.pt", 2, 1));
    FAIL() << "pushing up to 2 frames forward needs 6 frames";
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("short.h5 has 5 frames"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// A pushed-forward run continues exactly from its checkpoint, as every run does.
TEST(TrainerTest, APushedForwardRunResumesExactly) {
  const fs::path dir =
      fs::temp_directory_path() / ("dynscope_train_test_push_resume_" + std::to_string(getpid()));
  fs::create_directories(dir);
  TrainOptions straight = tiny_options((dir / "straight.pt").string());
  straight.pushforward_steps = 2;
  straight.max_steps = 4;
  train_model(straight);
  TrainOptions first = straight;
  first.out = (dir / "resumed.pt").string();
  first.max_steps = 2;
  train_model(first);
  TrainOptions second = first;
  second.max_steps = 4;
  second.resume = true;
  EXPECT_EQ(train_model(second).start_step, 2);
  expect_same_weights(straight.out, second.out);
  EXPECT_EQ(TrainOptions::from_json(read_text_file(recipe_path(second.out)), second.out)
                .pushforward_steps,
            2);
  fs::remove_all(dir);
}

TEST(TrainerTest, VelocityNoisePerPointPerObjectAndCentred) {
  const double sigma = 0.01;
  const int n = 4000;
  std::vector<int32_t> ids(n);
  for (int i = 0; i < n; ++i) ids[static_cast<size_t>(i)] = (i * 7) % 400;  // 400 objects
  Points v_true(n, 3);
  for (int i = 0; i < n; ++i) v_true.row(i) << 0.1 * i / n, -0.02, 0.5;

  auto noise = [&](NoiseMode mode, const std::vector<int32_t>& object_ids, uint64_t seed) {
    Points v_prev = v_true, v = v_true;
    Rng rng(seed);
    add_velocity_noise(sigma, mode, object_ids, &v_prev, &v, &rng);
    return std::pair<Points, Points>(v_prev - v_true, v - v_true);
  };
  auto std_of = [](const Points& m) { return std::sqrt(m.squaredNorm() / m.size()); };

  const auto [point_prev, point_v] = noise(NoiseMode::kPoint, ids, 3);
  EXPECT_NEAR(std_of(point_prev), sigma / std::sqrt(2.0), 0.03 * sigma);
  EXPECT_NEAR(std_of(point_v), sigma, 0.03 * sigma);
  EXPECT_GT((point_v.row(0) - point_v.row(400)).norm(), 0.0);  // same object, own draws

  const auto [object_prev, object_v] = noise(NoiseMode::kObject, ids, 3);
  for (int i = 400; i < n; ++i) {
    ASSERT_LT((object_v.row(i) - object_v.row(i % 400)).norm(), 1e-15) << i;
    ASSERT_LT((object_prev.row(i) - object_prev.row(i % 400)).norm(), 1e-15) << i;
  }
  const Points per_object_v = object_v.topRows(400), per_object_prev = object_prev.topRows(400);
  EXPECT_NEAR(std_of(per_object_prev), sigma / std::sqrt(2.0), 0.1 * sigma);
  EXPECT_NEAR(std_of(per_object_v), sigma, 0.1 * sigma);
  // v's noise is v_prev's plus an independent increment of the same std.
  EXPECT_NEAR(std_of(per_object_v - per_object_prev), sigma / std::sqrt(2.0), 0.1 * sigma);

  // Reversing the points reverses the noise: each object keeps its draw.
  std::vector<int32_t> reversed(ids.rbegin(), ids.rend());
  const auto [reversed_prev, reversed_v] = noise(NoiseMode::kObject, reversed, 3);
  EXPECT_LT((reversed_v.row(n - 1) - object_v.row(0)).norm(), 1e-15);

  // Centred: per-point draws (10 points per object) whose mean over each object is zero.
  const auto [centred_prev, centred_v] = noise(NoiseMode::kCentred, ids, 3);
  for (int object = 0; object < 400; ++object) {
    Vec3 sum_prev = Vec3::Zero(), sum_v = Vec3::Zero();
    for (int i = object; i < n; i += 400) {
      sum_prev += centred_prev.row(i).transpose();
      sum_v += centred_v.row(i).transpose();
    }
    ASSERT_LT(sum_prev.norm() + sum_v.norm(), 1e-13) << object;
  }
  EXPECT_NEAR(std_of(centred_v), sigma * std::sqrt(0.9), 0.03 * sigma);
  EXPECT_GT((centred_v.row(0) - centred_v.row(400)).norm(), 0.0);
  EXPECT_EQ(parse_noise_mode("centred"), NoiseMode::kCentred);
  EXPECT_THROW(parse_noise_mode("scene"), ValueError);

  Points short_v(3, 3);
  Points short_prev(3, 3);
  Rng rng(1);
  EXPECT_THROW(add_velocity_noise(sigma, NoiseMode::kObject, ids, &short_prev, &short_v, &rng),
               ValueError);
}

TEST(TrainOptionsTest, RecipeRoundTripAndDefaultsByScale) {
  TrainOptions o = tiny_options("x.pt");
  o.model.kind = ModelKind::kGnn;
  o.noise_std = 0.002;
  o.pushforward_steps = 2;
  o.data_dirs.push_back("other");
  o.description = "a test recipe";
  o.datasets = {{"data/drop", "drop", 10, 5, 0.0},
                {"other", "collide", 20, 6, 60.0, 14, true, "sparse"}};
  o.notes_json = R"({"wall_time_s":12.5,"final":{"loss":0.1}})";
  const TrainOptions back = TrainOptions::from_json(o.to_json(), "recipe.json");
  EXPECT_EQ(back.to_json(), o.to_json());
  EXPECT_EQ(back.data_dirs, o.data_dirs);
  EXPECT_EQ(back.pushforward_steps, 2);
  ASSERT_EQ(back.datasets.size(), 2u);
  EXPECT_EQ(back.datasets[1].scenario, "collide");
  EXPECT_EQ(back.datasets[1].count, 20);
  EXPECT_EQ(back.datasets[1].seed, 6u);
  EXPECT_EQ(back.datasets[1].frame_rate_hz, 60.0);
  EXPECT_EQ(back.datasets[0].frame_rate_hz, 0.0) << "the scenario's own rate";
  EXPECT_EQ(back.datasets[1].hide_outcome_frames, 14);
  EXPECT_TRUE(back.datasets[1].balance);
  EXPECT_EQ(back.datasets[0].hide_outcome_frames, 0);
  EXPECT_FALSE(back.datasets[0].balance);
  EXPECT_EQ(back.datasets[1].mesh_density, "sparse");
  EXPECT_EQ(back.datasets[0].mesh_density, "dense");
  EXPECT_EQ(o.to_json().find("mesh_density"), o.to_json().rfind("mesh_density"))
      << "written only where it is not the default";
  EXPECT_EQ(o.to_json().find("hide_outcome_frames"), o.to_json().rfind("hide_outcome_frames"))
      << "written only where scenes are selected";
  EXPECT_EQ(o.to_json().find("frame_rate_hz"), o.to_json().rfind("frame_rate_hz"))
      << "written only where it is not the scenario's own";
  EXPECT_EQ(TrainOptions::from_json(R"({"data":"one"})", "r.json").data_dirs,
            std::vector<std::string>{"one"});
  TrainOptions k = back;
  k.resolve("movi-a");
  EXPECT_EQ(k.scale, "kubric");
  EXPECT_DOUBLE_EQ(k.lr, 5e-3);
  EXPECT_EQ(k.epochs, 15);
  EXPECT_EQ(k.samples_per_scene, 2);
  EXPECT_DOUBLE_EQ(k.model.voxel, 0.3);
  EXPECT_DOUBLE_EQ(k.model.interaction_threshold, 0.4) << "threshold follows the scale preset";
  TrainOptions p = back;
  p.resolve("drop");
  EXPECT_DOUBLE_EQ(p.lr, 1e-3);
  EXPECT_EQ(p.samples_per_scene, 8);
  try {
    TrainOptions::from_json(R"({"epochs":"many"})", "r.json");
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_EQ(e.field(), "epochs");
  }
  try {
    TrainOptions::from_json(R"({"datasets":[{"scenario":"drop"}]})", "r.json");
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_EQ(e.field(), "datasets");
  }
}

}  // namespace
}  // namespace dynscope
