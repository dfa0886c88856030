// ModelConfig: presets, derived sizes, validation and the JSON round trip.
#include "engine/model/model_config.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "engine/core/error.h"

namespace dynscope {

std::string to_string(ModelKind kind) {
  switch (kind) {
    case ModelKind::kPointConv:
      return "pointconv";
    case ModelKind::kGnn:
      return "gnn";
    case ModelKind::kFlat:
      return "flat";
  }
  return "unknown";
}

ModelKind parse_model_kind(const std::string& name) {
  if (name == "pointconv") return ModelKind::kPointConv;
  if (name == "gnn") return ModelKind::kGnn;
  if (name == "flat") return ModelKind::kFlat;
  throw ValueError("model", "unknown model kind '" + name + "' (expected pointconv|gnn|flat)");
}

std::string to_string(TargetMode mode) { return mode == TargetMode::kAcceleration ? "acc" : "vel"; }

TargetMode parse_target_mode(const std::string& name) {
  if (name == "acc") return TargetMode::kAcceleration;
  if (name == "vel") return TargetMode::kVelocity;
  throw ValueError("target", "unknown target '" + name + "' (expected acc|vel)");
}

std::string to_string(InputMode mode) { return mode == InputMode::kPoints ? "points" : "mesh"; }

InputMode parse_input_mode(const std::string& name) {
  if (name == "points") return InputMode::kPoints;
  if (name == "mesh") return InputMode::kMesh;
  throw ValueError("input", "unknown input mode '" + name + "' (expected points|mesh)");
}

ModelConfig ModelConfig::preset(const std::string& name) {
  ModelConfig config;
  if (name == "physion") {
    config.voxel = 0.075;
    config.radius = 0.1;
    config.interaction_threshold = 0.1;
  } else if (name == "kubric") {
    config.voxel = 0.3;
    config.radius = 0.4;
    config.interaction_threshold = 0.4;
  } else {
    throw ValueError("scale", "unknown preset '" + name + "' (expected physion|kubric)");
  }
  return config;
}

int ModelConfig::channels(int level) const {
  return static_cast<int>(std::lround(width * std::pow(width_growth, level)));
}

double ModelConfig::voxel_at(int level) const {
  return level <= 0 ? 0.0 : voxel * std::pow(growth, level - 1);
}

double ModelConfig::radius_at(int level) const { return radius * std::pow(growth, level); }

bool relates_objects_at(int level, bool object_centric, bool point_input,
                        bool relational_top_only) {
  return object_centric && (level == 0 || (point_input && !relational_top_only));
}

bool ModelConfig::has_relational(int level) const {
  return relates_objects_at(level, kind != ModelKind::kFlat, input == InputMode::kPoints,
                            relational_top_only);
}

void ModelConfig::validate() const {
  auto require = [](bool ok, const char* field, const std::string& message) {
    if (!ok) throw ValueError(field, message);
  };
  require(width >= 1, "width", "must be >= 1, got " + std::to_string(width));
  require(width_growth >= 1.0 && width_growth <= 4.0, "width_growth",
          "must be in [1, 4], got " + std::to_string(width_growth));
  require(levels >= 1 && levels <= 8, "levels", "must be in [1, 8], got " + std::to_string(levels));
  require(bottleneck_blocks >= 0, "bottleneck_blocks", "must be >= 0");
  require(stem_blocks >= 0, "stem_blocks", "must be >= 0");
  require(c_mid >= 1, "c_mid", "must be >= 1, got " + std::to_string(c_mid));
  require(k >= 1, "k", "must be >= 1, got " + std::to_string(k));
  require(k_relational >= 1, "k_relational", "must be >= 1");
  require(pos_channels >= 0, "pos_channels", "must be >= 0");
  require(bottleneck_divisor >= 1, "bottleneck_divisor", "must be >= 1");
  require(voxel > 0 && std::isfinite(voxel), "voxel", "must be > 0");
  require(radius > 0 && std::isfinite(radius), "radius", "must be > 0");
  require(growth >= 1.0 && std::isfinite(growth), "growth", "must be >= 1");
  require(interaction_threshold > 0, "interaction_threshold", "must be > 0");
  require(interaction_lattice >= 1, "interaction_lattice", "must be >= 1");
  require(interaction_spacing >= 0 && std::isfinite(interaction_spacing), "interaction_spacing",
          "must be >= 0 (0: the same lattice on every face)");
  require(!(kind != ModelKind::kPointConv && input == InputMode::kMesh), "input",
          "mesh input (interaction-point relational path) is implemented for the pointconv "
          "model only");
}

std::string ModelConfig::to_json() const {
  nlohmann::json j;
  j["model"] = to_string(kind);
  j["target"] = to_string(target);
  j["input"] = to_string(input);
  j["width"] = width;
  j["width_growth"] = width_growth;
  j["levels"] = levels;
  j["bottleneck_blocks"] = bottleneck_blocks;
  j["stem_blocks"] = stem_blocks;
  j["c_mid"] = c_mid;
  j["k"] = k;
  j["k_relational"] = k_relational;
  j["pos_channels"] = pos_channels;
  j["bottleneck_divisor"] = bottleneck_divisor;
  j["voxel"] = voxel;
  j["radius"] = radius;
  j["growth"] = growth;
  j["layer_norm"] = layer_norm;
  j["interaction_threshold"] = interaction_threshold;
  j["interaction_lattice"] = interaction_lattice;
  if (interaction_spacing > 0) j["interaction_spacing"] = interaction_spacing;
  if (hold_static) j["hold_static"] = true;
  if (relational_top_only) j["relational_top_only"] = true;
  return j.dump();
}

namespace {

template <typename T>
void read_field(const nlohmann::json& j, const char* field, const std::string& source, T& out) {
  auto it = j.find(field);
  if (it == j.end()) return;
  try {
    out = it->get<T>();
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(source, field, std::string("wrong type: ") + e.what());
  }
}

template <typename Enum>
void read_enum(const nlohmann::json& j, const char* field, const std::string& source,
               Enum (*parse)(const std::string&), Enum& out) {
  std::string name;
  read_field(j, field, source, name);
  if (name.empty()) return;
  try {
    out = parse(name);
  } catch (const ValueError& e) {
    throw FormatError(source, field, e.what());
  }
}

}  // namespace

ModelConfig ModelConfig::from_json(const std::string& text, const std::string& source) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(source, "config", std::string("malformed JSON: ") + e.what());
  }
  if (!j.is_object()) throw FormatError(source, "config", "expected a JSON object");
  ModelConfig c;
  read_enum(j, "model", source, &parse_model_kind, c.kind);
  read_enum(j, "target", source, &parse_target_mode, c.target);
  read_enum(j, "input", source, &parse_input_mode, c.input);
  read_field(j, "width", source, c.width);
  read_field(j, "width_growth", source, c.width_growth);
  read_field(j, "levels", source, c.levels);
  read_field(j, "bottleneck_blocks", source, c.bottleneck_blocks);
  read_field(j, "stem_blocks", source, c.stem_blocks);
  read_field(j, "c_mid", source, c.c_mid);
  read_field(j, "k", source, c.k);
  read_field(j, "k_relational", source, c.k_relational);
  read_field(j, "pos_channels", source, c.pos_channels);
  read_field(j, "bottleneck_divisor", source, c.bottleneck_divisor);
  read_field(j, "voxel", source, c.voxel);
  read_field(j, "radius", source, c.radius);
  read_field(j, "growth", source, c.growth);
  read_field(j, "layer_norm", source, c.layer_norm);
  read_field(j, "interaction_threshold", source, c.interaction_threshold);
  read_field(j, "interaction_lattice", source, c.interaction_lattice);
  read_field(j, "interaction_spacing", source, c.interaction_spacing);
  read_field(j, "hold_static", source, c.hold_static);
  read_field(j, "relational_top_only", source, c.relational_top_only);
  try {
    c.validate();
  } catch (const ValueError& e) {
    throw FormatError(source, e.name(), e.what());
  }
  return c;
}

}  // namespace dynscope
