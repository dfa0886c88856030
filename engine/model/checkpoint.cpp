// Checkpoint save/load through torch::serialize archives, with errors mapped to dynscope errors.
#include "engine/model/checkpoint.h"

#include <torch/serialize/input-archive.h>
#include <torch/serialize/output-archive.h>

#include <cstdio>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include "engine/core/error.h"
#include "engine/io/temp_file.h"
#include "engine/io/zip_check.h"

namespace dynscope {

namespace {

std::string shape_string(const torch::Tensor& t) {
  std::ostringstream os;
  os << t.sizes();
  return os.str();
}

// Every tensor a model stores, parameters and buffers, by its full module path.
std::vector<std::pair<std::string, torch::Tensor>> model_tensors(const torch::nn::Module& m) {
  std::vector<std::pair<std::string, torch::Tensor>> out;
  for (const auto& item : m.named_parameters(true)) out.emplace_back(item.key(), item.value());
  for (const auto& item : m.named_buffers(true)) out.emplace_back(item.key(), item.value());
  return out;
}

torch::serialize::InputArchive open_archive(const std::string& path) {
  // LibTorch's reader never checks the archive's CRCs: a flipped bit in a weight would load.
  // Verified first, so a corrupt checkpoint is an error and not a silently different model.
  verify_zip_archive(path);
  torch::serialize::InputArchive archive;
  try {
    archive.load_from(path);
  } catch (const c10::Error& e) {
    throw IoError(path, std::string("cannot read checkpoint (missing, corrupt or truncated): ") +
                            e.what_without_backtrace());
  }
  c10::IValue format;
  bool has_format = false;
  try {
    has_format = archive.try_read("format", format);
  } catch (const c10::Error& e) {
    throw IoError(path, std::string("cannot read checkpoint: ") + e.what_without_backtrace());
  }
  if (!has_format || !format.isInt()) {
    throw FormatError(path, "format", "not a dynscope checkpoint");
  }
  if (format.toInt() != kCheckpointFormat) {
    throw FormatError(path, "format",
                      "unsupported checkpoint version " + std::to_string(format.toInt()) +
                          " (expected " + std::to_string(kCheckpointFormat) + ")");
  }
  return archive;
}

std::string read_config_text(torch::serialize::InputArchive& archive, const std::string& path) {
  c10::IValue config;
  bool ok = false;
  try {
    ok = archive.try_read("config", config);
  } catch (const c10::Error& e) {
    throw IoError(path, std::string("cannot read config: ") + e.what_without_backtrace());
  }
  if (!ok || !config.isString()) throw FormatError(path, "config", "missing or not a string");
  return config.toStringRef();
}

// Reads and checks every tensor first, then copies, so a mismatch leaves the model unchanged.
void load_weights(torch::serialize::InputArchive& archive, const std::string& path,
                  torch::nn::Module& model) {
  const auto tensors = model_tensors(model);
  std::set<std::string> expected{"format", "config"};
  std::vector<torch::Tensor> values;
  values.reserve(tensors.size());
  for (const auto& [name, target] : tensors) {
    expected.insert(name);
    torch::Tensor value;
    bool found = false;
    try {
      found = archive.try_read(name, value);
    } catch (const c10::Error& e) {
      throw IoError(path, "cannot read weight '" + name + "': " + e.what_without_backtrace());
    }
    if (!found) {
      throw Error(path + ": architecture mismatch: weight '" + name +
                  "' of the model is missing from the checkpoint");
    }
    if (value.sizes() != target.sizes() || value.scalar_type() != target.scalar_type()) {
      throw Error(path + ": architecture mismatch: weight '" + name + "' has shape " +
                  shape_string(value) + " in the checkpoint but " + shape_string(target) +
                  " in the model");
    }
    values.push_back(value);
  }
  for (const std::string& key : archive.keys()) {
    if (!expected.count(key)) {
      throw Error(path + ": architecture mismatch: checkpoint weight '" + key +
                  "' does not exist in the model");
    }
  }
  torch::NoGradGuard no_grad;
  for (size_t i = 0; i < tensors.size(); ++i) {
    torch::Tensor target = tensors[i].second;
    target.copy_(values[i].to(target.device()));
  }
}

}  // namespace

void save_checkpoint(const std::string& path, const DynamicsModel& model) {
  TempFile temp(path);
  try {
    torch::serialize::OutputArchive archive;
    archive.write("format", c10::IValue(kCheckpointFormat));
    archive.write("config", c10::IValue(model->config().to_json()));
    for (const auto& item : model->named_parameters(true)) {
      archive.write(item.key(), item.value().detach().to(torch::kCPU));
    }
    for (const auto& item : model->named_buffers(true)) {
      archive.write(item.key(), item.value().detach().to(torch::kCPU), /*is_buffer=*/true);
    }
    archive.save_to(temp.path());
  } catch (const c10::Error& e) {
    throw IoError(path, std::string("cannot write checkpoint: ") + e.what_without_backtrace());
  }
  temp.commit();
}

DynamicsModel load_checkpoint(const std::string& path) {
  torch::serialize::InputArchive archive = open_archive(path);
  const ModelConfig config = ModelConfig::from_json(read_config_text(archive, path), path);
  DynamicsModel model(config);
  load_weights(archive, path, *model);
  return model;
}

void load_checkpoint_weights(const std::string& path, DynamicsModel& model) {
  torch::serialize::InputArchive archive = open_archive(path);
  load_weights(archive, path, *model);
}

CheckpointInfo read_checkpoint_info(const std::string& path) {
  torch::serialize::InputArchive archive = open_archive(path);
  CheckpointInfo info;
  info.format_version = kCheckpointFormat;
  info.config_json = read_config_text(archive, path);
  info.config = ModelConfig::from_json(info.config_json, path);
  DynamicsModel model(info.config);
  load_weights(archive, path, *model);
  info.stats = model->stats();
  info.parameter_count = parameter_count(*model);
  return info;
}

}  // namespace dynscope
