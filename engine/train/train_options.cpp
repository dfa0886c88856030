// TrainOptions JSON round trip and resolution against the dataset scale.
#include "engine/train/train_options.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>

#include "engine/core/error.h"
#include "engine/core/threads.h"
#include "engine/io/temp_file.h"
#include "engine/train/velocity_noise.h"

namespace dynscope {
namespace {

// Largest value of an integer recipe field: seeds are uint64, max_steps and dataset counts int64,
// every other integer field an `int`. No integer field of a recipe may be negative.
double max_integer_field(const std::string& key) {
  if (key == "seed" || key == "init_seed") return 18446744073709551615.0;
  if (key == "max_steps" || key == "count") return 9223372036854775807.0;
  return std::numeric_limits<int32_t>::max();
}

// Checks the numbers of a recipe against the fields of `reference` (the JSON of default options:
// an integer there is an integer field), before nlohmann's conversions truncate 3.7 to 3, wrap
// -1 into a huge seed or 2^32 + 1 into 1. Throws FormatError(source, "path.to.field", ...) naming
// the accepted values.
void check_numbers(const nlohmann::json& given, const nlohmann::json& reference,
                   const std::string& source, const std::string& prefix) {
  for (auto it = given.begin(); it != given.end(); ++it) {
    const std::string field = prefix + it.key();
    const nlohmann::json& value = it.value();
    if (!reference.contains(it.key())) continue;
    const nlohmann::json& ref = reference.at(it.key());
    if (ref.is_object() && value.is_object()) {
      check_numbers(value, ref, source, field + ".");
      continue;
    }
    if (!value.is_number()) continue;  // wrong types are reported when the field is read
    const double v = value.get<double>();
    if (!std::isfinite(v)) throw FormatError(source, field, "must be a finite number");
    if (!ref.is_number_integer()) continue;
    const double hi = max_integer_field(it.key());
    if (v != std::floor(v) || v < 0 || v > hi) {
      const std::string max = hi > 1e19  ? "18446744073709551615"
                              : hi > 3e9 ? "9223372036854775807"
                                         : "2147483647";
      throw FormatError(source, field,
                        "must be an integer in [0, " + max + "], got " + value.dump());
    }
  }
}

}  // namespace

std::string TrainOptions::to_json() const {
  nlohmann::json j;
  if (!description.empty()) j["description"] = description;
  if (data_dirs.size() == 1) {
    j["data"] = data_dirs.front();
  } else {
    j["data"] = data_dirs;
  }
  if (!datasets.empty()) {
    nlohmann::json list = nlohmann::json::array();
    for (const DatasetRecipe& d : datasets) {
      nlohmann::json entry = {
          {"out", d.out}, {"scenario", d.scenario}, {"count", d.count}, {"seed", d.seed}};
      if (d.frame_rate_hz != 0) entry["frame_rate_hz"] = d.frame_rate_hz;
      if (d.hide_outcome_frames != 0) entry["hide_outcome_frames"] = d.hide_outcome_frames;
      if (d.balance) entry["balance"] = true;
      if (d.mesh_density != "dense") entry["mesh_density"] = d.mesh_density;
      list.push_back(entry);
    }
    j["datasets"] = list;
  }
  j["out"] = out;
  j["scale"] = scale;
  j["model_config"] = nlohmann::json::parse(model.to_json());
  j["set_voxel"] = set_voxel;
  j["set_radius"] = set_radius;
  j["faces"] = faces;
  j["sampling"] = {{"voxel", sampling.voxel},
                   {"oversample", sampling.oversample},
                   {"seed", sampling.seed},
                   {"input", to_string(sampling.input)}};
  j["epochs"] = epochs;
  j["samples_per_scene"] = samples_per_scene;
  j["batch"] = batch;
  j["world_size"] = world_size;
  j["effective_batch"] = static_cast<int64_t>(batch) * world_size;
  j["lr"] = lr;
  j["lr_schedule"] = lr_schedule;
  j["noise_std"] = noise_std;
  j["noise_mode"] = noise_mode;
  j["huber_delta"] = huber_delta;
  j["pushforward_steps"] = pushforward_steps;
  j["max_steps"] = max_steps;
  j["checkpoint_every"] = checkpoint_every;
  j["val_scenes"] = val_scenes;
  j["val_frames"] = val_frames;
  j["threads"] = threads;
  j["seed"] = seed;
  if (init_seed) j["init_seed"] = *init_seed;
  j["log"] = log_csv;
  j["keep_epochs"] = keep_epochs;
  if (!notes_json.empty()) j["notes"] = nlohmann::json::parse(notes_json);
  if (!progress_json.empty()) j["progress"] = nlohmann::json::parse(progress_json);
  return j.dump(2) + "\n";
}

TrainOptions TrainOptions::from_json(const std::string& text, const std::string& source,
                                     const TrainOptions& base) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(source, "recipe", std::string("malformed JSON: ") + e.what());
  }
  if (!j.is_object()) throw FormatError(source, "recipe", "expected a JSON object");
  nlohmann::json reference = nlohmann::json::parse(TrainOptions().to_json());
  reference["init_seed"] = uint64_t{0};  // written only when set
  check_numbers(j, reference, source, "");
  if (j.contains("datasets") && j.at("datasets").is_array()) {
    const nlohmann::json entry = {{"count", int64_t{1}},
                                  {"seed", uint64_t{0}},
                                  {"frame_rate_hz", 0.0},
                                  {"hide_outcome_frames", 0}};
    for (size_t i = 0; i < j.at("datasets").size(); ++i) {
      const nlohmann::json& d = j.at("datasets").at(i);
      if (d.is_object()) check_numbers(d, entry, source, "datasets[" + std::to_string(i) + "].");
    }
  }
  TrainOptions o = base;
  std::string field;
  try {
    auto get = [&](const char* name, auto& value) {
      field = name;
      if (j.contains(name)) value = j.at(name).get<std::decay_t<decltype(value)>>();
    };
    field = "data";
    if (j.contains("data")) {
      if (j.at("data").is_array()) {
        o.data_dirs = j.at("data").get<std::vector<std::string>>();
      } else {
        o.data_dirs = {j.at("data").get<std::string>()};
      }
    }
    get("description", o.description);
    field = "datasets";
    if (j.contains("datasets")) {
      o.datasets.clear();
      for (const auto& d : j.at("datasets")) {
        DatasetRecipe r;
        r.out = d.at("out").get<std::string>();
        r.scenario = d.at("scenario").get<std::string>();
        r.count = d.at("count").get<int64_t>();
        r.seed = d.value("seed", uint64_t{0});
        r.frame_rate_hz = d.value("frame_rate_hz", 0.0);
        r.hide_outcome_frames = d.value("hide_outcome_frames", 0);
        r.balance = d.value("balance", false);
        r.mesh_density = d.value("mesh_density", std::string("dense"));
        o.datasets.push_back(r);
      }
    }
    field = "notes";
    if (j.contains("notes")) o.notes_json = j.at("notes").dump();
    field = "progress";
    if (j.contains("progress")) {
      if (!j.at("progress").is_object()) throw ValueError("progress", "must be a JSON object");
      o.progress_json = j.at("progress").dump();
    }
    get("out", o.out);
    get("scale", o.scale);
    field = "model_config";
    if (j.contains("model_config")) {
      o.model = ModelConfig::from_json(j.at("model_config").dump(), source);
    }
    get("set_voxel", o.set_voxel);
    get("set_radius", o.set_radius);
    get("faces", o.faces);
    field = "sampling";
    if (j.contains("sampling")) {
      const auto& s = j.at("sampling");
      o.sampling.voxel = s.value("voxel", o.sampling.voxel);
      o.sampling.oversample = s.value("oversample", o.sampling.oversample);
      o.sampling.seed = s.value("seed", o.sampling.seed);
      if (s.contains("input"))
        o.sampling.input = parse_input_mode(s.at("input").get<std::string>());
    }
    get("epochs", o.epochs);
    get("samples_per_scene", o.samples_per_scene);
    get("batch", o.batch);
    get("world_size", o.world_size);
    if (j.contains("effective_batch")) {
      field = "effective_batch";
      if (j["effective_batch"].get<int64_t>() != static_cast<int64_t>(o.batch) * o.world_size) {
        throw ValueError("effective_batch", "must equal batch × world_size");
      }
    }
    get("lr", o.lr);
    get("lr_schedule", o.lr_schedule);
    get("noise_std", o.noise_std);
    get("noise_mode", o.noise_mode);
    get("keep_epochs", o.keep_epochs);
    get("huber_delta", o.huber_delta);
    get("pushforward_steps", o.pushforward_steps);
    get("max_steps", o.max_steps);
    get("checkpoint_every", o.checkpoint_every);
    get("val_scenes", o.val_scenes);
    get("val_frames", o.val_frames);
    get("threads", o.threads);
    get("seed", o.seed);
    field = "init_seed";
    if (j.contains("init_seed")) o.init_seed = j.at("init_seed").get<uint64_t>();
    get("log", o.log_csv);
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(source, field, std::string("wrong type: ") + e.what());
  } catch (const ValueError& e) {
    throw FormatError(source, field, e.what());
  }
  return o;
}

