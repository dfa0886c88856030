// Checkpoint files: weights, architecture config (JSON) and normalisation statistics in one file.
#pragma once

#include <string>

#include "engine/model/checkpoint_info.h"
#include "engine/model/dynamics_model.h"

namespace dynscope {

/// Current checkpoint layout version, stored under the key "format".
constexpr int64_t kCheckpointFormat = 1;

/// Writes `model` (weights and buffers by their module paths, "config" JSON, "format") to `path`
/// through a temporary file renamed into place, so an existing file is never left half written.
/// Throws IoError if the file cannot be written.
void save_checkpoint(const std::string& path, const DynamicsModel& model);

/// Builds the model described by the stored config and loads its weights and statistics.
/// The archive's structure and the CRC-32 of every member are verified first. Throws IoError for
/// a missing, truncated or foreign file, FormatError for a bad config or a corrupt archive (the
/// member whose CRC fails), and Error naming the key for weights that do not match the
/// architecture.
DynamicsModel load_checkpoint(const std::string& path);

/// Loads the weights and statistics of `path` into an existing model. Throws Error naming the
/// first missing, unexpected or differently shaped key when the architectures differ (the
/// model is unchanged then), IoError for an unreadable file.
void load_checkpoint_weights(const std::string& path, DynamicsModel& model);

}  // namespace dynscope
