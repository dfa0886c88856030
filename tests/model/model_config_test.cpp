// ModelConfig: JSON round trip, presets, validation and clear errors.
#include "engine/model/model_config.h"

#include <gtest/gtest.h>

#include "engine/core/error.h"
#include "engine/model/hierarchy.h"

namespace dynscope {
namespace {

TEST(ModelConfigTest, JsonRoundTripKeepsEveryField) {
  ModelConfig c = ModelConfig::preset("kubric");
  c.kind = ModelKind::kGnn;
  c.target = TargetMode::kVelocity;
  c.width = 24;
  c.width_growth = 1.0;
  c.levels = 2;
  c.bottleneck_blocks = 5;
  c.stem_blocks = 1;
  c.c_mid = 6;
  c.k = 12;
  c.k_relational = 9;
  c.pos_channels = 3;
  c.layer_norm = false;
  const ModelConfig d = ModelConfig::from_json(c.to_json());
  EXPECT_EQ(d.to_json(), c.to_json());
  EXPECT_EQ(d.kind, ModelKind::kGnn);
  EXPECT_EQ(d.target, TargetMode::kVelocity);
  EXPECT_DOUBLE_EQ(d.voxel, 0.3);
  EXPECT_DOUBLE_EQ(d.radius, 0.4);
  EXPECT_FALSE(d.layer_norm);
}

// hold_static round-trips; off, it is not written, so the configurations stored in checkpoints
// and training states before it existed still compare equal.
TEST(ModelConfigTest, HoldStaticRoundTripsAndIsOmittedWhenOff) {
  ModelConfig c = ModelConfig::preset("physion");
  EXPECT_FALSE(c.hold_static);
  EXPECT_EQ(c.to_json().find("hold_static"), std::string::npos);
  EXPECT_FALSE(ModelConfig::from_json(c.to_json()).hold_static);
  c.hold_static = true;
  const ModelConfig d = ModelConfig::from_json(c.to_json());
  EXPECT_TRUE(d.hold_static);
  EXPECT_EQ(d.to_json(), c.to_json());
  EXPECT_THROW(ModelConfig::from_json(R"({"hold_static": "yes"})"), FormatError);
}

// relational_top_only round-trips, is omitted when off, and decides with the input and the kind
// which levels relate objects.
TEST(ModelConfigTest, RelationalTopOnlyRoundTripsAndPicksTheLevels) {
  ModelConfig c = ModelConfig::preset("kubric");
  EXPECT_EQ(c.to_json().find("relational_top_only"), std::string::npos);
  EXPECT_TRUE(c.has_relational(0));
  EXPECT_TRUE(c.has_relational(3));
  c.relational_top_only = true;
  const ModelConfig d = ModelConfig::from_json(c.to_json());
  EXPECT_TRUE(d.relational_top_only);
  EXPECT_EQ(d.to_json(), c.to_json());
  EXPECT_TRUE(d.has_relational(0));
  EXPECT_FALSE(d.has_relational(1));
  ModelConfig mesh = ModelConfig::preset("kubric");
  mesh.input = InputMode::kMesh;
  EXPECT_TRUE(mesh.has_relational(0));
  EXPECT_FALSE(mesh.has_relational(2));
  ModelConfig flat = ModelConfig::preset("kubric");
  flat.kind = ModelKind::kFlat;
  EXPECT_FALSE(flat.has_relational(0));
  EXPECT_THROW(ModelConfig::from_json(R"({"relational_top_only": 1})"), FormatError);
}

// interaction_spacing round-trips, is omitted when off (older checkpoints read as 0) and must be
// a finite non-negative length.
TEST(ModelConfigTest, InteractionSpacingRoundTripsAndIsChecked) {
  ModelConfig c = ModelConfig::preset("kubric");
  c.input = InputMode::kMesh;
  EXPECT_EQ(c.to_json().find("interaction_spacing"), std::string::npos);
  EXPECT_EQ(ModelConfig::from_json(c.to_json()).interaction_spacing, 0.0);
  c.interaction_spacing = 0.3;
  const ModelConfig d = ModelConfig::from_json(c.to_json());
  EXPECT_EQ(d.interaction_spacing, 0.3);
  EXPECT_EQ(d.to_json(), c.to_json());
  EXPECT_EQ(HierarchyOptions::from_config(d).interaction_spacing, 0.3);
  EXPECT_THROW(ModelConfig::from_json(R"({"interaction_spacing": -0.1})"), FormatError);
  EXPECT_THROW(ModelConfig::from_json(R"({"interaction_spacing": "fine"})"), FormatError);
}

TEST(ModelConfigTest, PaperScalesGrowByOnePointFive) {
  const ModelConfig p = ModelConfig::preset("physion");
  EXPECT_DOUBLE_EQ(p.voxel_at(0), 0.0);
  EXPECT_DOUBLE_EQ(p.voxel_at(1), 0.075);
  EXPECT_NEAR(p.voxel_at(3), 0.16875, 1e-12);
  EXPECT_NEAR(p.radius_at(3), 0.3375, 1e-12);
  const ModelConfig k = ModelConfig::preset("kubric");
  EXPECT_NEAR(k.voxel_at(3), 0.675, 1e-12);
  EXPECT_NEAR(k.radius_at(3), 1.35, 1e-12);
  EXPECT_EQ(p.channels(0), 32);
  EXPECT_EQ(p.channels(2), 128);
  EXPECT_THROW(ModelConfig::preset("mars"), ValueError);
}

TEST(ModelConfigTest, ParsesAndRejectsNames) {
  EXPECT_EQ(parse_model_kind("flat"), ModelKind::kFlat);
  EXPECT_EQ(parse_target_mode("acc"), TargetMode::kAcceleration);
  EXPECT_EQ(parse_input_mode("mesh"), InputMode::kMesh);
  EXPECT_THROW(parse_model_kind("transformer"), ValueError);
  EXPECT_THROW(parse_target_mode("pos"), ValueError);
}

TEST(ModelConfigTest, MalformedJsonNamesSourceAndField) {
  try {
    ModelConfig::from_json("{\"width\": \"wide\"}", "ckpt.pt");
    FAIL() << "expected FormatError";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.field(), "width");
    EXPECT_NE(std::string(e.what()).find("ckpt.pt"), std::string::npos);
  }
  EXPECT_THROW(ModelConfig::from_json("{not json", "x"), FormatError);
  EXPECT_THROW(ModelConfig::from_json("[1,2]", "x"), FormatError);
  try {
    ModelConfig::from_json("{\"model\": \"mlp\"}", "x");
    FAIL() << "expected FormatError";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.field(), "model");
  }
  try {
    ModelConfig::from_json("{\"levels\": 0}", "x");
    FAIL() << "expected FormatError";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.field(), "levels");
  }
}

TEST(ModelConfigTest, ValidateRejectsFlatMesh) {
  ModelConfig c;
  c.kind = ModelKind::kFlat;
  c.input = InputMode::kMesh;
  EXPECT_THROW(c.validate(), ValueError);
}

}  // namespace
}  // namespace dynscope
