// Dataset generation: worker threads simulate seeded scenes, write HDF5 files and a JSON manifest.
#include "engine/sim/dataset.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

#include "engine/core/error.h"
#include "engine/core/log.h"
#include "engine/core/rng.h"
#include "engine/io/mesh_import.h"
#include "engine/io/scene_file.h"
#include "engine/io/temp_file.h"
#include "engine/sim/scenario.h"
#include "engine/sim/simulation.h"

namespace dynscope {
namespace {

namespace fs = std::filesystem;

constexpr const char* kManifestName = "manifest.json";

// Sorted paths of the files in `dir` that assimp can import.
std::vector<std::string> mesh_files_in(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw IoError(dir, "mesh directory does not exist");
  std::vector<std::string> files;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->is_regular_file(ec) && is_mesh_file(it->path().string())) {
      files.push_back(it->path().string());
    }
  }
  if (ec) throw IoError(dir, "cannot list directory: " + ec.message());
  if (files.empty()) throw IoError(dir, "holds no mesh files (OBJ, PLY, STL, glTF, ...)");
  std::sort(files.begin(), files.end());
  return files;
}

// True when scenes are selected among several draws (hide_outcome_frames or balance).
bool selects_draws(const DatasetOptions& options) {
  return options.hide_outcome_frames > 0 || options.balance;
}

// True when `scene` meets the selection options as scene `index`.
bool meets_selection(const Scene& scene, const DatasetOptions& options, int64_t index) {
  const int first = first_labelled_contact(scene);
  if (options.hide_outcome_frames > 0 && first >= 0 && first < options.hide_outcome_frames) {
    return false;
  }
  return !options.balance || (first >= 0 ? 1 : 0) == balanced_outcome(index);
}

// What scene `index` must meet, in words (for the error when no draw does).
std::string selection_text(const DatasetOptions& options, int64_t index) {
  std::string text;
  if (options.hide_outcome_frames > 0) {
    text = "no contact in the first " + std::to_string(options.hide_outcome_frames) + " frames";
  }
  if (options.balance) {
    text += (text.empty() ? "" : " and ") + std::string("outcome ") +
            std::to_string(balanced_outcome(index));
  }
  return text;
}

std::string manifest_text(const DatasetOptions& options, const std::vector<std::string>& mesh_files,
                          const SimSetup& first, const DatasetSummary& summary) {
  using nlohmann::json;
  json m;
  m["format"] = "dynscope-dataset";
  m["format_version"] = 1;
  m["scenario"] = options.scenario;
  m["count"] = options.count;
  m["seed"] = options.seed;
  m["seed_rule"] = "scene i uses derive_seed(seed, i) (engine/core/rng.h)";
  m["parameters"] = json::parse(scenario_parameters_json(options.scenario));
  // The rate and frame count as stored (a --frame-rate replaces the scenario's own).
  m["parameters"]["frame_rate_hz"] = first.physics_rate_hz / first.substeps_per_frame;
  m["parameters"]["num_frames"] = first.num_frames;
  m["parameters"]["mesh_density"] = mesh_density_name(first.mesh_density);
  if (!mesh_files.empty()) m["meshes"] = mesh_files;
  const bool labelled = scenario_has_contact_label(options.scenario);
  if (labelled) {
    m["label"] = "target_contacting_zone";
    m["positives"] = summary.positives;
  }
  const bool selected = selects_draws(options);
  if (selected) {
    m["selection"] = {
        {"hide_outcome_frames", options.hide_outcome_frames},
        {"balance", options.balance},
        {"rule",
         "scene i is the first of draws 0, 1, ... (seed derive_seed(seed, i), then "
         "derive_seed(derive_seed(seed, i), draw)) whose target does not touch the zone in its "
         "first hide_outcome_frames frames and, with balance, whose outcome is (i + i / 10) % 2"}};
  }
  json files = json::array();
  json split = {{"train", json::array()}, {"val", json::array()}, {"test", json::array()}};
  for (const DatasetEntry& e : summary.entries) {
    json f = {{"file", e.file},
              {"index", e.index},
              {"seed", e.seed},
              {"split", e.split},
              {"num_objects", e.num_objects}};
    if (labelled) f["outcome"] = e.outcome;
    if (selected) f["draws"] = e.draws;
    files.push_back(f);
    split[e.split].push_back(e.file);
  }
  m["files"] = files;
  m["split"] = split;
  m["split_rule"] =
      "index % 10: 0-7 train, 8 val, 9 test (3 to 9 scenes: last test, one before val)";
  return m.dump(2) + "\n";
}

}  // namespace

