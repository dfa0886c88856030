// Tests of ViewerState's jobs with a fake model: every race between a running job and the user
// replacing the scene, rollout or checkpoint ends with no crash and no stale result shown;
// cancellation; one loaded model per checkpoint reused across jobs.
#include "app/viewer/viewer_state.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "engine/core/error.h"
#include "engine/io/rollout_file.h"
#include "engine/io/scene_file.h"
#include "engine/io/trace_file.h"
#include "engine/model/model_config.h"
#include "engine/rollout/rollout_runner.h"
#include "engine/rollout/state_history.h"
#include "fake_model.h"
#include "viewer_test_util.h"

namespace dynscope::app::viewer {
namespace {

namespace fs = std::filesystem;
using testing::cv_rollout;
using testing::FakeModel;

std::string other_scene() {
  return std::string(DYNSCOPE_SOURCE_DIR) + "/assets/scenes/drop_0000.h5";
}

// Runs update_jobs (which starts any trace the view needs) until no job runs and every cancelled
// thread has ended (at most 10 s).
void settle(ViewerState& s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  s.update_jobs();  // may start the trace the view needs
  while ((s.busy() || s.retiring_jobs() > 0) && std::chrono::steady_clock::now() < end) {
    s.update_jobs();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  s.update_jobs();
}

// A rollout file of the collide scene whose scene file cannot be found.
std::string orphan_rollout_file() {
  const fs::path dir = fs::temp_directory_path() / "dynscope_viewer_state_test";
  fs::create_directories(dir);
  const Scene scene = read_scene(testing::collide_scene());
  Rollout r = cv_rollout(scene, (dir / "gone.h5").string());
  const std::string path = (dir / "orphan_rollout.h5").string();
  write_rollout(r, path);
  return path;
}

TEST(ViewerState, ReplacingTheSceneDropsARunningRollout) {
  FakeModel model;
  ViewerState s(&model);
  s.open_scene(testing::collide_scene());
  s.set_checkpoint("a.pt");
  model.hold();
  s.start_rollouts("");
  model.wait_started(1);
  const uint64_t before = s.generation();
  s.open_scene(other_scene());
  EXPECT_GT(s.generation(), before);
  EXPECT_FALSE(s.busy());  // the job was cancelled and retired at once
  model.release();
  settle(s);
  EXPECT_FALSE(s.has_rollout());  // the collide rollout never lands on the drop scene
  EXPECT_EQ(s.document().path, other_scene());
  EXPECT_GE(s.dropped_results(), 1);
}

TEST(ViewerState, RolloutFileWithoutItsSceneWhileARolloutRuns) {
  FakeModel model;
  ViewerState s(&model);
  s.open_scene(testing::collide_scene());
  s.set_checkpoint("a.pt");
  model.hold();
  s.start_rollouts("");
  model.wait_started(1);
  const std::string orphan = orphan_rollout_file();
  s.open_rollout(orphan);  // no scene: the scene document goes away
  EXPECT_FALSE(s.has_scene());
  model.release();
  settle(s);
  ASSERT_TRUE(s.has_rollout());
  EXPECT_EQ(s.rollout().path, orphan);  // the file's rollout, not the job's
  EXPECT_GE(s.dropped_results(), 1);
}

TEST(ViewerState, WhatIfRunningWhenAnotherSceneOpens) {
  FakeModel model;
  ViewerState s(&model);
  s.open_scene(testing::collide_scene());
  s.set_checkpoint("a.pt");
  ObjectEdit edit = object_initial_state(s.document().scene, 2, 2);
  edit.velocity += Vec3(0.0, 0.5, 0.0);
  model.hold();
  s.start_what_if(edit);
  model.wait_started(1);
  s.open_scene(other_scene());
  model.release();
  settle(s);
  EXPECT_FALSE(s.has_rollout());
  EXPECT_EQ(s.compared_rollout(), nullptr);
  EXPECT_EQ(s.document().path, other_scene());
  // The what-if of a rollout that is replaced by a rollout file: the file stays shown.
  s.open_scene(testing::collide_scene());
  s.set_checkpoint("a.pt");
  model.hold();
  s.start_what_if(edit);
  model.wait_started(2);
  s.open_rollout(orphan_rollout_file());
  model.release();
  settle(s);
  ASSERT_TRUE(s.has_rollout());
  EXPECT_EQ(s.compared_rollout(), nullptr);
  EXPECT_EQ(s.rollout().path, orphan_rollout_file());
}

TEST(ViewerState, OldCheckpointsTraceIsNeverInstalled) {
  FakeModel model;
  ViewerState s(&model);
  s.open_scene(testing::collide_scene());
  s.set_checkpoint("a.pt");
  s.set_frame(12);
  model.hold();
  s.update_jobs();  // starts the trace of a.pt at frame 12
  model.wait_traces_started(1);
  ASSERT_TRUE(s.busy());
  s.set_checkpoint("b.pt");
  model.release();
  settle(s);
  ASSERT_NE(s.shown_trace(), nullptr);  // b.pt's trace, captured after the change
  EXPECT_EQ(s.shown_trace()->checkpoint_path, "b.pt");
  EXPECT_EQ(s.shown_trace()->frame, 12);
  EXPECT_GE(s.dropped_results(), 1);
}

TEST(ViewerState, TraceOfTheOldSceneIsDropped) {
  FakeModel model;
  ViewerState s(&model);
  s.open_scene(testing::collide_scene());
  s.set_checkpoint("a.pt");
  s.set_frame(12);
  model.hold();
  s.update_jobs();
  model.wait_traces_started(1);
  s.open_scene(other_scene());  // frame 0: the model's first traceable frame (2) is wanted
  model.release();
  settle(s);
  // The old scene's trace was dropped; what is held is the new scene's, captured after the swap.
  ASSERT_NE(s.held_trace(), nullptr);
  EXPECT_EQ(s.held_trace()->scene_path, other_scene());
  EXPECT_EQ(s.held_trace()->frame, 2);
  EXPECT_EQ(s.dropped_results(), 1);
}

TEST(ViewerState, CancelStopsTheModelAndDropsTheResult) {
  FakeModel model;
  ViewerState s(&model);
  s.open_scene(testing::collide_scene());
  s.set_checkpoint("a.pt");
  model.hold();
  s.start_rollouts("b.pt");
  model.wait_started(1);
  s.cancel_jobs();
  EXPECT_FALSE(s.busy());
  settle(s);  // still held: only the cancel flag can end the job
  EXPECT_EQ(s.retiring_jobs(), 0u);
  EXPECT_EQ(model.cancelled_calls(), 1);
  EXPECT_FALSE(s.has_rollout());
  EXPECT_EQ(s.dropped_results(), 1);
  model.release();
  // A job can start again afterwards.
  s.start_rollouts("");
  settle(s);
  EXPECT_TRUE(s.has_rollout());
}

TEST(ViewerState, OneLoadedModelPerCheckpointAcrossJobs) {
  FakeModel model;
  ViewerState s(&model);
  s.open_scene(testing::collide_scene());
  s.set_checkpoint("a.pt");
  s.start_rollouts("b.pt");
  settle(s);
  ASSERT_TRUE(s.has_rollout());
  EXPECT_EQ(model.loads(), 2);
  // Traces at two frames and a what-if with a.pt: no further load.
  s.set_rollout_mode(RolloutMode::kGhost);
  s.open_scene(testing::collide_scene());
  for (int f : {5, 9}) {
    s.set_frame(f);
    settle(s);
    ASSERT_NE(s.shown_trace(), nullptr) << f;
  }
  ObjectEdit edit = object_initial_state(s.document().scene, 2, 2);
  s.start_what_if(edit);
  settle(s);
  EXPECT_TRUE(s.has_rollout());
  EXPECT_EQ(model.loads(), 2);
  EXPECT_EQ(s.model_cache()->loads(), 2);
  // Changing the checkpoint keeps only the models in use.
  s.set_checkpoint("c.pt");
  s.start_rollouts("");
  settle(s);
  EXPECT_EQ(model.loads(), 3);
  EXPECT_LE(s.model_cache()->size(), 2u);
}

// A checkpoint rewritten in place (a training run continued) is loaded again; an unchanged one is
// not.
TEST(ViewerState, ACheckpointRewrittenOnDiskIsLoadedAgain) {
  const fs::path dir = fs::temp_directory_path() / "dynscope_viewer_state_test";
  fs::create_directories(dir);
  const std::string checkpoint = (dir / "rewritten.pt").string();
  { std::ofstream(checkpoint) << "first"; }
  FakeModel model;
  ModelCache cache(model);
  const auto first = cache.get(checkpoint);
  EXPECT_EQ(cache.get(checkpoint), first);
  EXPECT_EQ(model.loads(), 1);
  { std::ofstream(checkpoint) << "second, longer"; }
  EXPECT_NE(cache.get(checkpoint), first);
  EXPECT_EQ(model.loads(), 2);
  EXPECT_EQ(cache.size(), 1u);
}

// A trace file is drawn only on the scene it was captured on: on another scene its neighbourhoods
// would be ones the model never used there.
TEST(ViewerState, ATraceOfAnotherSceneIsRefused) {
  const fs::path dir = fs::temp_directory_path() / "dynscope_viewer_state_test";
  fs::create_directories(dir);
  const std::string path = (dir / "collide_trace.h5").string();
  FakeModel model;
  ViewerState s(&model);
  s.open_scene(testing::collide_scene());
  s.set_checkpoint("a.pt");
  s.set_frame(5);
  settle(s);
  ASSERT_NE(s.held_trace(), nullptr);
  write_trace(*s.held_trace(), path);
  s.open_scene(other_scene());
  try {
    s.open_trace(path);
    FAIL() << "a trace of the collide scene was drawn on another scene";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("collide_trace.h5"), std::string::npos) << e.what();
  }
  EXPECT_EQ(s.document().path, other_scene());
  EXPECT_FALSE(s.trace_from_file());
  s.open_scene(testing::collide_scene());
  EXPECT_NO_THROW(s.open_trace(path));
  EXPECT_TRUE(s.trace_from_file());
}

// Level count and observed frames are the engine's (the model config, the rollout defaults), not
// the viewer's own numbers.
TEST(ViewerState, LevelsAndObservedFramesComeFromTheEngine) {
  ViewerState s;
  EXPECT_EQ(s.num_levels(), ModelConfig{}.levels);
  EXPECT_EQ(s.observed_frames(), RolloutOptions{}.observed_frames);
  s.open_scene(testing::collide_scene());
  const int levels = level_view_config(s.document().scene).levels;
  EXPECT_EQ(s.num_levels(), levels);
  s.set_level(levels - 1);
  EXPECT_THROW(s.set_level(levels), ValueError);
  EXPECT_EQ(s.level_counts().size(), static_cast<size_t>(levels));
  // The rollout's own count wins once one is shown.
  Rollout r = cv_rollout(s.document().scene, testing::collide_scene());
  r.observed_frames = 5;
  s.set_rollout(r, "r", &s.document().scene);
  EXPECT_EQ(s.observed_frames(), 5);
}

// Without a checkpoint the levels are the model's level view of the frame. Scrubbing never builds
// one on the UI thread: a background job does, and its result is installed by a later frame;
// one-off actions (a level change, a pick) build what they read at once.
TEST(ViewerState, ScrubbingBuildsLevelViewsInTheBackground) {
  ViewerState s;
  s.open_scene(testing::collide_scene());
  s.set_level(1);
  ASSERT_NE(s.shown_trace(), nullptr) << "a level change reads its level at once";
  EXPECT_EQ(s.shown_trace()->frame, 0);
  s.set_frame(12);
  EXPECT_EQ(s.shown_trace(), nullptr) << "frame 12's hierarchy was built on the UI thread";
  EXPECT_TRUE(s.busy());
  settle(s);
  s.ensure_render_data(/*in_background=*/true);
  ASSERT_NE(s.shown_trace(), nullptr);
  EXPECT_EQ(s.shown_trace()->frame, 12);
  EXPECT_FALSE(s.busy());
  // The same hierarchy the engine builds for that frame.
  LevelViews direct(s.document().scene, level_view_config(s.document().scene));
  const std::shared_ptr<const ModelTrace> expected = direct.at(12);
  ASSERT_EQ(s.shown_trace()->levels.size(), expected->levels.size());
  EXPECT_EQ(s.shown_trace()->levels[1].points, expected->levels[1].points);

  // A pick right after scrubbing reads the new frame's level at once.
  s.set_frame(15);
  s.select_point(3);
  ASSERT_NE(s.shown_trace(), nullptr);
  EXPECT_EQ(s.shown_trace()->frame, 15);
  EXPECT_EQ(s.selected_point(), 3);

  // A level-view job still running (or not yet taken) when another scene opens is dropped.
  s.set_frame(20);
  ASSERT_TRUE(s.busy());
  const int dropped = s.dropped_results();
  s.open_scene(other_scene());
  settle(s);
  EXPECT_EQ(s.dropped_results(), dropped + 1);
  s.ensure_render_data(/*in_background=*/true);
  settle(s);
  s.ensure_render_data(/*in_background=*/true);
  ASSERT_NE(s.shown_trace(), nullptr);
  EXPECT_EQ(s.shown_trace()->frame, 0);
  EXPECT_EQ(s.shown_trace()->levels[0].points.rows(),
            LevelViews(s.document().scene, level_view_config(s.document().scene))
                .at(0)
                ->levels[0]
                .points.rows())
      << "the new scene's levels, not the old one's";
}

TEST(ViewerState, AMeshFileSaysWhatItIsAndKeepsTheScene) {
  ViewerState s;
  s.open_scene(testing::collide_scene());
  const std::string mesh = std::string(DYNSCOPE_SOURCE_DIR) + "/assets/meshes/torus.obj";
  try {
    s.open_file(mesh);
    FAIL() << "a mesh opened as a scene";
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("is a mesh"), std::string::npos) << what;
    EXPECT_NE(what.find("--meshes"), std::string::npos) << what;
  }
  EXPECT_EQ(s.document().path, testing::collide_scene());
}

// With a rollout shown, the checkpoint's trace reads the rollout's own predicted frames (the pass
// that produced the next one); the inspector can switch to the ground truth and compare lists.
TEST(ViewerState, TracesOfARolloutReadItsOwnPrediction) {
  FakeModel model;
  ViewerState s(&model);
  s.open_scene(testing::collide_scene());
  const Scene scene = s.document().scene;
  Rollout r = cv_rollout(scene, testing::collide_scene());
  // Make the prediction differ from the truth so the two inputs can be told apart.
  for (size_t f = static_cast<size_t>(r.observed_frames); f < r.predicted.size(); ++f) {
    r.predicted[f].col(0).array() += 0.01 * static_cast<double>(f);
  }
  s.set_rollout(r, "r", &scene);
  s.set_checkpoint("fake.pt");
  s.set_frame(10);
  settle(s);
  ASSERT_TRUE(s.traces_rollout());
  const ModelTrace* t = s.shown_trace();
  ASSERT_NE(t, nullptr);
  EXPECT_EQ(t->source, kTraceSourceRollout);
  EXPECT_EQ(t->frame, 10);
  EXPECT_EQ(t->levels[0].points, r.predicted[10]);
  ASSERT_NE(s.truth_input_levels(), nullptr) << "the truth's hierarchy, to compare lists with";
  EXPECT_EQ(s.truth_input_levels()->levels[0].points, r.truth[10]);
  // Frames without a pass of their own: the first that predicted a frame, the one before the last.
  s.set_frame(0);
  EXPECT_EQ(s.trace_frame(), first_rollout_trace_frame(r.observed_frames));
  s.set_frame(r.num_frames() - 1);
  EXPECT_EQ(s.trace_frame(), r.num_frames() - 2);
  // The ground-truth input: the held rollout trace is no longer shown, a scene trace replaces it.
  s.set_frame(10);
  s.set_trace_input(TraceInput::kTruth);
  EXPECT_FALSE(s.traces_rollout());
  EXPECT_EQ(s.shown_trace(), nullptr);
  settle(s);
  ASSERT_NE(s.shown_trace(), nullptr);
  EXPECT_EQ(s.shown_trace()->source, kTraceSourceScene);
  EXPECT_EQ(s.truth_input_levels(), nullptr);
}

}  // namespace
}  // namespace dynscope::app::viewer
