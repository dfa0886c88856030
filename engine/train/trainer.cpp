// Training loop (LibTorch inside).
#include "engine/train/trainer.h"

#include <c10/util/Exception.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <numeric>
#include <utility>

#include "engine/core/error.h"
#include "engine/core/log.h"
#include "engine/core/prefetch_thread.h"
#include "engine/core/progress.h"
#include "engine/core/rng.h"
#include "engine/io/scene_file.h"
#include "engine/io/temp_file.h"
#include "engine/model/checkpoint.h"
#include "engine/model/torch_runtime.h"
#include "engine/rollout/dataset_split.h"
#include "engine/rollout/model_predictor.h"
#include "engine/rollout/pose_fitting.h"
#include "engine/rollout/rollout_runner.h"
#include "engine/train/adam_step.h"
#include "engine/train/point_loss.h"
#include "engine/train/process_group_torch.h"
#include "engine/train/train_state.h"

namespace dynscope {

namespace {

// Seed streams: one per purpose so that none shifts another.
constexpr uint64_t kOrderStream = 0x6f72646572ULL;
constexpr uint64_t kStepStream = 0x73746570ULL;
// At most this many frames per scene feed the normalisation statistics.
constexpr int kStatsFramesPerScene = 16;

// One scene with its model points and every frame's positions.
struct SceneData {
  std::string path;
  Scene scene;
  ModelPoints points;
  std::vector<Points> frames;
  std::vector<uint8_t> static_points;         // ScenePointCloud::static_mask
  int64_t moving_points = 0;                  // points not in static_points
  std::unique_ptr<RigidProjector> projector;  // the rigid projection of the scene's rollouts