std::string scene_file_name(const std::string& scenario, int64_t index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "_%04lld.h5", static_cast<long long>(index));
  return scenario + buf;
}

std::string split_of(int64_t index, int64_t count) {
  if (count < 10) {
    if (count < 3 || index < count - 2) return "train";
    return index == count - 2 ? "val" : "test";
  }
  const int64_t r = index % 10;
  return r < 8 ? "train" : (r == 8 ? "val" : "test");
}

int balanced_outcome(int64_t index) { return static_cast<int>((index + index / 10) % 2); }

uint64_t draw_seed(uint64_t seed, int64_t index, int draw) {
  const uint64_t first = derive_seed(seed, static_cast<uint64_t>(index));
  return draw == 0 ? first : derive_seed(first, static_cast<uint64_t>(draw));
}

std::vector<Mesh> load_mesh_dir(const std::string& dir) {
  std::vector<Mesh> meshes;
  for (const std::string& f : mesh_files_in(dir)) meshes.push_back(import_mesh(f));
  return meshes;
}

void check_dataset_options(const DatasetOptions& options) {
  if (!is_scenario(options.scenario)) scenario_summary(options.scenario);  // throws, lists names
  if (options.count < 1 || options.count > kMaxDatasetCount) {
    throw ValueError("count", "must be an integer in [1, " + std::to_string(kMaxDatasetCount) +
                                  "], got " + std::to_string(options.count));
  }
  if (options.jobs < 1 || options.jobs > kMaxDatasetJobs) {
    throw ValueError("jobs", "must be an integer in [1, " + std::to_string(kMaxDatasetJobs) +
                                 "], got " + std::to_string(options.jobs));
  }
  if (scenario_needs_meshes(options.scenario) && options.meshes_dir.empty()) {
    throw ValueError("meshes", "scenario " + options.scenario + " needs --meshes DIR");
  }
  if (!scenario_needs_meshes(options.scenario) && !options.meshes_dir.empty()) {
    throw ValueError("meshes", "only the movi-c scenario uses meshes, not " + options.scenario);
  }
  if (!(options.frame_rate_hz >= 0) || !std::isfinite(options.frame_rate_hz)) {
    throw ValueError("frame_rate", "must be a positive rate in Hz (or 0: the scenario's own)");
  }
  check_mesh_density(options.scenario, options.mesh_density);
  const bool labelled = scenario_has_contact_label(options.scenario);
  if (options.balance && !labelled) {
    throw ValueError(
        "balance", "only a scenario with a contact label can be balanced, not " + options.scenario);
  }
  if (options.hide_outcome_frames < 0) {
    throw ValueError("hide_outcome",
                     "must be >= 0 frames, got " + std::to_string(options.hide_outcome_frames));
  }
  if (options.hide_outcome_frames > 0 && !labelled) {
    throw ValueError("hide_outcome", "only a scenario with a contact label has an outcome, not " +
                                         options.scenario);
  }
  if (options.frame_rate_hz != 0 || options.hide_outcome_frames > 0) {
    // Whether the rate fits the scenario's physics steps (movi-c has movi-a's rates and frames),
    // and the frames stored at that rate.
    SimSetup setup = scenario_setup(options.scenario == "movi-c" ? "movi-a" : options.scenario,
                                    derive_seed(options.seed, 0));
    if (options.frame_rate_hz != 0) set_frame_rate(setup, options.frame_rate_hz);
    if (options.hide_outcome_frames >= setup.num_frames) {
      throw ValueError("hide_outcome",
                       std::to_string(options.hide_outcome_frames) +
                           " frames leave no frame for the outcome: " + options.scenario +
                           " scenes have " + std::to_string(setup.num_frames));
    }
  }
  if (options.out_dir.empty()) throw ValueError("out", "output directory is empty");
  std::error_code ec;
  fs::create_directories(options.out_dir, ec);
  if (ec || !fs::is_directory(options.out_dir)) {
    throw IoError(options.out_dir,
                  "cannot create output directory" + (ec ? ": " + ec.message() : std::string()));
  }
  const std::string probe = (fs::path(options.out_dir) / ".dynscope_write_test").string();
  {
    std::ofstream out(probe, std::ios::binary | std::ios::trunc);
    if (!out || !(out << "x") || (out.close(), !out)) {
      throw IoError(options.out_dir, "output directory is not writable");
    }
  }
  fs::remove(probe, ec);
}