TrainOptions TrainOptions::from_json(const std::string& text, const std::string& source) {
  return from_json(text, source, TrainOptions());
}

void TrainOptions::resolve(const std::string& scenario) {
  if (scale.empty()) scale = default_scale_preset(scenario);
  const ModelConfig preset = ModelConfig::preset(scale);
  const bool kubric = scale == "kubric";
  if (!set_voxel) model.voxel = preset.voxel;
  if (!set_radius) {
    model.radius = preset.radius;
    model.interaction_threshold = preset.interaction_threshold;
  }
  if (epochs == 0) epochs = kubric ? 15 : 30;
  if (samples_per_scene == 0) samples_per_scene = kubric ? 2 : 8;
  if (lr == 0) lr = kubric ? 5e-3 : 1e-3;
  // The points model can run on mesh vertices: that is mesh input without face reasoning.
  // A resolved recipe of a faces-off mesh run has model input "points" over mesh sampling.
  sampling.input = model.input == InputMode::kMesh || (!faces && sampling.input == InputMode::kMesh)
                       ? InputMode::kMesh
                       : InputMode::kPoints;
  if (model.input == InputMode::kMesh && !faces) model.input = InputMode::kPoints;
  if (sampling.voxel == 0) sampling.voxel = default_sampling_voxel(scenario);
  model.validate();
  // Ranges: a value outside is a typing error (or a corrupt recipe), never a run to start.
  auto in_range = [](const char* name, double v, double lo, double hi, bool lo_open) {
    if (std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi) return;
    char text[160];
    std::snprintf(text, sizeof text, "must be a finite number in %s%.6g, %.6g], got %.6g",
                  lo_open ? "(" : "[", lo, hi, v);
    throw ValueError(name, text);
  };
  in_range("epochs", epochs, 1, 1e6, false);
  in_range("samples-per-scene", samples_per_scene, 1, 1e6, false);
  in_range("batch", batch, 1, 65536, false);
  in_range("world_size", world_size, 1, 65536, false);
  in_range("lr", lr, 0, 10, true);
  if (lr_schedule != "constant" && lr_schedule != "cosine") {
    throw ValueError("lr-schedule", "must be constant or cosine, got '" + lr_schedule + "'");
  }
  in_range("huber-delta", huber_delta, 0, 1e6, true);
  in_range("checkpoint-every", checkpoint_every, 1, 1e9, false);
  in_range("pushforward-steps", pushforward_steps, 0, 1e6, false);
  in_range("val-frames", val_frames, 1, 1e6, false);
  in_range("noise-std", noise_std, 0, 1e3, false);
  parse_noise_mode(noise_mode);  // throws ValueError("noise-mode", ...) for other names
  in_range("max-steps", static_cast<double>(max_steps), 0, 1e15, false);
  in_range("val-scenes", val_scenes, 0, 1e6, false);
  in_range("threads", threads, 0, kMaxComputeThreads, false);
  in_range("sampling.voxel", sampling.voxel, 0, 1e6, true);
  in_range("sampling.oversample", sampling.oversample, 0, 1e4, true);
  in_range("model_config.width", model.width, 1, 4096, false);
  in_range("model_config.k", model.k, 1, 1024, false);
  in_range("model_config.k_relational", model.k_relational, 1, 1024, false);
  in_range("model_config.c_mid", model.c_mid, 1, 1024, false);
  in_range("model_config.bottleneck_blocks", model.bottleneck_blocks, 0, 64, false);
  in_range("model_config.stem_blocks", model.stem_blocks, 0, 64, false);
  if (out.empty()) throw ValueError("out", "no checkpoint path given");
  if (data_dirs.empty()) throw ValueError("data", "no dataset directory given");
  for (const DatasetRecipe& d : datasets) {
    if (d.out.empty() || d.scenario.empty() || d.count < 1) {
      throw ValueError("datasets", "every entry needs out, scenario and count >= 1");
    }
  }
}

