// Tests of the viewer with rollouts and a fake model: display modes, error strip, uploads,
// trace-driven inspector, background rollouts (two checkpoints, what-if) and bad files.
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>

#include "app/viewer/initial_state_edit.h"
#include "app/viewer/model_services.h"
#include "app/viewer/rollout_document.h"
#include "engine/core/error.h"
#include "engine/geometry/neighbors.h"
#include "engine/io/rollout_file.h"
#include "engine/io/scene_file.h"
#include "engine/rollout/model_points.h"
#include "engine/rollout/rollout_runner.h"
#include "viewer_test_util.h"

namespace dynscope::app::viewer {
namespace {

namespace fs = std::filesystem;
using testing::HeadlessViewer;

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("dynscope_viewer_rollout_test_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// A constant-velocity rollout of `scene` (torch-free), observed for 3 frames.
Rollout cv_rollout(const Scene& scene, const std::string& scene_path) {
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

const Scene& collide() {
  static const Scene scene = read_scene(testing::collide_scene());
  return scene;
}

const Rollout& collide_rollout() {
  static const Rollout r = cv_rollout(collide(), testing::collide_scene());
  return r;
}

std::string collide_rollout_file() {
  static const std::string path = [] {
    const fs::path p = temp_dir("file") / "collide_rollout.h5";
    write_rollout(collide_rollout(), p.string());
    return p.string();
  }();
  return path;
}

// Frames until no background job runs (at most `limit`).
void settle_jobs(HeadlessViewer& v, std::chrono::seconds limit = std::chrono::seconds(20)) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (v.app.busy() && std::chrono::steady_clock::now() < end) {
    v.app.frame();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  v.app.frame();
}

// Point-layer names drawn in each viewport.
std::vector<std::vector<std::string>> layer_names(const ViewerApp& app) {
  std::vector<std::vector<std::string>> out;
  for (const Viewport& p : app.viewports()) {
    out.emplace_back();
    for (const render::PointLayer& l : p.scene.points) out.back().push_back(l.name);
  }
  return out;
}

// A model that rolls out with constant velocity and traces a hand-made hierarchy: level 0 is a
// point cloud of the frame with kNN lists, and the picked point's filter weights are
// |h_k| = k + 1 over the same-object list. rollout() can be held until release().
class FakeModel : public ModelServices {
 public:
  Rollout rollout(const RolloutRequest& request, Progress* progress) override {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      ++rollouts_started_;
      started_.notify_all();
      released_.wait(lock, [&] { return !hold_; });
    }
    Rollout r = cv_rollout(request.scene, request.scene_path);
    if (progress) progress->advance(r.num_frames() - r.observed_frames);
    r.checkpoint_path = request.checkpoint;
    return r;
  }
  ModelTrace trace(const std::string& checkpoint, const Scene& scene, const std::string& path,
                   int frame, int level, int picked) override {
    ++traces_;
    PointCloudOptions options;
    options.voxel = 0.1;
    const ScenePointCloud cloud = build_point_cloud(scene, options);
    ModelTrace t;
    t.scene_path = path;
    t.checkpoint_path = checkpoint;
    t.frame = frame;
    TraceLevel l;
    l.points = cloud.positions(scene, frame);
    l.object_ids = cloud.object_id;
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
  void hold() {
    std::lock_guard<std::mutex> lock(mutex_);
    hold_ = true;
  }
  void release() {
    std::lock_guard<std::mutex> lock(mutex_);
    hold_ = false;
    released_.notify_all();
  }
  void wait_started(int n) {
    std::unique_lock<std::mutex> lock(mutex_);
    started_.wait(lock, [&] { return rollouts_started_ >= n; });
  }
  static constexpr int kK = 6;
  std::atomic<int> traces_{0};

 private:
  std::mutex mutex_;
  std::condition_variable released_, started_;
  bool hold_ = false;
  int rollouts_started_ = 0;
};

TEST(ViewerRollout, ShowsFrameKsPredictedPointsAtFrameK) {
  HeadlessViewer v;
  v.app.open_file(collide_rollout_file());
  ASSERT_TRUE(v.app.has_rollout());
  EXPECT_TRUE(v.app.has_scene());  // the scene it names was opened too (meshes)
  v.app.set_rollout_mode(RolloutMode::kPrediction);
  const Rollout& r = collide_rollout();
  for (int k : {0, 17, r.num_frames() - 1}) {
    v.app.set_frame(k);
    v.app.frame();
    const std::vector<Viewport> ports = v.app.viewports();
    ASSERT_EQ(ports.size(), 1u);
    const render::PointLayer& layer = ports[0].scene.points.at(0);
    EXPECT_EQ(layer.name, "prediction");
    EXPECT_EQ(layer.frame, k);
    for (int i : {0, 5}) {
      EXPECT_NEAR((layer.series->position(k, i) - r.predicted[k].row(i).transpose()).norm(), 0.0,
                  1e-5);
    }
    EXPECT_FALSE(ports[0].scene.meshes.empty());
  }
  EXPECT_TRUE(v.app.last_error().empty()) << v.app.last_error();
}

TEST(ViewerRollout, ModesChangeTheLayersDrawn) {
  HeadlessViewer v;
  v.app.open_rollout(collide_rollout_file());
  v.app.set_frame(30);
  using Names = std::vector<std::vector<std::string>>;
  v.app.set_rollout_mode(RolloutMode::kPrediction);
  EXPECT_EQ(layer_names(v.app), (Names{{"prediction"}}));
  v.app.set_rollout_mode(RolloutMode::kTruth);
  EXPECT_EQ(layer_names(v.app), (Names{{"truth"}}));
  v.app.set_rollout_mode(RolloutMode::kGhost);
  EXPECT_EQ(layer_names(v.app), (Names{{"prediction", "truth (ghost)"}}));
  v.app.set_rollout_mode(RolloutMode::kSideBySide);
  EXPECT_EQ(layer_names(v.app), (Names{{"truth"}, {"prediction"}}));
  // Side by side: two viewports, the same camera shifted apart, both drawn into one image.
  const std::vector<Viewport> ports = v.app.viewports();
  EXPECT_EQ(ports[0].x1, ports[1].x0);
  EXPECT_EQ(ports[0].camera.yaw_deg, ports[1].camera.yaw_deg);
  EXPECT_EQ(ports[0].camera.distance, ports[1].camera.distance);
  v.app.set_ui_visible(false);
  v.app.frame();
  const render::Image split = v.app.read_pixels();
  v.app.set_rollout_mode(RolloutMode::kPrediction);
  v.app.frame();
  EXPECT_LT(render::compare_images(split, v.app.read_pixels(), 8).fraction_within, 0.99);
  // Error colours follow the range: manual range reaches the layer.
  v.app.set_rollout_mode(RolloutMode::kPrediction);
  render::ViewSpec view = v.app.current_view();
  view.auto_range = false;
  view.range_max = 0.25f;
  v.app.set_view(view);
  const render::PointLayer& p = v.app.viewports()[0].scene.points[0];
  EXPECT_EQ(p.coloring, render::PointColoring::kScalar);
  EXPECT_FLOAT_EQ(p.range_max, 0.25f);
}

TEST(ViewerRollout, ScrubbingAddsNoUploads) {
  HeadlessViewer v;
  v.app.open_rollout(collide_rollout_file());
  v.app.set_rollout_mode(RolloutMode::kSideBySide);
  v.app.frame();
  const int64_t uploads = v.app.upload_count();
  for (int k : {5, 20, 40, 59, 0}) {
    v.app.set_frame(k);
    v.app.frame();
  }
  v.app.set_rollout_mode(RolloutMode::kGhost);
  v.app.frame();
  EXPECT_EQ(v.app.upload_count(), uploads);
}

TEST(ViewerRollout, JumpToThresholdFindsTheFirstFrameOverIt) {
  HeadlessViewer v;
  v.app.open_rollout(collide_rollout_file());
  const std::vector<double>& e = collide_rollout().point_error;
  const double threshold = 0.5 * *std::max_element(e.begin(), e.end());
  const int expected = first_frame_over(e, threshold);
  ASSERT_GT(expected, 0);
  EXPECT_LE(e[expected - 1], threshold);
  v.app.set_error_threshold(threshold);
  EXPECT_EQ(v.app.jump_to_error_threshold(), expected);
  EXPECT_EQ(v.app.current_frame(), expected);
  v.app.set_frame(2);
  v.app.set_error_threshold(1e9);
  EXPECT_EQ(v.app.jump_to_error_threshold(), -1);
  EXPECT_EQ(v.app.current_frame(), 2);
  v.app.show_panel(Panel::kContacts);
  v.app.frame();
  v.app.frame();
  EXPECT_TRUE(v.app.last_error().empty()) << v.app.last_error();
}

TEST(ViewerRollout, BadRolloutFileGivesAnErrorPopup) {
  const fs::path dir = temp_dir("bad");
  HeadlessViewer v;
  v.app.open_scene(testing::collide_scene());
  v.app.frame();
  std::ofstream(dir / "broken.h5") << "not hdf5";
  try {
    v.app.open_rollout((dir / "broken.h5").string());
    FAIL() << "no error for a corrupt rollout";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("broken.h5"), std::string::npos) << e.what();
  }
  // A scene file is HDF5 but not a rollout.
  EXPECT_THROW(v.app.open_rollout(testing::collide_scene()), Error);
  // Opened from the Files section: the error becomes the popup, the scene stays, frames go on.
  v.app.request_open((dir / "broken.h5").string());
  EXPECT_NO_THROW(v.app.frame());
  EXPECT_NE(v.app.last_error().find("broken.h5"), std::string::npos) << v.app.last_error();
  EXPECT_NO_THROW(v.app.frame());
  EXPECT_TRUE(v.app.has_scene());
  EXPECT_FALSE(v.app.has_rollout());
  EXPECT_EQ(v.app.document().path, testing::collide_scene());
}

TEST(ViewerRollout, TraceDrivesTheInspector) {
  FakeModel model;
  HeadlessViewer v(&model);
  ViewerApp& app = v.app;
  app.open_scene(testing::collide_scene());
  app.set_checkpoint("fake.pt");
  app.set_frame(12);
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while ((app.busy() || !app.shown_trace()) && std::chrono::steady_clock::now() < end) app.frame();
  ASSERT_NE(app.shown_trace(), nullptr);
  EXPECT_EQ(app.shown_trace()->frame, 12);
  app.select_point(7);
  while ((app.busy() || app.shown_trace()->queries.empty()) &&
         std::chrono::steady_clock::now() < end) {
    app.frame();
  }
  ASSERT_FALSE(app.shown_trace()->queries.empty());
  const Neighborhood n = point_neighborhood(*app.active_data(), 7, 12, 16);
  EXPECT_EQ(n.k, FakeModel::kK);
  EXPECT_EQ(n.object_conv, "unet.stem.0.object.conv");
  const TraceList& same = app.shown_trace()->levels[0].lists[0];
  ASSERT_FALSE(n.object.empty());
  // The listed neighbours are the trace's, each with its |h| (k + 1 for list column k).
  int listed = 0;
  for (int k = 0; k < FakeModel::kK; ++k) {
    if (!same.mask(7, k) || same.index(7, k) == 7) continue;
    EXPECT_EQ(n.object[static_cast<size_t>(listed)].point, same.index(7, k));
    EXPECT_DOUBLE_EQ(n.object[static_cast<size_t>(listed)].weight, k + 1.0);
    ++listed;
  }
  EXPECT_EQ(listed, static_cast<int>(n.object.size()));
  app.show_panel(Panel::kInspector);
  app.show_panel(Panel::kLevels);
  app.frame();
  app.frame();
  EXPECT_TRUE(app.last_error().empty()) << app.last_error();
}

TEST(ViewerRollout, WhatIfRunsInTheBackground) {
  FakeModel model;
  HeadlessViewer v(&model);
  ViewerApp& app = v.app;
  app.open_scene(testing::collide_scene());
  app.set_checkpoint("fake.pt");
  settle_jobs(v);
  ObjectEdit edit = object_initial_state(collide(), 2, 2);
  edit.velocity += Vec3(0.0, 0.5, 0.0);
  model.hold();
  app.start_what_if(edit);
  model.wait_started(1);
  // The model is blocked: frames keep coming and the UI shows the job.
  for (int i = 0; i < 5; ++i) app.frame();
  EXPECT_TRUE(app.busy());
  EXPECT_FALSE(app.has_rollout());
  model.release();
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (app.busy() && std::chrono::steady_clock::now() < end) app.frame();
  ASSERT_TRUE(app.has_rollout()) << app.last_error();
  ASSERT_NE(app.compared_rollout(), nullptr);
  EXPECT_EQ(app.rollout_mode(), RolloutMode::kSideBySide);
  // New vs original: same points at the observed start apart from the edited object's motion.
  const Rollout& edited = app.rollout().rollout;
  const Rollout& original = app.compared_rollout()->rollout;
  EXPECT_GT((edited.predicted.back() - original.predicted.back()).norm(), 1e-3);
}

TEST(ViewerRollout, TwoCheckpointsSideBySide) {
  FakeModel model;
  HeadlessViewer v(&model);
  ViewerApp& app = v.app;
  app.open_scene(testing::collide_scene());
  app.set_checkpoint("a.pt");
  app.start_rollouts("b.pt");
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (app.busy() && std::chrono::steady_clock::now() < end) app.frame();
  ASSERT_TRUE(app.has_rollout()) << app.last_error();
  ASSERT_NE(app.compared_rollout(), nullptr);
  EXPECT_EQ(app.rollout().rollout.checkpoint_path, "a.pt");
  EXPECT_EQ(app.compared_rollout()->rollout.checkpoint_path, "b.pt");
  const std::vector<Viewport> ports = app.viewports();
  ASSERT_EQ(ports.size(), 2u);
  EXPECT_EQ(ports[0].scene.points[0].series, app.compared_rollout()->series.prediction);
  EXPECT_EQ(ports[1].scene.points[0].series, app.rollout().series.prediction);
}

TEST(InitialStateEdit, StateReadsBackAndHistoryMovesRigidly) {
  const Scene& scene = collide();
  const int t = 2, object = 2;
  ObjectEdit edit = object_initial_state(scene, object, t);
  edit.position += Vec3(0.1, -0.2, 0.05);
  edit.euler_deg += Vec3(0.0, 0.0, 30.0);
  edit.velocity = Vec3(0.3, 0.0, 0.0);
  const Scene edited = apply_initial_state_edit(scene, edit, t);
  const ObjectEdit back = object_initial_state(edited, object, t);
  EXPECT_NEAR((back.position - edit.position).norm(), 0.0, 1e-9);
  EXPECT_NEAR((back.velocity - edit.velocity).norm(), 0.0, 1e-9);
  const Quat want = Quat(Eigen::AngleAxisd(edit.euler_deg.z() * M_PI / 180, Vec3::UnitZ()) *
                         Eigen::AngleAxisd(edit.euler_deg.y() * M_PI / 180, Vec3::UnitY()) *
                         Eigen::AngleAxisd(edit.euler_deg.x() * M_PI / 180, Vec3::UnitX()));
  EXPECT_NEAR(want.angularDistance(edited.trajectories[object].poses[t].rotation), 0.0, 1e-9);
  // Later frames and other objects keep the recording.
  EXPECT_EQ(edited.trajectories[object].poses[t + 1].position,
            scene.trajectories[object].poses[t + 1].position);
  EXPECT_EQ(edited.trajectories[0].poses[0].position, scene.trajectories[0].poses[0].position);
  EXPECT_THROW(apply_initial_state_edit(scene, edit, 0), ValueError);
  edit.object = 99;
  EXPECT_THROW(apply_initial_state_edit(scene, edit, t), ValueError);
}

}  // namespace
}  // namespace dynscope::app::viewer
