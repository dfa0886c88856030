// A fake model for the viewer tests: constant-velocity rollouts and a hand-made trace, with
// calls that can be held to provoke races between jobs and the UI.
#pragma once

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>

#include "app/viewer/model_services.h"
#include "engine/core/error.h"
#include "engine/geometry/neighbors.h"
#include "engine/geometry/point_cloud.h"
#include "engine/model/model_config.h"
#include "engine/rollout/explain_report.h"
#include "engine/rollout/model_points.h"
#include "engine/rollout/rollout_runner.h"

namespace dynscope::app::viewer::testing {

// A constant-velocity rollout of `scene` (torch-free), observed for 3 frames.
inline Rollout cv_rollout(const Scene& scene, const std::string& scene_path) {
  SamplingOptions sampling;
  sampling.voxel = 0.1;
  const ModelPoints points = build_model_points(scene, sampling);
  RolloutOptions options;
  options.observed_frames = 3;
  options.floor_clamp = true;
  Rollout r = run_rollout(scene, points, constant_velocity_predictor(9.81, scene.dt_s), options);
  r.scene_path = scene_path;
  r.sampling_voxel = points.voxel;
  return r;
}

// A model that rolls out with constant velocity and traces a hand-made hierarchy: level 0 is a
// point cloud of the frame with kNN lists, and the picked point's filter weights are
// |h_k| = k + 1 over the same-object list. rollout() and trace() can be held until release()
// (or until their job is cancelled, which they notice as the engine's model does).
class FakeModel : public ModelServices {
 public:
  struct Loaded : LoadedCheckpoint {
    std::string path;
  };
  std::shared_ptr<LoadedCheckpoint> load(const std::string& checkpoint) override {
    ++loads_;
    auto m = std::make_shared<Loaded>();
    m->path = checkpoint;
    return m;
  }
  Rollout rollout(LoadedCheckpoint& model, const RolloutRequest& request,
                  JobControl& control) override {
    EXPECT_EQ(static_cast<Loaded&>(model).path, request.checkpoint);
    wait_while_held(control, rollouts_started_);
    Rollout r = cv_rollout(request.scene, request.scene_path);
    if (control.progress()) control.progress()->advance(r.num_frames() - r.observed_frames);
    r.checkpoint_path = request.checkpoint;
    return r;
  }
  ModelTrace trace(LoadedCheckpoint& model, const TraceRequest& request,
                   JobControl& control) override {
    EXPECT_EQ(static_cast<Loaded&>(model).path, request.checkpoint);
    wait_while_held(control, traces_started_);
    ++traces_;
    const Scene& scene = *request.scene;
    const int frame = request.frame, level = request.level, picked = request.picked;
    PointCloudOptions options;
    options.voxel = 0.1;
    const ScenePointCloud cloud = build_point_cloud(scene, options);
    ModelTrace t;
    t.scene_path = request.scene_path;
    t.checkpoint_path = request.checkpoint;
    t.frame = frame;
    TraceLevel l;
    l.points = cloud.positions(scene, frame);
    l.object_ids = cloud.object_id;
    t.model_config = ModelConfig::preset("physion").to_json();
    if (request.rollout) {  // the rollout's own prediction, as the engine's model reads it
      t.source = kTraceSourceRollout;
      t.rollout_path = request.rollout_path;
      l.points = request.rollout->predicted[static_cast<size_t>(frame)];
      l.object_ids = request.rollout->object_ids;
    }
    l.radius = 0.2;
    const NeighborList same = knn_same_object(l.points, l.object_ids, l.points, l.object_ids, kK);
    const NeighborList rel =
        knn_other_objects(l.points, l.object_ids, l.points, l.object_ids, kK, l.radius);
    l.lists.push_back({"same", 0, 0, same.index, same.mask});
    l.lists.push_back({"relational", 0, 0, rel.index, rel.mask});
    t.levels.push_back(l);
    if (level != 0) throw ValueError("level", "the fake model has one level");
    if (picked >= 0) {
      TraceQuery q;
      q.point = picked;
      q.conv = "unet.stem.0.object.conv";
      q.list = "0/same";
      q.query_index = picked;
      for (int k = 0; k < kK; ++k) {
        q.neighbors.push_back(same.index(picked, k));
        q.mask.push_back(same.mask(picked, k));
      }
      q.weights = Eigen::MatrixXd::Zero(kK, 2);
      for (int k = 0; k < kK; ++k) q.weights(k, 0) = k + 1.0;
      t.queries.push_back(q);
    }
    TraceFeatures f;
    f.block = "input";
    f.norms.assign(static_cast<size_t>(l.points.rows()), 1.5);
    t.features.push_back(f);
    return t;
  }
  // The divergence as the engine finds it (torch-free) and a hand-made attribution of the
  // resolved question: 60 % to its own object's kNN, 40 % to the first other object's relational
  // edges, spread evenly over each object's points.
  RolloutExplanation explain(LoadedCheckpoint& model, const ExplainJobRequest& request,
                             JobControl& control) override {
    EXPECT_EQ(static_cast<Loaded&>(model).path, request.checkpoint);
    wait_while_held(control, explains_started_);
    ++explains_;
    const Rollout& r = *request.rollout;
    RolloutExplanation out;
    out.divergence = find_divergence(r, ModelConfig::preset("physion"));
    const ExplainSelection s = resolve_selection(r, out.divergence, request.frame, request.object,
                                                 request.point, request.target, "frame");
    Explanation& e = out.explanation;
    e.frame = s.frame;
    e.target = s.target;
    e.point = s.point;
    for (int i = 0; i < r.num_points(); ++i) {
      const int32_t id = r.object_ids[static_cast<size_t>(i)];
      if (s.point >= 0 ? i == s.point : id == s.object) e.points.push_back(i);
    }
    if (e.points.empty()) throw ValueError("object", "no points");
    e.object = r.object_ids[static_cast<size_t>(e.points.front())];
    e.error = mean_error_of(r, e.points, e.frame + 1);
    e.error_growth = e.error - mean_error_of(r, e.points, e.frame);
    e.value = e.error;
    int32_t other = e.object;
    for (int32_t id : r.object_ids) {
      if (id != e.object) {
        other = id;
        break;
      }
    }
    e.point_shares.assign(static_cast<size_t>(r.num_points()), 0.0);
    auto add = [&](const char* list, int32_t object, double share) {
      Contributor c;
      c.list = list;
      c.object = object;
      c.share = share;
      c.magnitude = share;
      c.effect = share;
      std::vector<int> points;
      for (int i = 0; i < r.num_points(); ++i) {
        if (r.object_ids[static_cast<size_t>(i)] == object) points.push_back(i);
      }
      c.edges = static_cast<int>(points.size());
      for (int i : points) {
        c.points.push_back(i);
        c.point_shares.push_back(share / static_cast<double>(points.size()));
        e.point_shares[static_cast<size_t>(i)] += c.point_shares.back();
      }
      e.contributors.push_back(c);
    };
    add("same", e.object, other == e.object ? 1.0 : 0.6);
    if (other != e.object) add("relational", other, 0.4);
    e.edge_total = 1.0;
    return out;
  }
  void hold() {
    std::lock_guard<std::mutex> lock(mutex_);
    hold_ = true;
  }
  void release() {
    std::lock_guard<std::mutex> lock(mutex_);
    hold_ = false;
    released_.notify_all();
  }
  void wait_started(int n) { wait_for(rollouts_started_, n); }
  void wait_traces_started(int n) { wait_for(traces_started_, n); }
  void wait_explains_started(int n) { wait_for(explains_started_, n); }
  std::atomic<int> explains_{0};
  int cancelled_calls() const { return cancelled_; }
  int loads() const { return loads_; }
  static constexpr int kK = 6;
  std::atomic<int> traces_{0};

 private:
  void wait_while_held(JobControl& control, int& started) {
    std::unique_lock<std::mutex> lock(mutex_);
    ++started;
    started_.notify_all();
    while (hold_) {
      if (control.cancelled()) {
        ++cancelled_;
        throw JobCancelled();
      }
      released_.wait_for(lock, std::chrono::milliseconds(5));
    }
  }
  void wait_for(int& counter, int n) {
    std::unique_lock<std::mutex> lock(mutex_);
    started_.wait(lock, [&] { return counter >= n; });
  }
  std::mutex mutex_;
  std::condition_variable released_, started_;
  bool hold_ = false;
  int rollouts_started_ = 0;
  int traces_started_ = 0;
  int explains_started_ = 0;
  std::atomic<int> cancelled_{0};
  std::atomic<int> loads_{0};
};

}  // namespace dynscope::app::viewer::testing