double learning_rate_at(const TrainOptions& o, int64_t step, int64_t total) {
  if (o.lr_schedule != "cosine" || total <= 1) return o.lr;
  const double progress =
      std::clamp(static_cast<double>(step) / static_cast<double>(total - 1), 0.0, 1.0);
  const double pi = std::acos(-1.0);
  return o.lr * (kCosineFinalFraction +
                 (1.0 - kCosineFinalFraction) * 0.5 * (1.0 + std::cos(pi * progress)));
}

std::string train_state_path(const std::string& checkpoint) { return checkpoint + ".state"; }

namespace {
// X.pt -> X + suffix + ".pt"; any other name gets suffix + ".pt" appended.
std::string sibling_checkpoint(const std::string& checkpoint, const std::string& suffix) {
  const std::string ext = ".pt";
  if (checkpoint.size() > ext.size() &&
      checkpoint.compare(checkpoint.size() - ext.size(), ext.size(), ext) == 0) {
    return checkpoint.substr(0, checkpoint.size() - ext.size()) + suffix + ext;
  }
  return checkpoint + suffix + ext;
}
}  // namespace

std::string best_checkpoint_path(const std::string& checkpoint) {
  return sibling_checkpoint(checkpoint, ".best");
}

std::string epoch_checkpoint_path(const std::string& checkpoint, int epoch) {
  char number[16];
  std::snprintf(number, sizeof number, "%02d", epoch);
  return sibling_checkpoint(checkpoint, std::string(".epoch") + number);
}
std::string recipe_path(const std::string& checkpoint) { return checkpoint + ".recipe.json"; }

SamplingOptions checkpoint_sampling(const std::string& checkpoint, const ModelConfig& config) {
  const std::string path = recipe_path(checkpoint);
  SamplingOptions s;
  s.input = config.input;
  if (!std::filesystem::exists(path)) return s;
  return TrainOptions::from_json(read_text_file(path), path).sampling;
}

}  // namespace dynscope
