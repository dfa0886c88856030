// What a checkpoint holds, as plain data for tools that do not run the model (no torch here).
#pragma once

#include <cstdint>
#include <string>

#include "engine/model/model_config.h"
#include "engine/model/norm_stats.h"

namespace dynscope {

/// Summary of a checkpoint file.
struct CheckpointInfo {
  int64_t format_version = 0;   ///< Checkpoint layout version (currently 1).
  ModelConfig config;           ///< Architecture it was saved with.
  std::string config_json;      ///< The stored configuration text.
  NormStats stats;              ///< Normalisation statistics.
  int64_t parameter_count = 0;  ///< Trainable scalars.
};

/// Reads a checkpoint's summary (implemented with the checkpoint reader in checkpoint.cpp).
/// Throws IoError if the file is missing, truncated or not a dynscope checkpoint, FormatError
/// for a malformed configuration, Error for weights that do not fit the configuration.
CheckpointInfo read_checkpoint_info(const std::string& path);

}  // namespace dynscope
