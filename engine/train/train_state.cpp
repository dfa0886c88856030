// Training state archives and the recipe's progress record.
#include "engine/train/train_state.h"

#include <c10/util/Exception.h>
#include <torch/serialize.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "engine/core/error.h"
#include "engine/io/temp_file.h"

namespace dynscope {

void save_train_state(const std::string& path, torch::optim::Adam& optimizer, const RunProgress& p,
                      const std::string& config_json, int world_size) {
  TempFile temp(path);
  torch::serialize::OutputArchive archive;
  optimizer.save(archive);
  archive.write("step", c10::IValue(p.step));
  archive.write("config", c10::IValue(config_json));
  archive.write("world_size", c10::IValue(static_cast<int64_t>(world_size)));
  archive.write("wall_seconds", c10::IValue(p.wall_seconds));
  archive.write("chunks", c10::IValue(p.chunks));
  archive.write("best_step", c10::IValue(p.best_step));
  archive.write("best_val_error", c10::IValue(p.best_val_error));
  try {
    archive.save_to(temp.path());
  } catch (const c10::Error& e) {
    throw IoError(path, std::string("cannot write training state: ") + e.what_without_backtrace());
  }
  temp.commit();
}

RunProgress load_train_state(const std::string& path, torch::optim::Adam& optimizer,
                             const std::string& config_json, int world_size) {
  if (!std::filesystem::exists(path)) {
    throw IoError(path,
                  "training state missing; cannot --resume (was the run started with "
                  "this --out?)");
  }
  torch::serialize::InputArchive archive;
  try {
    archive.load_from(path);
  } catch (const c10::Error& e) {
    throw IoError(path, std::string("cannot read training state: ") + e.what_without_backtrace());
  }
  c10::IValue step, config;
  if (!archive.try_read("step", step) || !archive.try_read("config", config)) {
    throw FormatError(path, "step", "not a dynscope training state");
  }
  if (config.toStringRef() != config_json) {
    throw FormatError(path, "config",
                      "the state was saved for another architecture; start without --resume "
                      "or use the original options");
  }
  c10::IValue saved_world;
  const int64_t saved = archive.try_read("world_size", saved_world) ? saved_world.toInt() : 1;
  if (saved != world_size) {
    throw FormatError(path, "world_size",
                      "the state was saved by a run of " + std::to_string(saved) +
                          " rank(s); resume it with --nproc " + std::to_string(saved) +
                          " (this run has " + std::to_string(world_size) + ")");
  }
  optimizer.load(archive);
  RunProgress p;
  p.step = step.toInt();
  // Fields a state may lack (written before they were recorded) keep RunProgress's defaults.
  c10::IValue value;
  if (archive.try_read("wall_seconds", value)) p.wall_seconds = value.toDouble();
  if (archive.try_read("chunks", value)) p.chunks = value.toInt();
  if (archive.try_read("best_step", value)) p.best_step = value.toInt();
  if (archive.try_read("best_val_error", value)) p.best_val_error = value.toDouble();
  return p;
}

std::string progress_record(const RunProgress& p, int64_t steps, int64_t total_steps,
                            int64_t steps_per_epoch) {
  nlohmann::json j = {{"steps", steps},
                      {"total_steps", total_steps},
                      {"steps_per_epoch", steps_per_epoch},
                      {"wall_time_s", std::round(p.wall_seconds * 10.0) / 10.0},
                      {"chunks", p.chunks}};
  if (p.best_step >= 0) {
    j["best"] = {{"step", p.best_step}, {"val_rollout_error", p.best_val_error}};
  }
  return j.dump();
}

}  // namespace dynscope
