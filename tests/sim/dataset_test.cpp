// Tests of dataset generation: files, manifest, determinism across --jobs, option checks.
#include "engine/sim/dataset.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "engine/core/error.h"
#include "engine/core/rng.h"
#include "engine/io/scene_file.h"
#include "engine/sim/scenario.h"
#include "engine/sim/simulation.h"

namespace dynscope {
namespace {

namespace fs = std::filesystem;

// A fresh directory under the system temp dir, removed when the test ends.
class TempDir {
 public:
  explicit TempDir(const std::string& tag)
      : path_(fs::temp_directory_path() /
              ("dynscope_dataset_test_" + tag + "_" + std::to_string(getpid()))) {
    fs::remove_all(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string str(const std::string& child = "") const {
    return child.empty() ? path_.string() : (path_ / child).string();
  }

 private:
  fs::path path_;
};

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Element-by-element equality of two scenes as stored (HDF5 files also hold creation times).
void expect_same_scene(const Scene& a, const Scene& b, const std::string& what) {
  ASSERT_EQ(a.objects.size(), b.objects.size()) << what;
  ASSERT_EQ(a.num_frames(), b.num_frames()) << what;
  EXPECT_EQ(a.scenario, b.scenario) << what;
  EXPECT_EQ(a.seed, b.seed) << what;
  EXPECT_EQ(a.dt_s, b.dt_s) << what;
  EXPECT_EQ(a.labels, b.labels) << what;
  for (size_t i = 0; i < a.objects.size(); ++i) {
    const Object &x = a.objects[i], &y = b.objects[i];
    EXPECT_EQ(x.id, y.id) << what;
    EXPECT_EQ(x.name, y.name) << what;
    EXPECT_EQ(x.role, y.role) << what;
    EXPECT_EQ(x.mass, y.mass) << what;
    EXPECT_EQ(x.friction, y.friction) << what;
    EXPECT_EQ(x.restitution, y.restitution) << what;
    EXPECT_EQ(x.scale, y.scale) << what;
    EXPECT_EQ(x.color, y.color) << what;
    EXPECT_EQ(x.mesh.vertices, y.mesh.vertices) << what;
    EXPECT_EQ(x.mesh.faces, y.mesh.faces) << what;
    for (int f = 0; f < a.num_frames(); ++f) {
      EXPECT_EQ(a.trajectories[i].poses[f].position, b.trajectories[i].poses[f].position) << what;
      EXPECT_EQ(a.trajectories[i].poses[f].rotation.coeffs(),
                b.trajectories[i].poses[f].rotation.coeffs())
          << what;
    }
  }
}

TEST(Dataset, FileNamesAndSplit) {
  EXPECT_EQ(scene_file_name("movi-a", 7), "movi-a_0007.h5");
  EXPECT_EQ(scene_file_name("drop", 12345), "drop_12345.h5");
  int train = 0, val = 0, test = 0;
  for (int i = 0; i < 100; ++i) {
    const std::string s = split_of(i, 100);
    train += s == "train";
    val += s == "val";
    test += s == "test";
  }
  EXPECT_EQ(train, 80);
  EXPECT_EQ(val, 10);
  EXPECT_EQ(test, 10);
}

TEST(Dataset, EverySplitHasAScene) {
  for (int64_t count = 1; count <= 40; ++count) {
    std::map<std::string, int> sizes;
    for (int64_t i = 0; i < count; ++i) ++sizes[split_of(i, count)];
    EXPECT_EQ(sizes["train"] + sizes["val"] + sizes["test"], count);
    EXPECT_GE(sizes["train"], 1) << count << " scenes";
    if (count >= 3) {
      EXPECT_GE(sizes["val"], 1) << count << " scenes";
      EXPECT_GE(sizes["test"], 1) << count << " scenes";
    } else {
      EXPECT_EQ(sizes["train"], count);
    }
  }
  // Three scenes: one of each.
  EXPECT_EQ(split_of(0, 3), "train");
  EXPECT_EQ(split_of(1, 3), "val");
  EXPECT_EQ(split_of(2, 3), "test");
}

TEST(Dataset, CountAndJobsOutOfRangeNameTheRange) {
  DatasetOptions options;
  options.scenario = "drop";
  options.out_dir = "unused";
  options.count = kMaxDatasetCount + 1;
  try {
    check_dataset_options(options);
    ADD_FAILURE() << "a count above the bound was accepted";
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("count: must be an integer in [1, "), std::string::npos)
        << e.what();
  }
  options.count = 1;
  options.jobs = 100000;
  try {
    check_dataset_options(options);
    ADD_FAILURE() << "100000 jobs were accepted";
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("jobs: must be an integer in [1, 1024], got 100000"),
              std::string::npos)
        << e.what();
  }
}

// --mesh-density sparse is recorded in the manifest and stored in every scene file: boxes keep
// their 8 corners and cylinders their rims, never the dense grids (98 and 226 vertices).
TEST(Dataset, SparseMeshesAreStoredAndRecorded) {
  TempDir dir("sparse");
  DatasetOptions options;
  options.scenario = "movi-a";
  options.count = 4;
  options.seed = 8;
  options.out_dir = dir.str("out");
  options.mesh_density = MeshDensity::kSparse;
  const DatasetSummary summary = generate_dataset(options);
  const nlohmann::json m = nlohmann::json::parse(read_text(summary.manifest_path));
  EXPECT_EQ(m["parameters"]["mesh_density"], "sparse");
  std::set<Eigen::Index> counts;
  for (const DatasetEntry& e : summary.entries) {
    for (const Object& o : read_scene(options.out_dir + "/" + e.file).objects) {
      counts.insert(o.mesh.num_vertices());
    }
  }
  EXPECT_TRUE(counts.count(8)) << "no sparse box among " << counts.size() << " mesh sizes";
  EXPECT_FALSE(counts.count(98)) << "a dense box was stored";
  EXPECT_FALSE(counts.count(226)) << "a dense cylinder was stored";
}

TEST(Dataset, WritesScenesAndManifest) {
  TempDir dir("manifest");
  DatasetOptions options;
  options.scenario = "support";
  options.count = 10;
  options.seed = 5;
  options.out_dir = dir.str("out/nested");  // created with its parents
  const DatasetSummary summary = generate_dataset(options);
  ASSERT_EQ(summary.entries.size(), 10u);
  const nlohmann::json m = nlohmann::json::parse(read_text(summary.manifest_path));
  EXPECT_EQ(m["scenario"], "support");
  EXPECT_EQ(m["count"], 10);
  EXPECT_EQ(m["seed"], 5);
  EXPECT_EQ(m["parameters"]["num_frames"], 60);
  EXPECT_EQ(m["parameters"]["frame_rate_hz"], 30.0);
  EXPECT_EQ(m["parameters"]["mesh_density"], "dense");
  ASSERT_EQ(m["files"].size(), 10u);
  EXPECT_EQ(m["split"]["train"].size(), 8u);
  EXPECT_EQ(m["split"]["val"][0], "support_0008.h5");
  EXPECT_EQ(m["split"]["test"][0], "support_0009.h5");
  int positives = 0;
  for (int i = 0; i < 10; ++i) {
    const nlohmann::json& f = m["files"][i];
    EXPECT_EQ(f["file"], scene_file_name("support", i));
    EXPECT_EQ(f["seed"].get<uint64_t>(), derive_seed(5, static_cast<uint64_t>(i)));
    // Each file holds exactly the scene generate_scene() makes for its seed.
    const Scene stored = read_scene(options.out_dir + "/" + f["file"].get<std::string>());
    const Scene fresh = generate_scene("support", f["seed"].get<uint64_t>());
    expect_same_scene(stored, fresh, f["file"]);
    EXPECT_EQ(f["outcome"].get<int>(), contact_outcome(fresh) ? 1 : 0);
    EXPECT_EQ(f["num_objects"].get<size_t>(), fresh.objects.size());
    positives += f["outcome"].get<int>();
  }
  EXPECT_EQ(m["positives"], positives);
  EXPECT_EQ(summary.positives, positives);
  EXPECT_FALSE(fs::exists(options.out_dir + "/.dynscope_write_test"));
}

TEST(Dataset, JobsDoNotChangeTheResults) {
  TempDir dir("jobs");
  DatasetOptions options;
  options.scenario = "movi-a";
  options.count = 6;
  options.seed = 11;
  options.out_dir = dir.str("one");
  generate_dataset(options);
  options.out_dir = dir.str("two");
  options.jobs = 2;
  generate_dataset(options);
  EXPECT_EQ(read_text(dir.str("one/manifest.json")), read_text(dir.str("two/manifest.json")));
  for (int i = 0; i < 6; ++i) {
    const std::string name = scene_file_name("movi-a", i);
    expect_same_scene(read_scene(dir.str("one/" + name)), read_scene(dir.str("two/" + name)), name);
  }
}

TEST(Dataset, BalancedOutcomesAlternateWithinAndAcrossSplits) {
  for (int64_t start : {0, 20, 1000}) {
    std::map<std::string, std::pair<int, int>> split;  // positives, scenes
    for (int64_t i = start; i < start + 20; ++i) {
      auto& [positives, scenes] = split[split_of(i, 10000)];
      positives += balanced_outcome(i);
      ++scenes;
    }
    EXPECT_EQ(split["train"], std::make_pair(8, 16)) << start;
    EXPECT_EQ(split["val"], std::make_pair(1, 2)) << start;
    EXPECT_EQ(split["test"], std::make_pair(1, 2)) << start;
  }
  EXPECT_EQ(draw_seed(7, 3, 0), derive_seed(7, 3));
  EXPECT_EQ(draw_seed(7, 3, 2), derive_seed(derive_seed(7, 3), 2));
}

// --hide-outcome and --balance: every scene is the first of its draws that meets both, the draws
// before it each fail one, and the result does not depend on --jobs.
TEST(Dataset, SelectedScenesHideTheirOutcomeAndAreBalanced) {
  TempDir dir("selection");
  DatasetOptions options;
  options.scenario = "collide";  // most positives touch the zone early: many redraws
  options.count = 12;
  options.seed = 5;
  options.hide_outcome_frames = 14;
  options.balance = true;
  options.out_dir = dir.str("one");
  const DatasetSummary summary = generate_dataset(options);
  options.jobs = 3;
  options.out_dir = dir.str("two");
  generate_dataset(options);
  EXPECT_EQ(read_text(dir.str("one/manifest.json")), read_text(dir.str("two/manifest.json")));
  EXPECT_EQ(summary.positives, 6);
  const nlohmann::json m = nlohmann::json::parse(read_text(summary.manifest_path));
  EXPECT_EQ(m["selection"]["hide_outcome_frames"], 14);
  EXPECT_EQ(m["selection"]["balance"], true);
  int redrawn = 0;
  for (int i = 0; i < 12; ++i) {
    const nlohmann::json& f = m["files"][i];
    const int draws = f["draws"].get<int>();
    ASSERT_GE(draws, 1);
    EXPECT_EQ(f["seed"].get<uint64_t>(), draw_seed(5, i, draws - 1));
    const Scene stored = read_scene(dir.str("one/" + f["file"].get<std::string>()));
    expect_same_scene(stored, generate_scene("collide", f["seed"].get<uint64_t>()), f["file"]);
    const int first = first_labelled_contact(stored);
    EXPECT_TRUE(first < 0 || first >= 14) << f["file"] << " touches at frame " << first;
    EXPECT_EQ(first >= 0 ? 1 : 0, balanced_outcome(i)) << f["file"];
    EXPECT_EQ(f["outcome"].get<int>(), balanced_outcome(i));
    for (int d = 0; d + 1 < draws; ++d) {
      const Scene rejected = generate_scene("collide", draw_seed(5, i, d));
      const int at = first_labelled_contact(rejected);
      EXPECT_TRUE((at >= 0 && at < 14) || (at >= 0 ? 1 : 0) != balanced_outcome(i))
          << f["file"] << " draw " << d << " met the selection but was not kept";
    }
    redrawn += draws > 1 ? 1 : 0;
  }
  EXPECT_GT(redrawn, 3) << "the selection should have redrawn several collide scenes";
}

TEST(Dataset, BadOptionsFailBeforeAnyWork) {
  TempDir dir("bad");
  DatasetOptions options;
  options.scenario = "drop";
  options.count = 3;
  options.out_dir = dir.str("out");
  auto message = [&](const DatasetOptions& o) -> std::string {
    try {
      generate_dataset(o);
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  DatasetOptions o = options;
  o.scenario = "nope";
  EXPECT_NE(message(o).find("unknown scenario 'nope'"), std::string::npos) << message(o);
  o = options;
  o.count = 0;
  EXPECT_NE(message(o).find("count"), std::string::npos) << message(o);
  o = options;
  o.jobs = 0;
  EXPECT_NE(message(o).find("jobs"), std::string::npos) << message(o);
  o = options;
  o.meshes_dir = dir.str();
  EXPECT_NE(message(o).find("only the movi-c scenario"), std::string::npos) << message(o);
  o = options;
  o.scenario = "movi-c";
  EXPECT_NE(message(o).find("needs --meshes"), std::string::npos) << message(o);
  o = options;
  o.scenario = "movi-c";
  o.meshes_dir = dir.str();
  o.mesh_density = MeshDensity::kSparse;
  EXPECT_NE(message(o).find("mesh_density: movi-c draws the given meshes"), std::string::npos)
      << message(o);
  o = options;
  o.frame_rate_hz = 70;
  EXPECT_NE(message(o).find("frame_rate: 70 Hz is not a whole number"), std::string::npos) << message(o);
  o.frame_rate_hz = -1;
  EXPECT_NE(message(o).find("frame_rate: must be a positive rate"), std::string::npos)
      << message(o);
  o = options;
  o.hide_outcome_frames = -1;
  EXPECT_NE(message(o).find("hide_outcome: must be >= 0"), std::string::npos) << message(o);
  o.hide_outcome_frames = 60;  // drop stores 60 frames
  EXPECT_NE(message(o).find("hide_outcome: 60 frames leave no frame for the outcome: drop scenes "
                            "have 60"),
            std::string::npos)
      << message(o);
  o = options;
  o.scenario = "movi-a";
  o.hide_outcome_frames = 5;
  EXPECT_NE(message(o).find("hide_outcome: only a scenario with a contact label"),
            std::string::npos)
      << message(o);
  o.hide_outcome_frames = 0;
  o.balance = true;
  EXPECT_NE(message(o).find("balance: only a scenario with a contact label"), std::string::npos)
      << message(o);
  EXPECT_FALSE(fs::exists(options.out_dir)) << "nothing created for bad options";

  // An output path below a regular file can never be created (also when running as root).
  fs::create_directories(dir.str());
  std::ofstream(dir.str("file")) << "x";
  o = options;
  o.out_dir = dir.str("file/sub");
  EXPECT_NE(message(o).find(dir.str("file/sub") + ": cannot create output directory"),
            std::string::npos)
      << message(o);
}

// The bundled samples are exactly what the generators make today (assets/scenes/README.md says
// how to regenerate them after a recipe change).
TEST(Samples, BundledScenesMatchTheirGenerators) {
  const fs::path dir = fs::path(DYNSCOPE_SOURCE_DIR) / "assets" / "scenes";
  int checked = 0;
  for (const std::string& name : scenario_names()) {
    const std::string manifest = (dir / (name + "_manifest.json")).string();
    ASSERT_TRUE(fs::is_regular_file(manifest)) << manifest;
    const nlohmann::json m = nlohmann::json::parse(read_text(manifest));
    ScenarioOptions options;
    if (scenario_needs_meshes(name)) {
      options.meshes =
          load_mesh_dir((fs::path(DYNSCOPE_SOURCE_DIR) / "assets" / "meshes").string());
    }
    for (const nlohmann::json& f : m["files"]) {
      const Scene stored = read_scene((dir / f["file"].get<std::string>()).string());
      expect_same_scene(stored, generate_scene(name, f["seed"].get<uint64_t>(), options),
                        f["file"]);
      ++checked;
    }
  }
  EXPECT_GE(checked, 2 * static_cast<int>(scenario_names().size()) - 1);
}

TEST(Dataset, MeshDirectoryMustHoldMeshes) {
  TempDir dir("meshes");
  fs::create_directories(dir.str());
  EXPECT_THROW(load_mesh_dir(dir.str()), IoError);
  EXPECT_THROW(load_mesh_dir(dir.str("missing")), IoError);
}

}  // namespace
}  // namespace dynscope