  // The points a model's loss counts in this scene: the moving ones where it holds static bodies.
  int64_t loss_points(const ModelConfig& c) const {
    return c.hold_static ? moving_points : points.size();
  }
};

SceneData load_scene(const std::string& path, const SamplingOptions& sampling) {
  SceneData d;
  d.path = path;
  d.scene = read_scene(path);
  if (d.scene.num_frames() < 4) {
    throw ValueError(
        path, "has " + std::to_string(d.scene.num_frames()) + " frames; training needs at least 4");
  }
  d.points = build_model_points(d.scene, sampling);
  for (int f = 0; f < d.scene.num_frames(); ++f) d.frames.push_back(d.points.positions(d.scene, f));
  d.static_points = d.points.cloud.static_mask(d.scene);
  for (const uint8_t s : d.static_points) d.moving_points += s == 0 ? 1 : 0;
  d.projector = std::make_unique<RigidProjector>(d.points.cloud, d.scene);
  return d;
}

// One training example: noisy state at t and the true p(t+1).
struct Example {
  PointState state;
  Points next;
  const SceneData* scene = nullptr;
  int frame = 0;  // t
  int push = 0;   // frames the model still pushes it forward before the loss
};

Example make_example(const SceneData& d, int t, const TrainOptions& o, Rng* rng) {
  Example e;
  e.scene = &d;
  e.frame = t;
  const Points& p2 = d.frames[static_cast<size_t>(t - 2)];
  const Points& p1 = d.frames[static_cast<size_t>(t - 1)];
  const Points& p0 = d.frames[static_cast<size_t>(t)];
  Points v_prev = p1 - p2;
  Points v = p0 - p1;
  Points pos = p0;
  if (rng != nullptr && o.noise_std > 0) {
    add_velocity_noise(o.noise_std, parse_noise_mode(o.noise_mode), d.points.cloud.object_id,
                       &v_prev, &v, rng);
    pos = p2 + v_prev + v;  // positions follow the noisy velocities
  }
  e.state.position = pos;
  e.state.velocity = v;
  e.state.prev_velocity = v_prev;
  e.state.object_ids = d.points.cloud.object_id;
  e.state.faces = d.points.faces;
  e.state.static_points = d.static_points;
  e.next = d.frames[static_cast<size_t>(t + 1)];
  return e;
}

// A batch ready for the network: its examples' inputs concatenated into one, their true p(t+1).
struct PreparedBatch {
  ModelInput input;
  torch::Tensor truth;  // float64 [P,3]
  // float32 [P,1], 0 for the static points of a model that holds them; else undefined.
  torch::Tensor moving;
  int64_t points = 0;
  int64_t global_points = 0;      // points of the whole step over all ranks (normalises the loss)
  bool empty = false;             // this rank has no example in the step (end of an epoch)
  std::vector<Example> examples;  // kept for pushing forward (TrainOptions::pushforward_steps)
};

// Builds every example's hierarchy and tensors. Reads only the model's configuration, so it may
// run on another thread while the model trains.
PreparedBatch prepare_batch(const DynamicsModelImpl& model, const std::vector<Example>& examples) {
  const bool hold_static = model.config().hold_static;
  std::vector<ModelInput> inputs;
  std::vector<torch::Tensor> truths;
  std::vector<float> moving;
  PreparedBatch b;
  for (const Example& e : examples) {
    inputs.push_back(make_model_input(e.state, model.build_hierarchy(e.state)));
    truths.push_back(points_to_tensor(e.next));
    b.points += e.state.size();
    if (!hold_static) continue;
    for (Eigen::Index i = 0; i < e.state.size(); ++i) {
      moving.push_back(e.state.static_points.empty() ||
                               e.state.static_points[static_cast<size_t>(i)] == 0
                           ? 1.0f
                           : 0.0f);
    }
  }
  b.input = concatenate_inputs(inputs);
  b.truth = torch::cat(truths);
  if (hold_static) {
    b.moving =
        torch::from_blob(moving.data(), {static_cast<int64_t>(moving.size()), 1}, torch::kFloat)
            .clone();
  }
  return b;
}

// Sum over points and components of the Huber loss in target-std units, one forward pass for the
// whole batch; held static points (ModelConfig::hold_static) add nothing.
torch::Tensor batch_loss(DynamicsModel& model, const PreparedBatch& b, double delta) {
  return point_loss_sum(model->predict_positions(b.input), b.truth, model->stats().target_std,
                        delta, b.moving);
}

// Replaces every example of `b` that is still to be pushed (Example::push) by the state the model
// itself reaches from it one step later, as a rollout does (the prediction without gradient, held
// static points, rigid projection), with the true positions of that later frame as its target;
// then prepares the batch again.
void push_forward(DynamicsModel& model, PreparedBatch& b) {
  torch::Tensor delta;
  {
    torch::NoGradGuard no_grad;
    delta = model->predict_delta(b.input);
    if (b.moving.defined()) delta = delta * b.moving;  // held static points stay put
    delta = delta.to(torch::kCPU, torch::kDouble).contiguous();
  }
  Eigen::Index offset = 0;
  for (Example& e : b.examples) {
    const Eigen::Index n = e.state.size();
    const double* d = delta.data_ptr<double>() + 3 * offset;
    offset += n;
    if (e.push == 0) continue;
    --e.push;
    const Points raw = e.state.position + Eigen::Map<const Points>(d, n, 3);
    Points reached = e.scene->projector->project(raw);
    e.state.prev_velocity = std::move(e.state.velocity);
    e.state.velocity = reached - e.state.position;
    e.state.position = std::move(reached);
    ++e.frame;
    e.next = e.scene->frames[static_cast<size_t>(e.frame + 1)];
  }
  const int64_t global_points = b.global_points;
  std::vector<Example> examples = std::move(b.examples);
  b = prepare_batch(*model, examples);
  b.global_points = global_points;
  b.examples = std::move(examples);
}

NormStats compute_stats(const std::vector<SceneData>& scenes, TargetMode target) {
  NormStatsAccumulator acc(target);
  for (const SceneData& d : scenes) {
    const int frames = static_cast<int>(d.frames.size());
    const int stride = std::max(1, (frames - 2) / kStatsFramesPerScene);
    for (int t = 1; t + 1 < frames; t += stride) {
      acc.add(d.frames[static_cast<size_t>(t - 1)], d.frames[static_cast<size_t>(t)],
              d.frames[static_cast<size_t>(t + 1)]);
    }
  }
  return acc.finish(1e-6);
}

// FNV-1a over the bytes of every parameter and buffer, in module order.
uint64_t parameter_digest(DynamicsModel& model) {
  uint64_t h = 1469598103934665603ULL;
  auto add = [&h](const torch::Tensor& t) {
    const torch::Tensor c = t.detach().contiguous();
    const auto* p = static_cast<const unsigned char*>(c.data_ptr());
    for (size_t i = 0; i < c.nbytes(); ++i) h = (h ^ p[i]) * 1099511628211ULL;
  };
  for (const torch::Tensor& t : model->parameters()) add(t);
  for (const torch::Tensor& t : model->buffers()) add(t);
  return h;
}

struct CsvLog {
  std::ofstream out;
  CsvLog(const std::string& path, bool append) {
    if (path.empty()) return;
    const bool exists = std::filesystem::exists(path);
    out.open(path, append ? std::ios::app : std::ios::trunc);
    if (!out) throw IoError(path, "cannot open log for writing");
    if (!append || !exists) out << "step,epoch,loss,val_loss,val_rollout_error,seconds\n";
  }
  void row(int64_t step, int epoch, double loss, double val_loss, double val_err, double s) {
    if (!out.is_open()) return;
    char line[200];
    std::snprintf(line, sizeof line, "%lld,%d,%.8g,%s,%s,%.3f\n", static_cast<long long>(step),
                  epoch, loss, std::isnan(val_loss) ? "" : std::to_string(val_loss).c_str(),
                  std::isnan(val_err) ? "" : std::to_string(val_err).c_str(), s);
    out << line;
    out.flush();
  }
};

TrainResult run(TrainOptions o, bool show_progress, ProcessGroup* group) {
  if (o.data_dirs.empty()) throw ValueError("data", "no dataset directory given");
  const int world = group ? group->world_size() : 1;
  const int rank = group ? group->rank() : 0;
  const bool leader = rank == 0;
  std::vector<DatasetSplit> train_splits, val_splits;
  for (const std::string& dir : o.data_dirs) {
    train_splits.push_back(read_dataset_split(dir, "train"));
    val_splits.push_back(read_dataset_split(dir, "val"));
    if (train_splits.back().items.empty()) {
      throw ValueError("data", dir + " has no training scenes");
    }
    const std::string& first = train_splits.front().scenario;
    const std::string& scenario = train_splits.back().scenario;
    if (default_scale_preset(scenario) != default_scale_preset(first) ||
        default_sampling_voxel(scenario) != default_sampling_voxel(first)) {
      throw ValueError("data", "cannot train on " + first + " and " + scenario +
                                   " together: their scenes have different scales");
    }
  }
  o.world_size = world;
  o.resolve(train_splits.front().scenario);
  set_torch_threads(o.threads);

  std::vector<SceneData> train, val;
  for (const DatasetSplit& split : train_splits) {
    for (const DatasetItem& item : split.items) train.push_back(load_scene(item.path, o.sampling));
  }
  // Validation scenes are taken round-robin over the datasets so each scenario is represented.
  // Rank 0 alone validates, so only it reads them.
  for (size_t i = 0; leader && static_cast<int>(val.size()) < o.val_scenes; ++i) {
    bool any = false;
    for (const DatasetSplit& split : val_splits) {
      if (i >= split.items.size() || static_cast<int>(val.size()) >= o.val_scenes) continue;
      val.push_back(load_scene(split.items[i].path, o.sampling));
      any = true;
    }
    if (!any) break;
  }
  for (const SceneData& d : train) {
    if (static_cast<int>(d.frames.size()) < 4 + o.pushforward_steps) {
      throw ValueError("pushforward-steps",
                       d.path + " has " + std::to_string(d.frames.size()) + " frames; pushing " +
                           std::to_string(o.pushforward_steps) + " forward needs at least " +
                           std::to_string(4 + o.pushforward_steps));
    }
  }
  if (val.empty() && leader) {
    log_warn(o.data_dirs.front(),
             ": the validation split is empty (or --val-scenes 0); validation is skipped");
  }

  // Initialisation draws from LibTorch's one global generator: ranks that share a process (the
  // tests run two as threads) must not interleave their draws, or rank 0's weights would depend
  // on timing.
  static std::mutex init_mutex;
  std::unique_lock<std::mutex> init_lock(init_mutex);
  torch::manual_seed(o.init_seed.value_or(o.seed));
  DynamicsModel model(o.model);
  init_lock.unlock();
  const std::string config_json = model->config().to_json();
  torch::optim::Adam optimizer(model->parameters(), torch::optim::AdamOptions(o.lr));
  RunProgress done;
  if (o.resume) {
    load_checkpoint_weights(o.out, model);
    done = load_train_state(train_state_path(o.out), optimizer, config_json, world);
  } else if (leader) {
    model->set_stats(compute_stats(train, o.model.target));
  }
  if (group) {
    // One model on every rank: rank 0's parameters and statistics (buffers).
    std::vector<torch::Tensor> state = model->parameters();
    for (const torch::Tensor& b : model->buffers()) state.push_back(b);
    broadcast_tensors(*group, state, "the initial parameters");
  }

  const auto n_train = static_cast<int64_t>(train.size());
  const int64_t draws = n_train * o.samples_per_scene;
  const int64_t global_batch = static_cast<int64_t>(o.batch) * world;
  const int64_t steps_per_epoch = (draws + global_batch - 1) / global_batch;
  // The learning-rate schedule spans every epoch; max_steps only ends a run (or a chunk) early.
  const int64_t schedule_steps = steps_per_epoch * o.epochs;
  int64_t total = schedule_steps;
  if (o.max_steps > 0) total = std::min(total, o.max_steps);

  int64_t step = done.step;
  ++done.chunks;
  TrainResult result;
  result.start_step = step;
  result.steps_per_epoch = steps_per_epoch;
  result.world_size = world;
  CsvLog log(leader ? o.log_csv : std::string(), o.resume);
  const auto t0 = std::chrono::steady_clock::now();
  const double wall_before = done.wall_seconds;
  // The recipe beside a checkpoint records what the run has done so far, over every chunk.
  auto write_recipe = [&](const std::string& checkpoint) {
    TrainOptions recorded = o;
    recorded.progress_json = progress_record(done, step, schedule_steps, steps_per_epoch);
    write_text_file_atomically(recipe_path(checkpoint), recorded.to_json());
  };
  // A new run's recipe is there from the start; a resumed run's already says what it has done,
  // and is rewritten at its next save (a sitting stopped before it then counts for nothing).
  if (leader && !o.resume) write_recipe(o.out);
  std::unique_ptr<Progress> progress;
  if (show_progress && leader) progress = std::make_unique<Progress>("train", total - step);
  auto seconds = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };

