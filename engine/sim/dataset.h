// Dataset generation: many seeded scenes of one scenario written as HDF5 files plus a manifest.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/progress.h"
#include "engine/scene/mesh.h"
#include "engine/sim/shapes.h"

namespace dynscope {

/// What `dynscope generate` was asked for.
struct DatasetOptions {
  std::string scenario;      ///< One of scenario_names().
  int64_t count = 0;         ///< Number of scenes, >= 1.
  uint64_t seed = 0;         ///< Base seed; scene i uses derive_seed(seed, i).
  std::string out_dir;       ///< Created if missing.
  int jobs = 1;              ///< Worker threads, >= 1; results do not depend on it.
  std::string meshes_dir;    ///< Mesh files for "movi-c"; must be empty for other scenarios.
  double frame_rate_hz = 0;  ///< Stored frames per second; 0: the scenario's own (set_frame_rate).
  /// Tessellation of the stored meshes of primitive shapes (ScenarioOptions::mesh_density).
  MeshDensity mesh_density = MeshDensity::kDense;
  /// > 0: a trial whose target touches the zone in its first this many frames is drawn again
  /// (labelled scenarios only), so that an observer of those frames cannot read its outcome.
  int hide_outcome_frames = 0;
  /// Scene i is drawn again until its outcome is balanced_outcome(i) (labelled scenarios only).
  bool balance = false;
};

/// One written scene.
struct DatasetEntry {
  std::string file;  ///< File name inside the output directory.
  int64_t index = 0;
  uint64_t seed = 0;
  std::string split;  ///< "train", "val" or "test".
  int num_objects = 0;
  int outcome = -1;  ///< 1/0 = target touched the zone in some frame / never; -1 = no label.
  int draws = 1;  ///< Trials drawn for this scene (> 1 only with hide_outcome_frames or balance).
};

/// What generate_dataset() wrote.
struct DatasetSummary {
  std::vector<DatasetEntry> entries;  ///< In index order.
  std::string manifest_path;
  int64_t positives = 0;  ///< Entries with outcome 1.
};

/// File name of scene `index`: "<scenario>_<index zero-padded to 4 digits>.h5".
std::string scene_file_name(const std::string& scenario, int64_t index);

/// Deterministic 80/10/10 split of scene `index` of `count`: index % 10 in 0..7 "train", 8 "val",
/// 9 "test" from 10 scenes on; with 3 to 9 scenes the last is "test", the one before "val" and
/// the rest "train" (so every split has a scene); with 1 or 2 every scene is "train".
std::string split_of(int64_t index, int64_t count);

/// The outcome DatasetOptions::balance asks of scene `index`: (index + index / 10) % 2. Every
/// twenty consecutive scenes hold ten of each, and so does each split over twenty scenes (the
/// splits go by index % 10, and the pattern alternates within and between blocks of ten).
int balanced_outcome(int64_t index);

/// The seed of draw `draw` (0, 1, ...) of scene `index`: derive_seed(seed, index) for the first,
/// derive_seed(derive_seed(seed, index), draw) for the others.
uint64_t draw_seed(uint64_t seed, int64_t index, int draw);

/// Most trials one scene may draw to meet hide_outcome_frames and balance.
constexpr int kMaxDraws = 1000;

/// Largest --count of one dataset (a larger one is a typing error, not a dataset).
constexpr int64_t kMaxDatasetCount = 10000000;
/// Largest --jobs of one dataset generation.
constexpr int kMaxDatasetJobs = 1024;

/// Loads every mesh file (sorted by name) of `dir` through import_mesh. Throws IoError if the
/// directory cannot be read or holds no mesh file, or a file fails to import.
std::vector<Mesh> load_mesh_dir(const std::string& dir);

/// Checks every option before any work: known scenario, count >= 1, jobs >= 1, meshes only
/// (and always) for "movi-c", a frame rate >= 0, hide_outcome_frames and balance only for a
/// labelled scenario (hide_outcome_frames below its frame count), and an output directory that can
/// be created and written. Creates the output directory. Throws ValueError (bad option) or IoError
/// (bad path) naming it.
void check_dataset_options(const DatasetOptions& options);

/// Generates `options.count` scenes on `options.jobs` threads, writes each to
/// out_dir/scene_file_name() and then out_dir/manifest.json (scenario, count, base seed,
/// per-file seed, split, outcome, generator parameters, their frame rate and frame count as
/// stored; with hide_outcome_frames or balance the rule and each file's draws). Scene i is the
/// first of its draws (draw_seed) that meets hide_outcome_frames and balance; after kMaxDraws
/// draws that do not, generation fails naming the scene. The same options give identical files
/// whatever `jobs` is. Reports each finished scene
/// to `progress` if not null. Throws like check_dataset_options, or the first error a worker met
/// (the files written so far remain).
DatasetSummary generate_dataset(const DatasetOptions& options, Progress* progress = nullptr);

}  // namespace dynscope
