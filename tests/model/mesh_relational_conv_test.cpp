// Mesh relational path: zero without interactions, a whole mesh model runs and trains.
#include "engine/model/mesh_relational_conv.h"

#include <gtest/gtest.h>
#include <torch/types.h>
#include <torch/utils.h>

#include "engine/core/error.h"
#include "engine/model/dynamics_model.h"
#include "tests/model/model_test_util.h"

namespace dynscope {
namespace {

MeshTensors mesh_tensors(const testing::TestMesh& m, double gap_threshold) {
  HierarchyOptions o;
  o.levels = 1;
  o.k = 4;
  o.interaction_threshold = gap_threshold;
  return to_tensors(build_mesh_hierarchy(m.vertices, m.ids, m.faces, o)).levels[0].mesh;
}

TEST(MeshRelationalConvTest, OnlyVerticesOfInteractingFacesReceiveFeatures) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(1);
  const auto m = testing::make_two_boxes(0.05);
  const MeshTensors mesh = mesh_tensors(m, 0.1);
  MeshRelationalConv conv(MeshRelationalConvOptions(5, 6).c_mid(4).pos_channels(3));
  const torch::Tensor vertices = points_to_tensor(m.vertices);
  const torch::Tensor y = conv->forward(torch::randn({vertices.size(0), 5}), vertices, mesh);
  ASSERT_EQ(y.sizes(), (std::vector<int64_t>{vertices.size(0), 6}));
  const torch::Tensor has = mesh.vertex_points.valid_count() > 0;
  ASSERT_TRUE(has.any().item<bool>());
  const torch::Tensor silent = y.index({has.logical_not()});
  EXPECT_TRUE(torch::equal(silent, torch::zeros_like(silent)));
  EXPECT_GT(y.index({has}).abs().sum().item<float>(), 0.0f);

  const MeshTensors none = mesh_tensors(testing::make_two_boxes(1.0), 0.1);
  const torch::Tensor z = conv->forward(torch::randn({vertices.size(0), 5}), vertices, none);
  EXPECT_TRUE(torch::equal(z, torch::zeros_like(z)));
}

TEST(MeshRelationalConvTest, MeshModelRunsAndEveryParameterGetsAGradient) {
  torch::manual_seed(2);
  ModelConfig c = testing::tiny_config();
  c.input = InputMode::kMesh;
  c.levels = 2;
  c.voxel = 0.6;
  c.stem_blocks = 1;
  c.interaction_threshold = 0.1;
  const auto m = testing::make_two_boxes(0.05);
  PointState st;
  st.position = m.vertices;
  st.velocity = Points::Constant(m.vertices.rows(), 3, 0.01);
  st.prev_velocity = Points::Zero(m.vertices.rows(), 3);
  st.object_ids = m.ids;
  st.faces = m.faces;
  DynamicsModel model(c);
  const Hierarchy h = model->build_hierarchy(st);
  ASSERT_TRUE(h.has_mesh);
  EXPECT_EQ(h.levels[0].relational.rows(), 0) << "mesh input uses no point relational lists";
  const ModelInput in = make_model_input(st, h);
  model->predict_delta(in).square().sum().backward();
  for (const auto& p : model->named_parameters()) {
    ASSERT_TRUE(p.value().grad().defined()) << p.key();
    EXPECT_TRUE(torch::isfinite(p.value().grad()).all().item<bool>()) << p.key();
  }
  EXPECT_TRUE(
      model->named_parameters().contains("unet.stem.0.relational.conv.to_vertex.linear.weight"));
  EXPECT_FALSE(model->named_parameters().contains("unet.encoder.0.relational.reduce.weight"));
  EXPECT_TRUE(model->predict_next(st).allFinite());

  PointState no_faces = st;
  no_faces.faces = Faces(0, 3);
  EXPECT_THROW(model->build_hierarchy(no_faces), ValueError);
}

}  // namespace
}  // namespace dynscope