  // The per-epoch shuffle of the draws: each training scene samples_per_scene times.
  auto epoch_order = [&](int64_t epoch) {
    std::vector<int64_t> order(static_cast<size_t>(draws));
    for (int64_t i = 0; i < draws; ++i) order[static_cast<size_t>(i)] = i % n_train;
    Rng shuffle(derive_seed(o.seed ^ kOrderStream, static_cast<uint64_t>(epoch)));
    for (int64_t i = draws - 1; i > 0; --i) {
      std::swap(order[static_cast<size_t>(i)],
                order[static_cast<size_t>(shuffle.uniform_int(0, i))]);
    }
    return order;
  };
  // The examples of step s: its slice of the epoch order, each with a random frame and noise, all
  // from seeds of (seed, epoch, s), so a resumed run draws exactly what an uninterrupted one does.
  // Data-parallel: the step's batch × W examples are drawn in one sequence (as one process with
  // that batch would) and rank r keeps the r-th batch of them.
  auto step_batch = [&train, &model, o, steps_per_epoch, draws, global_batch, rank](
                        int64_t s, std::shared_ptr<const std::vector<int64_t>> order) {
    Rng rng(derive_seed(o.seed ^ kStepStream, static_cast<uint64_t>(s)));
    const int64_t first = (s % steps_per_epoch) * global_batch;
    const int64_t mine = first + static_cast<int64_t>(rank) * o.batch;
    std::vector<Example> examples;
    int64_t global_points = 0;
    for (int64_t b = first; b < std::min(first + global_batch, draws); ++b) {
      const SceneData& d = train[static_cast<size_t>((*order)[static_cast<size_t>(b)])];
      global_points += d.loss_points(model->config());
      if (b >= mine + o.batch) continue;  // later ranks' examples: nothing more to draw for them
      // With pushing forward, the drawn frame is where the loss is taken; the example starts a
      // number of frames earlier drawn from 0 to pushforward_steps, and the model pushes it on.
      const int t = static_cast<int>(
          rng.uniform_int(2 + o.pushforward_steps, static_cast<int64_t>(d.frames.size()) - 2));
      const int push =
          o.pushforward_steps > 0 ? static_cast<int>(rng.uniform_int(0, o.pushforward_steps)) : 0;
      Example e = make_example(d, t - push, o, &rng);
      e.push = push;
      if (b >= mine) examples.push_back(std::move(e));
    }
    PreparedBatch batch;
    if (examples.empty()) {
      batch.empty = true;
    } else {
      batch = prepare_batch(*model, examples);
      if (o.pushforward_steps > 0) batch.examples = std::move(examples);
    }
    batch.global_points = global_points;
    return batch;
  };
  std::shared_ptr<const std::vector<int64_t>> order;
  int64_t order_epoch = -1;
  auto order_for = [&](int64_t s) {
    const int64_t epoch = s / steps_per_epoch;
    if (epoch != order_epoch) {
      order = std::make_shared<const std::vector<int64_t>>(epoch_order(epoch));
      order_epoch = epoch;
    }
    return order;
  };
  double epoch_loss = 0.0;
  int64_t epoch_steps = 0;
  auto save = [&] {
    if (!leader) return;
    done.step = step;
    done.wall_seconds = wall_before + seconds();
    save_checkpoint(o.out, model);
    save_train_state(train_state_path(o.out), optimizer, done, config_json, world);
    write_recipe(o.out);
  };
  const std::vector<torch::Tensor> parameters = model->parameters();