DatasetSummary generate_dataset(const DatasetOptions& options, Progress* progress) {
  check_dataset_options(options);
  ScenarioOptions scenario_options;
  std::vector<std::string> mesh_files;
  if (!options.meshes_dir.empty()) {
    scenario_options.meshes = load_mesh_dir(options.meshes_dir);
    for (const std::string& f : mesh_files_in(options.meshes_dir)) {
      mesh_files.push_back(fs::path(f).filename().string());
    }
  }
  scenario_options.frame_rate_hz = options.frame_rate_hz;
  scenario_options.mesh_density = options.mesh_density;
  // Building one setup up front reports scenario-specific input errors before any thread starts.
  const SimSetup first =
      scenario_setup(options.scenario, derive_seed(options.seed, 0), scenario_options);

  const bool labelled = scenario_has_contact_label(options.scenario);
  DatasetSummary summary;
  summary.entries.resize(static_cast<size_t>(options.count));
  std::atomic<int64_t> next{0};
  std::atomic<int64_t> positives{0};
  std::atomic<bool> failed{false};
  std::mutex write_mutex, error_mutex;
  std::exception_ptr error;
  auto work = [&] {
    while (!failed) {
      const int64_t i = next++;
      if (i >= options.count) return;
      try {
        DatasetEntry e;
        e.index = i;
        e.file = scene_file_name(options.scenario, i);
        e.split = split_of(i, options.count);
        Scene scene;
        for (int draw = 0;; ++draw) {
          if (draw == kMaxDraws) {
            throw ValueError("selection", e.file + ": none of " + std::to_string(kMaxDraws) +
                                              " draws met " + selection_text(options, i));
          }
          e.seed = draw_seed(options.seed, i, draw);
          scene = generate_scene(options.scenario, e.seed, scenario_options);
          e.draws = draw + 1;
          if (meets_selection(scene, options, i)) break;
        }
        e.num_objects = static_cast<int>(scene.objects.size());
        if (labelled) e.outcome = contact_outcome(scene) ? 1 : 0;
        {
          // HDF5's C++ layer is not reentrant; the simulation, which dominates, stays parallel.
          std::lock_guard<std::mutex> lock(write_mutex);
          write_scene(scene, (fs::path(options.out_dir) / e.file).string());
        }
        if (e.outcome == 1) ++positives;
        summary.entries[static_cast<size_t>(i)] = std::move(e);
        if (progress) {
          if (labelled) progress->set_status("positives " + std::to_string(positives.load()));
          progress->advance();
        }
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        failed = true;
      }
    }
  };
  const auto threads = static_cast<int>(std::min<int64_t>(options.jobs, options.count));
  if (threads == 1) {
    work();
  } else {
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) pool.emplace_back(work);
    for (std::thread& t : pool) t.join();
  }
  if (error) std::rethrow_exception(error);
  summary.positives = positives;
  summary.manifest_path = (fs::path(options.out_dir) / kManifestName).string();
  write_text_file_atomically(summary.manifest_path,
                             manifest_text(options, mesh_files, first, summary));
  log_debug("generate: wrote ", options.count, " scenes and ", summary.manifest_path);
  return summary;
}

}  // namespace dynscope
