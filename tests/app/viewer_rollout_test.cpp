// Tests of the viewer with rollouts and a fake model: display modes, error strip, uploads,
// trace-driven inspector, background rollouts (two checkpoints, what-if) and bad files.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <cstdlib>
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
#include "fake_model.h"
#include "viewer_test_util.h"

namespace dynscope::app::viewer {
namespace {

namespace fs = std::filesystem;
using testing::cv_rollout;
using testing::FakeModel;
using testing::HeadlessViewer;

// A directory of this process (ctest runs the tests of this binary in parallel processes).
fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("dynscope_viewer_rollout_test_" + name + "_" +
                                                    std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
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
  while (v.app.state().busy() && std::chrono::steady_clock::now() < end) {
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

TEST(ViewerRollout, ShowsFrameKsPredictedPointsAtFrameK) {
  HeadlessViewer v;
  v.app.state().open_file(collide_rollout_file());
  ASSERT_TRUE(v.app.state().has_rollout());
  EXPECT_TRUE(v.app.state().has_scene());  // the scene it names was opened too (meshes)
  v.app.state().set_rollout_mode(RolloutMode::kPrediction);
  const Rollout& r = collide_rollout();
  for (int k : {0, 17, r.num_frames() - 1}) {
    v.app.state().set_frame(k);
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
  v.app.state().open_rollout(collide_rollout_file());
  v.app.state().set_frame(30);
  using Names = std::vector<std::vector<std::string>>;
  v.app.state().set_rollout_mode(RolloutMode::kPrediction);
  EXPECT_EQ(layer_names(v.app), (Names{{"prediction"}}));
  v.app.state().set_rollout_mode(RolloutMode::kTruth);
  EXPECT_EQ(layer_names(v.app), (Names{{"truth"}}));
  v.app.state().set_rollout_mode(RolloutMode::kGhost);
  EXPECT_EQ(layer_names(v.app), (Names{{"prediction", "truth (ghost)"}}));
  v.app.state().set_rollout_mode(RolloutMode::kSideBySide);
  EXPECT_EQ(layer_names(v.app), (Names{{"truth"}, {"prediction"}}));
  // Side by side: two viewports, the same camera shifted apart, both drawn into one image.
  const std::vector<Viewport> ports = v.app.viewports();
  EXPECT_EQ(ports[0].rect.x + ports[0].rect.width, ports[1].rect.x);
  EXPECT_EQ(ports[0].camera.yaw_deg, ports[1].camera.yaw_deg);
  EXPECT_EQ(ports[0].camera.distance, ports[1].camera.distance);
  v.app.set_ui_visible(false);
  v.app.frame();
  const render::Image split = v.app.read_pixels();
  v.app.state().set_rollout_mode(RolloutMode::kPrediction);
  v.app.frame();
  EXPECT_LT(render::compare_images(split, v.app.read_pixels(), 8).fraction_within, 0.99);
  // Error colours follow the range: manual range reaches the layer.
  v.app.state().set_rollout_mode(RolloutMode::kPrediction);
  render::ViewSpec view = v.app.state().current_view();
  view.auto_range = false;
  view.range_max = 0.25f;
  v.app.state().set_view(view);
  // A copy: viewports() returns a temporary (a reference into it dangled; AddressSanitizer).
  const render::PointLayer p = v.app.viewports()[0].scene.points[0];
  EXPECT_EQ(p.coloring, render::PointColoring::kScalar);
  EXPECT_FLOAT_EQ(p.range_max, 0.25f);
}

// At an observed frame truth and prediction coincide: the translucent truth ghost must not tint
// the prediction (it once did, by drawing over it at equal depth), so ghost mode looks exactly
// like prediction-only mode there.
TEST(ViewerRollout, GhostAtAnObservedFrameLeavesThePredictionUntinted) {
  HeadlessViewer v;
  ViewerState& state = v.app.state();
  state.open_rollout(collide_rollout_file());
  state.set_frame(0);
  state.set_rollout_mode(RolloutMode::kPrediction);
  v.app.frame();
  v.app.frame();
  const render::Image alone = v.app.read_pixels();
  state.set_rollout_mode(RolloutMode::kGhost);
  v.app.frame();
  v.app.frame();
  const render::Image ghost = v.app.read_pixels();
  int differing = 0, drawn = 0;
  for (int y = 10; y < testing::kHeight - 140; ++y) {
    for (int x = 400; x < testing::kWidth; ++x) {
      const uint8_t* a = alone.pixel(x, y);
      const uint8_t* b = ghost.pixel(x, y);
      if (a[0] != alone.pixel(testing::kWidth - 2, 12)[0]) ++drawn;
      for (int c = 0; c < 3; ++c) {
        if (std::abs(int{a[c]} - int{b[c]}) > 2) {
          ++differing;
          break;
        }
      }
    }
  }
  EXPECT_GT(drawn, 1000) << "nothing drawn in the 3D view";
  EXPECT_EQ(differing, 0) << "the ghost changed pixels where it coincides with the prediction";
}

TEST(ViewerRollout, ScrubbingAddsNoUploads) {
  HeadlessViewer v;
  v.app.state().open_rollout(collide_rollout_file());
  v.app.state().set_rollout_mode(RolloutMode::kSideBySide);
  v.app.frame();
  const int64_t uploads = v.app.upload_count();
  for (int k : {5, 20, 40, 59, 0}) {
    v.app.state().set_frame(k);
    v.app.frame();
  }
  v.app.state().set_rollout_mode(RolloutMode::kGhost);
  v.app.frame();
  EXPECT_EQ(v.app.upload_count(), uploads);
}

TEST(ViewerRollout, JumpToThresholdFindsTheFirstFrameOverIt) {
  HeadlessViewer v;
  v.app.state().open_rollout(collide_rollout_file());
  const std::vector<double>& e = collide_rollout().point_error;
  const double threshold = 0.5 * *std::max_element(e.begin(), e.end());
  const int expected = first_frame_over(e, threshold);
  ASSERT_GT(expected, 0);
  EXPECT_LE(e[expected - 1], threshold);
  v.app.state().set_error_threshold(threshold);
  EXPECT_EQ(v.app.state().jump_to_error_threshold(), expected);
  EXPECT_EQ(v.app.state().current_frame(), expected);
  v.app.state().set_frame(2);
  v.app.state().set_error_threshold(1e9);
  EXPECT_EQ(v.app.state().jump_to_error_threshold(), -1);
  EXPECT_EQ(v.app.state().current_frame(), 2);
  v.app.state().show_panel(Panel::kContacts);
  v.app.frame();
  v.app.frame();
  EXPECT_TRUE(v.app.last_error().empty()) << v.app.last_error();
}

TEST(ViewerRollout, BadRolloutFileGivesAnErrorPopup) {
  const fs::path dir = temp_dir("bad");
  HeadlessViewer v;
  v.app.state().open_scene(testing::collide_scene());
  v.app.frame();
  std::ofstream(dir / "broken.h5") << "not hdf5";
  try {
    v.app.state().open_rollout((dir / "broken.h5").string());
    FAIL() << "no error for a corrupt rollout";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("broken.h5"), std::string::npos) << e.what();
  }
  // A scene file is HDF5 but not a rollout.
  EXPECT_THROW(v.app.state().open_rollout(testing::collide_scene()), Error);
  // Opened from the Files section: the error becomes the popup, the scene stays, frames go on.
  v.app.request_open((dir / "broken.h5").string());
  EXPECT_NO_THROW(v.app.frame());
  EXPECT_NE(v.app.last_error().find("broken.h5"), std::string::npos) << v.app.last_error();
  EXPECT_NO_THROW(v.app.frame());
  EXPECT_TRUE(v.app.state().has_scene());
  EXPECT_FALSE(v.app.state().has_rollout());
  EXPECT_EQ(v.app.state().document().path, testing::collide_scene());
}

TEST(ViewerRollout, TraceDrivesTheInspector) {
  FakeModel model;
  HeadlessViewer v(&model);
  ViewerApp& app = v.app;
  app.state().open_scene(testing::collide_scene());
  app.state().set_checkpoint("fake.pt");
  app.state().set_frame(12);
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while ((app.state().busy() || !app.state().shown_trace()) &&
         std::chrono::steady_clock::now() < end)
    app.frame();
  ASSERT_NE(app.state().shown_trace(), nullptr);
  EXPECT_EQ(app.state().shown_trace()->frame, 12);
  app.state().select_point(7);
  while ((app.state().busy() || app.state().shown_trace()->queries.empty()) &&
         std::chrono::steady_clock::now() < end) {
    app.frame();
  }
  ASSERT_FALSE(app.state().shown_trace()->queries.empty());
  const Neighborhood n = point_neighborhood(*app.state().active_data(), 7, 12);
  EXPECT_EQ(n.k, FakeModel::kK);
  EXPECT_EQ(n.object_conv, "unet.stem.0.object.conv");
  const TraceList& same = app.state().shown_trace()->levels[0].lists[0];
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
  app.state().show_panel(Panel::kInspector);
  app.state().show_panel(Panel::kLevels);
  app.frame();
  app.frame();
  EXPECT_TRUE(app.last_error().empty()) << app.last_error();
}

// A saved view with a picked point and the level layers, opened over a rollout while the
// checkpoint's trace is still being captured: the frame draws without the neighbourhood (it has
// no lists yet), never an error, and with them once the trace arrives.
TEST(ViewerRollout, APickWaitsForTheTraceWithoutErrors) {
  FakeModel model;
  HeadlessViewer v(&model);
  ViewerApp& app = v.app;
  app.state().open_scene(testing::collide_scene());
  const Scene scene = app.state().document().scene;
  app.state().set_rollout(cv_rollout(scene, testing::collide_scene()), "r", &scene);
  app.state().set_checkpoint("fake.pt");
  model.hold();
  render::ViewSpec view = app.state().current_view();
  view.frame = 12;
  view.picked_point = 3;
  view.layers.level_points = true;
  view.layers.neighborhoods = true;
  view.layers.interaction_points = true;
  app.state().set_view(view);
  for (int i = 0; i < 3; ++i) app.frame();
  EXPECT_EQ(app.error_count(), 0) << app.last_error();
  EXPECT_EQ(app.state().shown_trace(), nullptr);
  model.release();
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while ((app.state().busy() || !app.state().shown_trace()) &&
         std::chrono::steady_clock::now() < end) {
    app.frame();
  }
  ASSERT_NE(app.state().shown_trace(), nullptr);
  EXPECT_EQ(app.state().shown_trace()->source, kTraceSourceRollout);
  app.frame();
  EXPECT_EQ(app.error_count(), 0) << app.last_error();
}

TEST(ViewerRollout, WhatIfRunsInTheBackground) {
  FakeModel model;
  HeadlessViewer v(&model);
  ViewerApp& app = v.app;
  app.state().open_scene(testing::collide_scene());
  app.state().set_checkpoint("fake.pt");
  settle_jobs(v);
  ObjectEdit edit = object_initial_state(collide(), 2, 2);
  edit.velocity += Vec3(0.0, 0.5, 0.0);
  model.hold();
  app.state().start_what_if(edit);
  model.wait_started(1);
  // The model is blocked: frames keep coming and the UI shows the job.
  for (int i = 0; i < 5; ++i) app.frame();
  EXPECT_TRUE(app.state().busy());
  EXPECT_FALSE(app.state().has_rollout());
  model.release();
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (app.state().busy() && std::chrono::steady_clock::now() < end) app.frame();
  ASSERT_TRUE(app.state().has_rollout()) << app.last_error();
  ASSERT_NE(app.state().compared_rollout(), nullptr);
  EXPECT_EQ(app.state().rollout_mode(), RolloutMode::kSideBySide);
  // New vs original: same points at the observed start apart from the edited object's motion.
  const Rollout& edited = app.state().rollout().rollout;
  const Rollout& original = app.state().compared_rollout()->rollout;
  EXPECT_GT((edited.predicted.back() - original.predicted.back()).norm(), 1e-3);
}

TEST(ViewerRollout, TwoCheckpointsSideBySide) {
  FakeModel model;
  HeadlessViewer v(&model);
  ViewerApp& app = v.app;
  app.state().open_scene(testing::collide_scene());
  app.state().set_checkpoint("a.pt");
  app.state().start_rollouts("b.pt");
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (app.state().busy() && std::chrono::steady_clock::now() < end) app.frame();
  ASSERT_TRUE(app.state().has_rollout()) << app.last_error();
  ASSERT_NE(app.state().compared_rollout(), nullptr);
  EXPECT_EQ(app.state().rollout().rollout.checkpoint_path, "a.pt");
  EXPECT_EQ(app.state().compared_rollout()->rollout.checkpoint_path, "b.pt");
  const std::vector<Viewport> ports = app.viewports();
  ASSERT_EQ(ports.size(), 2u);
  EXPECT_EQ(ports[0].scene.points[0].series, app.state().compared_rollout()->series.prediction);
  EXPECT_EQ(ports[1].scene.points[0].series, app.state().rollout().series.prediction);
}

// The point of `set` drawn nearest the eye in viewport `port` among those projecting into the
// viewport's free part (not under the panels), with its pixel; -1 when none does.
int nearest_drawn(const ViewerApp& app, int port, PickSet set, Vec3* pixel) {
  const Viewport p = app.viewports()[static_cast<size_t>(port)];
  const RolloutDocument& doc =
      set == PickSet::kCompared ? *app.state().compared_rollout() : app.state().rollout();
  const int f = app.state().current_frame();
  const Points& at = set == PickSet::kTruth ? doc.rollout.truth[static_cast<size_t>(f)]
                                            : doc.rollout.predicted[static_cast<size_t>(f)];
  const int lo = std::max(p.rect.x, 400) + 10, hi = p.rect.x + p.rect.width - 10;
  int best = -1;
  for (Eigen::Index i = 0; i < at.rows(); ++i) {
    const Vec3 s = p.camera.project(at.row(i).transpose(), testing::kWidth, testing::kHeight);
    if (s.x() < lo || s.x() > hi || s.y() < 10 || s.y() > testing::kHeight - 140) continue;
    if (best < 0 || s.z() < pixel->z()) {
      best = static_cast<int>(i);
      *pixel = s;
    }
  }
  return best;
}

// Ghost mode draws the prediction opaque and the truth translucent: a click selects whichever
// of the two is drawn in front at the pixel, and says which set and frame it was.
TEST(ViewerPick, GhostModePicksThePredictionOrTheTruthDrawn) {
  HeadlessViewer v;
  ViewerState& state = v.app.state();
  state.open_rollout(collide_rollout_file());
  state.set_rollout_mode(RolloutMode::kGhost);
  state.set_frame(40);
  v.app.frame();
  Vec3 pred_pixel = Vec3::Zero(), truth_pixel = Vec3::Zero();
  const int pred = nearest_drawn(v.app, 0, PickSet::kPrediction, &pred_pixel);
  const int truth = nearest_drawn(v.app, 0, PickSet::kTruth, &truth_pixel);
  ASSERT_GE(pred, 0);
  ASSERT_GE(truth, 0);
  // The nearer of the two sets' nearest points is what a click at its centre hits.
  const bool pred_first = pred_pixel.z() <= truth_pixel.z();
  const Vec3 pixel = pred_first ? pred_pixel : truth_pixel;
  ASSERT_TRUE(v.app.pick(static_cast<int>(pixel.x()), static_cast<int>(pixel.y())));
  Selection sel = state.selection();
  EXPECT_EQ(sel.set, pred_first ? PickSet::kPrediction : PickSet::kTruth);
  EXPECT_EQ(sel.point, pred_first ? pred : truth);
  EXPECT_EQ(sel.frame, 40);
  EXPECT_EQ(state.selected_point(), -1);  // no level point is selected with it
  // Prediction-only mode: the prediction's nearest point is picked as the prediction.
  state.set_rollout_mode(RolloutMode::kPrediction);
  ASSERT_EQ(nearest_drawn(v.app, 0, PickSet::kPrediction, &pred_pixel), pred);
  ASSERT_TRUE(v.app.pick(static_cast<int>(pred_pixel.x()), static_cast<int>(pred_pixel.y())));
  EXPECT_EQ(state.selection().set, PickSet::kPrediction);
  EXPECT_EQ(state.selection().point, pred);
  // The selection follows scrubbing (points keep their identity) and remembers its frame.
  state.set_frame(45);
  EXPECT_EQ(state.selection().point, pred);
  EXPECT_EQ(state.selection().frame, 40);
  state.show_panel(Panel::kInspector);
  v.app.frame();
  v.app.frame();
  EXPECT_TRUE(v.app.last_error().empty()) << v.app.last_error();
  // Empty sky keeps it; clearing drops it.
  EXPECT_FALSE(v.app.pick(testing::kWidth - 2, 2));
  EXPECT_EQ(state.selection().set, PickSet::kPrediction);
  state.select_point(-1);
  EXPECT_TRUE(state.selection().empty());
}

// The selected point is marked in the 3D view, with the same point of the other set and the
// error vector between them, at every frame it is scrubbed to, without uploads per frame.
TEST(ViewerPick, TheSelectionIsMarkedWithItsErrorVector) {
  HeadlessViewer v;
  ViewerState& state = v.app.state();
  state.open_rollout(collide_rollout_file());
  state.set_rollout_mode(RolloutMode::kGhost);
  state.set_frame(40);
  const RolloutDocument& doc = state.rollout();
  const int point = 7;
  state.select(PickSet::kPrediction, point);
  v.app.frame();
  const int64_t uploads = v.app.upload_count();
  for (int f : {41, 50, 40}) {
    state.set_frame(f);
    v.app.frame();
    const std::vector<Viewport> ports = v.app.viewports();
    ASSERT_EQ(ports.size(), 1u);
    const render::LineSet* error = nullptr;
    for (const render::LineSet& l : ports[0].scene.lines) {
      if (l.name == "selection error") error = &l;
    }
    ASSERT_NE(error, nullptr) << f;
    const Vec3 pred = doc.rollout.predicted[static_cast<size_t>(f)].row(point).transpose();
    const Vec3 truth = doc.rollout.truth[static_cast<size_t>(f)].row(point).transpose();
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(error->positions[k], pred[k], 1e-5) << f;
      EXPECT_NEAR(error->positions[3 + k], truth[k], 1e-5) << f;
    }
  }
  EXPECT_EQ(v.app.upload_count(), uploads) << "the marker was uploaded again while scrubbing";
  // The marker is drawn: magenta at the predicted point's pixel.
  const Viewport port = v.app.viewports()[0];
  const Vec3 s = port.camera.project(doc.rollout.predicted[40].row(point).transpose(),
                                     testing::kWidth, testing::kHeight);
  const render::Image image = v.app.read_pixels();
  const uint8_t* px = image.pixel(static_cast<int>(s.x()), static_cast<int>(s.y()));
  EXPECT_GT(px[0], 150) << "not magenta at the selected point";
  EXPECT_LT(px[1], 90) << "not magenta at the selected point";
  // Clearing the selection removes it.
  state.select_point(-1);
  EXPECT_EQ(state.selection_marker(), nullptr);
}

TEST(ViewerPick, SideBySidePicksTheSetOfTheViewportClicked) {
  HeadlessViewer v;
  ViewerState& state = v.app.state();
  state.open_rollout(collide_rollout_file());
  state.set_rollout_mode(RolloutMode::kSideBySide);
  state.set_frame(40);
  v.app.frame();
  Vec3 pixel = Vec3::Zero();
  const int truth = nearest_drawn(v.app, 0, PickSet::kTruth, &pixel);
  ASSERT_GE(truth, 0);
  ASSERT_TRUE(v.app.pick(static_cast<int>(pixel.x()), static_cast<int>(pixel.y())));
  EXPECT_EQ(state.selection().set, PickSet::kTruth);
  EXPECT_EQ(state.selection().point, truth);
  const int pred = nearest_drawn(v.app, 1, PickSet::kPrediction, &pixel);
  ASSERT_GE(pred, 0);
  ASSERT_TRUE(v.app.pick(static_cast<int>(pixel.x()), static_cast<int>(pixel.y())));
  EXPECT_EQ(state.selection().set, PickSet::kPrediction);
  EXPECT_EQ(state.selection().point, pred);
  // Sets that are not shown, or points they do not have, are refused.
  EXPECT_THROW(state.select(PickSet::kCompared, 0), ValueError);
  EXPECT_THROW(
      state.select(PickSet::kTruth, static_cast<int>(state.rollout().rollout.num_points())),
      ValueError);
  EXPECT_EQ(state.selection().point, pred);
  // Replacing the rollout drops the selection.
  state.open_rollout(collide_rollout_file());
  EXPECT_TRUE(state.selection().empty());
}

// Frames 0..1 cannot be traced (the state reads p(t-2)): the level browser and inspector use the
// model's trace of frame 2, the first it can trace, and its points can be picked there.
TEST(ViewerPick, ObservedFrameUsesTheFirstTraceableFrame) {
  FakeModel model;
  HeadlessViewer v(&model);
  ViewerState& state = v.app.state();
  state.open_scene(testing::collide_scene());
  state.set_checkpoint("fake.pt");
  state.set_frame(0);
  EXPECT_EQ(state.trace_frame(), 2);
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while ((state.busy() || !state.shown_trace()) && std::chrono::steady_clock::now() < end) {
    v.app.frame();
  }
  ASSERT_NE(state.shown_trace(), nullptr) << v.app.last_error();
  EXPECT_EQ(state.shown_trace()->frame, 2);
  EXPECT_EQ(state.current_frame(), 0);
  EXPECT_EQ(state.level_frame(), 2);
  const std::vector<Viewport> ports = v.app.viewports();
  ASSERT_EQ(ports.size(), 1u);
  EXPECT_NE(ports[0].caption.find("frame 2"), std::string::npos) << ports[0].caption;
  // Picking reads the trace's level points, drawn at frame 2.
  const Points p = state.shown_trace()->levels[0].points;
  int best = -1;
  Vec3 pixel = Vec3::Zero();
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const Vec3 s = state.camera().project(p.row(i).transpose(), testing::kWidth, testing::kHeight);
    if (s.x() < 400 || s.x() > testing::kWidth - 10 || s.y() < 10 ||
        s.y() > testing::kHeight - 80) {
      continue;
    }
    if (best < 0 || s.z() < pixel.z()) {
      best = static_cast<int>(i);
      pixel = s;
    }
  }
  ASSERT_GE(best, 0);
  ASSERT_TRUE(v.app.pick(static_cast<int>(pixel.x()), static_cast<int>(pixel.y())));
  EXPECT_EQ(state.selection().set, PickSet::kLevel);
  EXPECT_EQ(state.selection().point, best);
  EXPECT_EQ(state.selection().frame, 2);
  state.show_panel(Panel::kInspector);
  v.app.frame();
  v.app.frame();
  EXPECT_TRUE(v.app.last_error().empty()) << v.app.last_error();
  // Frame 1 reads the same trace; frame 5 is traced as itself.
  state.set_frame(1);
  EXPECT_NE(state.shown_trace(), nullptr);
  state.set_frame(5);
  EXPECT_EQ(state.trace_frame(), 5);
  EXPECT_EQ(state.shown_trace(), nullptr);
  // Without a checkpoint every frame is its own.
  state.set_checkpoint("");
  state.set_frame(0);
  EXPECT_EQ(state.trace_frame(), 0);
  EXPECT_EQ(state.level_frame(), 0);
}

// A viewer showing the constant-velocity collide rollout with the fake checkpoint attached.
void show_rollout_with_checkpoint(HeadlessViewer& v) {
  ViewerState& state = v.app.state();
  state.open_scene(testing::collide_scene());
  const Scene scene = state.document().scene;
  state.set_rollout(collide_rollout(), "r", &scene);
  state.set_checkpoint("fake.pt");
  settle_jobs(v);
}

bool has_layer(const ViewerApp& app, const std::string& name) {
  for (const std::vector<std::string>& port : layer_names(app)) {
    if (std::find(port.begin(), port.end(), name) != port.end()) return true;
  }
  return false;
}

TEST(ViewerExplain, TheDivergenceIsExplainedInTheBackgroundAndColoursThePrediction) {
  FakeModel model;
  HeadlessViewer v(&model);
  ViewerState& state = v.app.state();
  EXPECT_THROW(state.start_explain(-1, -1, -1, ExplainTarget::kError), ValueError) << "no rollout";
  state.open_scene(testing::collide_scene());
  const Scene scene = state.document().scene;
  state.set_rollout(collide_rollout(), "r", &scene);
  EXPECT_THROW(state.start_explain(-1, -1, -1, ExplainTarget::kError), ValueError)
      << "no checkpoint";
  state.set_checkpoint("fake.pt");
  settle_jobs(v);
  state.start_explain(-1, -1, -1, ExplainTarget::kError);
  EXPECT_TRUE(state.busy());
  settle_jobs(v);
  ASSERT_NE(state.explanation(), nullptr) << v.app.last_error();
  const RolloutExplanation& x = *state.explanation();
  ASSERT_TRUE(x.divergence.found());
  EXPECT_EQ(x.explanation.frame, x.divergence.frame);
  EXPECT_EQ(x.explanation.object, x.divergence.object);
  EXPECT_EQ(state.current_frame(), x.divergence.frame) << "the timeline moves to the pass";
  EXPECT_EQ(x.divergence.curves.objects.size(), scene.objects.size());
  // The prediction is drawn in the attribution's colours, still pickable as the prediction.
  EXPECT_TRUE(has_layer(v.app, "attribution"));
  EXPECT_TRUE(has_layer(v.app, "explained"));
  EXPECT_FALSE(state.layers().level_points) << "the level points would cover the colours";
  EXPECT_FALSE(has_layer(v.app, "prediction"));
  bool pickable = false;
  for (const Viewport& p : v.app.viewports()) {
    for (size_t i = 0; i < p.scene.points.size(); ++i) {
      pickable = pickable || (p.scene.points[i].name == "attribution" &&
                              p.layer_sets[i] == PickSet::kPrediction);
    }
  }
  EXPECT_TRUE(pickable);
  const render::PointAttribution& a = state.attribution();
  ASSERT_EQ(a.shares.size(), static_cast<size_t>(collide_rollout().num_points()));
  EXPECT_EQ(a.explained, x.explanation.points);
  state.set_attribution_colors(false);
  v.app.frame();
  EXPECT_TRUE(has_layer(v.app, "prediction"));
  EXPECT_FALSE(has_layer(v.app, "attribution"));
  // A chosen point at the current pass.
  state.select(PickSet::kPrediction, 5);
  state.start_explain(state.current_frame(), -1, 5, ExplainTarget::kAcceleration);
  settle_jobs(v);
  ASSERT_NE(state.explanation(), nullptr);
  EXPECT_EQ(state.explanation()->explanation.point, 5);
  EXPECT_EQ(state.explanation()->explanation.target, ExplainTarget::kAcceleration);
  EXPECT_TRUE(state.attribution_colors());
  EXPECT_EQ(v.app.error_count(), 0) << v.app.last_error();
}

TEST(ViewerExplain, AnExplanationStartedForAnotherDocumentIsDropped) {
  FakeModel model;
  HeadlessViewer v(&model);
  ViewerState& state = v.app.state();
  show_rollout_with_checkpoint(v);
  const Scene scene = state.document().scene;
  for (int kind = 0; kind < 3; ++kind) {
    model.hold();
    const int started = model.explains_.load();
    state.start_explain(-1, -1, -1, ExplainTarget::kError);
    EXPECT_THROW(state.start_explain(-1, -1, -1, ExplainTarget::kError), ValueError)
        << "one explanation at a time";
    v.app.frame();
    if (kind == 0) state.set_rollout(collide_rollout(), "another rollout", &scene);
    if (kind == 1) state.set_checkpoint("other.pt");
    if (kind == 2) state.open_scene(testing::collide_scene());
    model.release();
    settle_jobs(v);
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (state.retiring_jobs() > 0 && std::chrono::steady_clock::now() < end) v.app.frame();
    EXPECT_EQ(state.explanation(), nullptr) << "kind " << kind;
    EXPECT_EQ(state.attribution_series(), nullptr);
    EXPECT_GE(model.explains_.load() + model.cancelled_calls(), started);
    EXPECT_EQ(v.app.error_count(), 0) << v.app.last_error();
    if (kind == 1) state.set_checkpoint("fake.pt");
    if (kind == 2) {
      state.set_rollout(collide_rollout(), "r", &scene);
      state.set_checkpoint("fake.pt");
    }
    settle_jobs(v);
  }
  EXPECT_GE(state.dropped_results(), 3);
}

TEST(ViewerExplain, AContactPairOpensTheInspectorOnItsNearestPoint) {
  FakeModel model;
  HeadlessViewer v(&model);
  ViewerState& state = v.app.state();
  show_rollout_with_checkpoint(v);
  const Rollout& r = collide_rollout();
  const int32_t a = r.object_ids.front(), b = r.object_ids.back();
  ASSERT_NE(a, b);
  const int frame = 20;
  state.inspect_pair(frame, a, b);
  EXPECT_EQ(state.current_frame(), frame);
  const Selection pick = state.selection();
  ASSERT_EQ(pick.set, PickSet::kPrediction);
  EXPECT_EQ(r.object_ids[static_cast<size_t>(pick.point)], a);
  // No point of a is nearer to b than the chosen one.
  const Points& p = r.predicted[frame];
  auto gap = [&](int i) {
    double best = 1e300;
    for (Eigen::Index j = 0; j < p.rows(); ++j) {
      if (r.object_ids[static_cast<size_t>(j)] == b)
        best = std::min(best, (p.row(i) - p.row(j)).norm());
    }
    return best;
  };
  for (int i = 0; i < p.rows(); ++i) {
    if (r.object_ids[static_cast<size_t>(i)] == a) {
      EXPECT_GE(gap(i), gap(pick.point) - 1e-12);
    }
  }
  EXPECT_THROW(state.inspect_pair(frame, a, 999), ValueError);
  EXPECT_THROW(state.inspect_pair(1000, a, b), ValueError);
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
