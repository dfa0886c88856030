// Trace files: exact write→read round trip and clear errors for wrong files.
#include "engine/io/trace_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "engine/core/error.h"
#include "engine/io/h5_util.h"

namespace dynscope {
namespace {

std::string trace_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("dynscope_trace_" + name + ".h5")).string();
}

// A list of `rows` x `k` neighbours drawn from `sources` points of level `s`.
TraceList make_list(const std::string& name, int rows, int k, int q, int s, int sources) {
  TraceList l;
  l.name = name;
  l.query_level = q;
  l.source_level = s;
  l.index = IndexMatrix::Zero(rows, k);
  l.mask = MaskMatrix::Zero(rows, k);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < k; ++j) {
      const bool valid = (i + j) % 3 != 0;
      l.index(i, j) = valid ? (i * 7 + j) % sources : -1;
      l.mask(i, j) = valid ? 1 : 0;
    }
  }
  return l;
}

ModelTrace make_trace(bool mesh) {
  ModelTrace t;
  t.scene_path = "scene.h5";
  t.checkpoint_path = "model.pt";
  t.model_config = "{}";
  t.frame = 5;
  for (int l = 0; l < 2; ++l) {
    TraceLevel lv;
    const int n = l == 0 ? 6 : 3;
    lv.points = Points::Random(n, 3);
    lv.object_ids.assign(static_cast<size_t>(n), 4);
    if (l > 0) lv.kept = {0, 2, 5};
    lv.voxel = l * 0.075;
    lv.radius = 0.1 * (l + 1);
    lv.lists.push_back(make_list("same", n, 4, l, l, n));
    if (l > 0) lv.lists.push_back(make_list("down", n, 4, l, l - 1, 6));
    t.levels.push_back(lv);
  }
  if (mesh) {
    t.has_mesh = true;
    t.mesh.faces.resize(2, 3);
    t.mesh.faces << 0, 1, 2, 3, 4, 5;
    t.mesh.points = Points::Random(2, 3);
    t.mesh.face = {0, 1};
    t.mesh.object_ids = {4, 5};
    t.mesh.lists.push_back(make_list("senders", 2, 1, -1, -1, 2));
  }
  t.features.push_back({"decoder.0", 0, {1, 2, 3, 4, 5, 6}});
  t.features.push_back({"encoder.0", 1, {0.5, 0.25, 0.125}});
  TraceQuery q;
  q.point = 3;
  q.conv = "unet.encoder.0.object.conv";
  q.level = 1;
  q.list = "1/down";
  q.query_index = 2;
  q.neighbors = {5, 4, -1};
  q.mask = {1, 1, 0};
  q.weights = Eigen::MatrixXd::Random(3, 4);
  t.queries.push_back(q);
  return t;
}

TEST(TraceFileTest, WriteReadIsExact) {
  for (bool mesh : {false, true}) {
    const ModelTrace t = make_trace(mesh);
    const std::string path = trace_path(mesh ? "mesh" : "points");
    write_trace(t, path);
    const ModelTrace r = read_trace(path);
    EXPECT_EQ(r.scene_path, t.scene_path);
    EXPECT_EQ(r.checkpoint_path, t.checkpoint_path);
    EXPECT_EQ(r.frame, t.frame);
    ASSERT_EQ(r.levels.size(), t.levels.size());
    for (size_t l = 0; l < t.levels.size(); ++l) {
      EXPECT_EQ(r.levels[l].points, t.levels[l].points);
      EXPECT_EQ(r.levels[l].object_ids, t.levels[l].object_ids);
      EXPECT_EQ(r.levels[l].kept, t.levels[l].kept);
      EXPECT_EQ(r.levels[l].voxel, t.levels[l].voxel);
      EXPECT_EQ(r.levels[l].radius, t.levels[l].radius);
      ASSERT_EQ(r.levels[l].lists.size(), t.levels[l].lists.size());
      for (const TraceList& want : t.levels[l].lists) {
        bool found = false;
        for (const TraceList& got : r.levels[l].lists) {
          if (got.name != want.name) continue;
          found = true;
          EXPECT_EQ(got.index, want.index);
          EXPECT_EQ(got.mask, want.mask);
          EXPECT_EQ(got.query_level, want.query_level);
          EXPECT_EQ(got.source_level, want.source_level);
        }
        EXPECT_TRUE(found) << want.name;
      }
    }
    EXPECT_EQ(r.has_mesh, mesh);
    if (mesh) {
      EXPECT_EQ(r.mesh.faces, t.mesh.faces);
      EXPECT_EQ(r.mesh.points, t.mesh.points);
      EXPECT_EQ(r.mesh.face, t.mesh.face);
      ASSERT_EQ(r.mesh.lists.size(), 1u);
      EXPECT_EQ(r.mesh.lists[0].index, t.mesh.lists[0].index);
    }
    ASSERT_EQ(r.features.size(), 2u);  // read back in name order
    EXPECT_EQ(r.features[0].block, "decoder.0");
    EXPECT_EQ(r.features[0].norms, t.features[0].norms);
    EXPECT_EQ(r.features[1].level, 1);
    ASSERT_EQ(r.queries.size(), 1u);
    EXPECT_EQ(r.queries[0].conv, t.queries[0].conv);
    EXPECT_EQ(r.queries[0].list, t.queries[0].list);
    EXPECT_EQ(r.queries[0].query_index, 2);
    EXPECT_EQ(r.queries[0].neighbors, t.queries[0].neighbors);
    EXPECT_EQ(r.queries[0].mask, t.queries[0].mask);
    EXPECT_EQ(r.queries[0].weights, t.queries[0].weights);
  }
}