  // The next batch is prepared on a thread of its own while the current step runs on this one.
  PrefetchThread<PreparedBatch> prefetch;
  if (step < total) {
    prefetch.start([&step_batch, s = step, ord = order_for(step)] { return step_batch(s, ord); });
  }
  while (step < total) {
    PreparedBatch batch = prefetch.take();
    if (step + 1 < total) {
      prefetch.start(
          [&step_batch, s = step + 1, ord = order_for(step + 1)] { return step_batch(s, ord); });
    }
    model->train();
    optimizer.zero_grad();
    const auto step_start = std::chrono::steady_clock::now();
    auto pushing = [&batch] {
      return std::any_of(batch.examples.begin(), batch.examples.end(),
                         [](const Example& e) { return e.push > 0; });
    };
    while (pushing()) push_forward(model, batch);
    // Normalised by the points of the whole step (all ranks), so summed gradients are the mean.
    torch::Tensor loss =
        batch.empty ? torch::zeros({}, torch::kFloat)
                    : batch_loss(model, batch, o.huber_delta) /
                          static_cast<double>(std::max<int64_t>(batch.global_points, 1) * 3);
    if (!batch.empty) loss.backward();
    double value = loss.item<double>();
    if (group) {
      std::vector<torch::Tensor> grads;
      for (const torch::Tensor& p : parameters) {
        if (!p.grad().defined()) p.mutable_grad() = torch::zeros_like(p);
        grads.push_back(p.grad());
      }
      const torch::Tensor total_loss = torch::full({1}, value, torch::kDouble);
      grads.push_back(total_loss);
      const auto t_reduce = std::chrono::steady_clock::now();
      allreduce_sum(*group, grads, "the gradients");
      result.allreduce_seconds +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t_reduce).count();
      value = total_loss.item<double>();
    }
    const double lr = learning_rate_at(o, step, schedule_steps);
    for (torch::optim::OptimizerParamGroup& g : optimizer.param_groups()) {
      static_cast<torch::optim::AdamOptions&>(g.options()).lr(lr);
    }
    adam_step(optimizer);
    result.train_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - step_start).count();
    ++step;
    result.losses.push_back(value);
    if (!std::isfinite(value)) {
      throw Error("training diverged at step " + std::to_string(step) + " (loss " +
                  std::to_string(value) + "); lower --lr");
    }
    result.last_loss = value;
    epoch_loss += value;
    ++epoch_steps;
    double val_loss = std::numeric_limits<double>::quiet_NaN();
    double val_err = std::numeric_limits<double>::quiet_NaN();
    if (step % steps_per_epoch == 0 || step == total) {
      EpochReport rep;
      rep.epoch = static_cast<int>((step - 1) / steps_per_epoch);
      rep.step = step;
      rep.train_loss = epoch_loss / static_cast<double>(epoch_steps);
      rep.val_loss = val_loss;
      rep.val_rollout_error = val_err;
      if (!val.empty()) {
        model->eval();
        torch::NoGradGuard no_grad;
        double sum = 0.0, err = 0.0;
        int64_t n = 0;
        // One hierarchy cache across the validation rollouts: each scene re-anchors its objects.
        HierarchyCache cache;
        StepPredictor predict = [&model, &cache](const PointState& s) {
          return model->predict_next(s, &cache);
        };
        for (const SceneData& d : val) {
          const int t = static_cast<int>(d.frames.size()) / 2;
          const Example e = make_example(
              d, std::max(2, std::min(t, static_cast<int>(d.frames.size()) - 2)), o, nullptr);
          sum += batch_loss(model, prepare_batch(*model, {e}), o.huber_delta).item<double>();
          n += d.loss_points(model->config()) * 3;
          RolloutOptions ro;
          ro.observed_frames = 3;
          ro.frames = std::min(d.scene.num_frames(), std::max(o.val_frames, 4));
          err += run_rollout(d.scene, d.points, predict, ro).point_error.back();
        }
        val_loss = rep.val_loss = sum / static_cast<double>(std::max<int64_t>(n, 1));
        val_err = rep.val_rollout_error = err / static_cast<double>(val.size());
        // Model selection on the validation split: the best epoch so far is kept beside the
        // run's latest checkpoint. Only whole epochs compete, so where a sitting happens to end
        // cannot change which checkpoint is kept.
        if (leader && step % steps_per_epoch == 0 && val_err < done.best_val_error) {
          done.best_val_error = val_err;
          done.best_step = step;
          done.wall_seconds = wall_before + seconds();
          const std::string best = best_checkpoint_path(o.out);
          save_checkpoint(best, model);
          write_recipe(best);
        }
      }
      if (leader && o.keep_epochs && step % steps_per_epoch == 0) {
        const std::string kept = epoch_checkpoint_path(o.out, rep.epoch + 1);
        save_checkpoint(kept, model);
        write_recipe(kept);
      }
      result.epochs.push_back(rep);
      if (leader) {
        log_info("epoch ", rep.epoch + 1, " step ", step, ": train loss ", rep.train_loss,
                 ", val loss ", rep.val_loss, ", val rollout error ", rep.val_rollout_error);
      }
      epoch_loss = 0.0;
      epoch_steps = 0;
    }
    log.row(step, static_cast<int>((step - 1) / steps_per_epoch), value, val_loss, val_err,
            seconds());
    if (progress) {
      char status[96];
      std::snprintf(status, sizeof status, "loss %.4g", value);
      progress->set_status(status);
      progress->advance();
    }
    if (step % o.checkpoint_every == 0 || step == total) save();
  }
  if (result.start_step == step) save();
  if (progress) progress->finish();
  result.steps = step;
  result.wall_seconds = done.wall_seconds;
  result.chunks = done.chunks;
  result.best_step = done.best_step;
  result.parameter_digest = parameter_digest(model);
  if (group) {
    const std::vector<std::string> digests =
        group->gather_bytes("parameter digests", std::to_string(result.parameter_digest));
    for (size_t r = 1; r < digests.size(); ++r) {
      if (digests[r] != digests[0]) {
        throw Error("data-parallel ranks diverged: rank " + std::to_string(r) +
                    " ends with other parameters than rank 0");
      }
    }
    if (leader) {
      log_info("parameters identical on all ", world, " ranks (digest ", digests[0], ")");
    }
  }
  return result;
}

}  // namespace

TrainResult train_model(TrainOptions options, bool show_progress, ProcessGroup* group) {
  try {
    return run(std::move(options), show_progress, group);
  } catch (const c10::Error& e) {
    throw Error(std::string("training failed in LibTorch: ") + e.what_without_backtrace());
  }
}

}  // namespace dynscope
