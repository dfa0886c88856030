// Trace files: exact write→read round trip and clear errors for wrong files.
#include "engine/io/trace_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "engine/core/error.h"
#include "engine/io/h5_util.h"

namespace dynscope {
namespace {

std::string trace_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("dynscope_trace_" + name + ".h5")).string();
}

TraceList make_list(const std::string& name, int rows, int k, int q, int s) {
  TraceList l;
  l.name = name;
  l.query_level = q;
  l.source_level = s;
  l.index = IndexMatrix::Zero(rows, k);
  l.mask = MaskMatrix::Zero(rows, k);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < k; ++j) {
      const bool valid = (i + j) % 3 != 0;
      l.index(i, j) = valid ? (i * 7 + j) % 11 : -1;
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
    lv.lists.push_back(make_list("same", n, 4, l, l));
    if (l > 0) lv.lists.push_back(make_list("down", n, 4, l, l - 1));
    t.levels.push_back(lv);
  }
  if (mesh) {
    t.has_mesh = true;
    t.mesh.faces.resize(2, 3);
    t.mesh.faces << 0, 1, 2, 3, 4, 5;
    t.mesh.points = Points::Random(2, 3);
    t.mesh.face = {0, 1};
    t.mesh.object_ids = {4, 5};
    t.mesh.lists.push_back(make_list("senders", 2, 1, -1, -1));
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

}  // namespace
}  // namespace dynscope