TEST(TraceFileTest, WrongFilesGiveClearErrors) {
  const std::string text = trace_path("text");
  std::ofstream(text) << "plain text";
  EXPECT_THROW(read_trace(text), IoError);
  const std::string other = trace_path("other");
  {
    h5::Group root = h5::Group::create_file(other);
    root.write_attribute("format", std::string("dynscope-rollout"));
    root.close();
  }
  try {
    read_trace(other);
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_EQ(e.field(), "@format");
  }
  ModelTrace bad = make_trace(false);
  bad.queries[0].mask.pop_back();
  EXPECT_THROW(write_trace(bad, trace_path("bad")), ValueError);
}

// The field named by the FormatError that reading `trace` back throws ("" if none).
std::string read_back_error(const ModelTrace& trace, const std::string& name) {
  const std::string path = trace_path(name);
  write_trace(trace, path);
  try {
    read_trace(path);
  } catch (const FormatError& e) {
    return e.field();
  }
  return "";
}

TEST(TraceFileTest, InconsistentTracesAreRejectedOnRead) {
  ModelTrace short_features = make_trace(false);
  short_features.features[0].norms.pop_back();  // one row short of level 0's six points
  EXPECT_EQ(read_back_error(short_features, "short"), "features/decoder.0");

  ModelTrace nan_points = make_trace(false);
  nan_points.levels[1].points(1, 2) = std::nan("");
  EXPECT_EQ(read_back_error(nan_points, "nan"), "levels/1/points");

  ModelTrace bad_index = make_trace(false);
  bad_index.levels[1].lists[0].index(0, 1) = 3;  // level 1 has points 0..2
  EXPECT_EQ(read_back_error(bad_index, "index"), "levels/1/lists/same/index");

  ModelTrace bad_kept = make_trace(false);
  bad_kept.levels[1].kept[2] = 6;
  EXPECT_EQ(read_back_error(bad_kept, "kept"), "levels/1/kept");

  ModelTrace bad_query = make_trace(false);
  bad_query.queries[0].query_index = 3;
  EXPECT_EQ(read_back_error(bad_query, "query"), "queries/0/@query_index");

  ModelTrace bad_level = make_trace(false);
  bad_level.features[1].level = 2;
  EXPECT_EQ(read_back_error(bad_level, "level"), "features/encoder.0");

  EXPECT_EQ(read_back_error(make_trace(true), "good"), "");
}

TEST(TraceFileTest, TraceMustMatchTheSceneItIsUsedWith) {
  Scene scene;
  scene.dt_s = 0.1;
  Object o;
  o.id = 4;
  o.mesh.vertices.resize(3, 3);
  o.mesh.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  o.mesh.faces.resize(1, 3);
  o.mesh.faces << 0, 1, 2;
  scene.objects = {o};
  scene.trajectories.resize(1);
  scene.trajectories[0].poses.assign(6, Pose{});
  ModelTrace t = make_trace(false);
  t.levels[0].points = Points::Constant(6, 3, 0.25);
  EXPECT_NO_THROW(check_trace_matches_scene(t, scene, "t.h5"));

  ModelTrace far = t;
  far.levels[0].points(2, 0) = 5.0;  // nowhere near the triangle
  EXPECT_THROW(check_trace_matches_scene(far, scene, "t.h5"), FormatError);

  ModelTrace other_object = t;
  other_object.levels[0].object_ids[1] = 9;
  EXPECT_THROW(check_trace_matches_scene(other_object, scene, "t.h5"), FormatError);

  ModelTrace late = t;
  late.frame = 6;  // the scene has frames 0..5
  EXPECT_THROW(check_trace_matches_scene(late, scene, "t.h5"), FormatError);

  // A rollout-state trace reads predictions, which may have left their object; its objects must
  // still be the scene's.
  ModelTrace predicted = far;
  predicted.source = kTraceSourceRollout;
  EXPECT_NO_THROW(check_trace_matches_scene(predicted, scene, "t.h5"));
  predicted.levels[0].object_ids[1] = 9;
  EXPECT_THROW(check_trace_matches_scene(predicted, scene, "t.h5"), FormatError);
}

TEST(TraceFileTest, SourceRoundTripsAndOldFilesAreSceneTraces) {
  ModelTrace t = make_trace(false);
  EXPECT_EQ(t.source, kTraceSourceScene);
  t.source = kTraceSourceRollout;
  t.rollout_path = "runs/r.h5";
  const std::string path = trace_path("source");
  write_trace(t, path);
  const ModelTrace r = read_trace(path);
  EXPECT_EQ(r.source, kTraceSourceRollout);
  EXPECT_EQ(r.rollout_path, "runs/r.h5");
  t.source = "dream";
  EXPECT_THROW(write_trace(t, path), ValueError);
}

}  // namespace
}  // namespace dynscope
