// Fuzz suite: structured mutations of every file kind the commands read (scenes, rollouts, traces,
// checkpoints, recipes, view specs, meshes), each run through the built binary. Every run must
// exit 0 or fail with one "dynscope: error:" line, never end by a signal or a timeout, stay under
// 2 GB, and leave the outputs of an earlier run unchanged when it fails.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_util.h"

namespace dynscope::fuzz {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const std::string kSource = DYNSCOPE_SOURCE_DIR;
const std::string kScene = kSource + "/assets/scenes/movi-a_0000.h5";
const std::string kCheckpoint = kSource + "/assets/models/movi-a_pointconv_acc.pt";
constexpr double kTimeoutS = 20.0;
constexpr long kMaxRssKb = 2L * 1024 * 1024;

// A scratch directory for one test, removed at the end.
class Scratch {
 public:
  Scratch() {
    static std::atomic<int> counter{0};
    dir_ = fs::temp_directory_path() /
           ("dynscope-fuzz-" + std::to_string(getpid()) + "-" + std::to_string(counter++));
    fs::create_directories(dir_);
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

 private:
  fs::path dir_;
};

// Outputs a command may replace; they hold sentinel bytes that must survive a failed run.
struct Outputs {
  std::vector<std::string> files;
  void plant() const {
    for (const std::string& f : files) {
      fs::create_directories(fs::path(f).parent_path());
      write_bytes(f, "sentinel of an earlier run: " + f);
    }
  }
  void expect_unchanged(const std::string& what) const {
    for (const std::string& f : files) {
      EXPECT_EQ(read_bytes(f), "sentinel of an earlier run: " + f)
          << what << ": a failed run changed " << f;
    }
  }
};

// Runs `args` and checks the run's ending; `what` names the mutation in failure messages.
void expect_clean_run(const std::vector<std::string>& args, const Outputs& outputs,
                      const std::string& log, const std::string& what) {
  outputs.plant();
  const RunResult r = run_binary(args, log, kTimeoutS);
  std::string command;
  for (const std::string& a : args) command += " " + a;
  const std::string context = what + "\n  dynscope" + command + "\n" + r.output;
  ASSERT_FALSE(r.timed_out) << "timed out after " << kTimeoutS << " s: " << context;
  ASSERT_EQ(r.signal, 0) << "killed by signal " << r.signal << " (" << strsignal(r.signal)
                         << "): " << context;
  EXPECT_LT(r.max_rss_kb, kMaxRssKb) << "peak memory " << r.max_rss_kb << " kB: " << context;
  if (r.exit_code == 0) return;
  // The error is the last line: "dynscope: error: ..." on one line.
  std::string text = r.output.substr(0, r.output.find_last_not_of("\n") + 1);
  const std::string last = text.substr(text.find_last_of('\n') + 1);
  EXPECT_EQ(last.rfind("dynscope: error: ", 0), 0u) << "no one-line error: " << context;
  outputs.expect_unchanged(context);
}

// Runs every mutation of `original` (copied to `input` first) through each of `commands`
// (argument lists where "{}" stands for the input); command k runs for every `stride[k]`-th
// mutation only, so slow commands see a sample.
struct Command {
  std::vector<std::string> args;
  Outputs outputs;
  size_t stride = 1;
};

// Mutations per test by default: every run starts the whole binary (about a second of CPU), and
// the suite must stay within a few minutes on two cores. DYNSCOPE_FUZZ_MUTATIONS raises it for a
// deeper run; the sample is spread evenly over the full list, so every kind of mutation is hit.
size_t mutation_budget() {
  const char* env = std::getenv("DYNSCOPE_FUZZ_MUTATIONS");
  return env != nullptr ? static_cast<size_t>(std::strtoull(env, nullptr, 10)) : 28;
}

std::vector<Mutation> sample(const std::vector<Mutation>& all, size_t budget) {
  if (all.size() <= budget) return all;
  std::vector<Mutation> out;
  for (size_t i = 0; i < budget; ++i) out.push_back(all[i * all.size() / budget]);
  return out;
}

int fuzz_file(const std::string& original, const std::string& input,
              const std::vector<Mutation>& all_mutations, const std::vector<Command>& commands,
              const std::string& log, size_t budget = mutation_budget()) {
  const std::vector<Mutation> mutations = sample(all_mutations, budget);
  int runs = 0;
  for (size_t m = 0; m < mutations.size(); ++m) {
    fs::copy_file(original, input, fs::copy_options::overwrite_existing);
    mutations[m].apply(input);
    for (const Command& c : commands) {
      if (m % c.stride != 0) continue;
      std::vector<std::string> args = c.args;
      for (std::string& a : args) {
        if (a == "{}") a = input;
      }
      expect_clean_run(args, c.outputs, log, mutations[m].name);
      ++runs;
      if (::testing::Test::HasFatalFailure()) return runs;
    }
  }
  return runs;
}

// Structured mutations of an HDF5 file: every group and dataset deleted, datasets with NaN,
// inf, huge or negative values, another type, one row short or long, a huge declared shape;
// every attribute deleted or replaced by NaN, -1, a huge value or a string; then truncations,
// bit flips and zeroed blocks. Paths differing only in numbers (frames/0003, vertices_2) are
// mutated for the first `per_pattern` of them.
std::vector<Mutation> h5_mutations(const std::string& path, int per_pattern, uint64_t seed) {
  const H5Contents c = list_h5(path);
  std::map<std::string, int> seen;
  auto take = [&](const std::string& p, const char* kind) {
    return seen[std::string(kind) + path_pattern(p)]++ < per_pattern;
  };
  std::vector<Mutation> out;
  for (const std::string& g : c.groups) {
    if (!take(g, "g")) continue;
    out.push_back({"group " + g + " deleted", [g](const std::string& p) {
                     edit_h5(p, [&](hid_t f) { H5Ldelete(f, g.c_str(), H5P_DEFAULT); });
                   }});
  }
  for (const std::string& d : c.datasets) {
    if (!take(d, "d")) continue;
    out.push_back({"dataset " + d + " deleted", [d](const std::string& p) {
                     edit_h5(p, [&](hid_t f) { H5Ldelete(f, d.c_str(), H5P_DEFAULT); });
                   }});
    for (double v : {std::nan(""), static_cast<double>(INFINITY), 1e300, -1.0, 3.7}) {
      out.push_back(
          {"dataset " + d + " filled with " + std::to_string(v), [d, v](const std::string& p) {
             edit_h5(p, [&](hid_t f) { replace_dataset(f, d, dataset_dims(f, d), v); });
           }});
    }
    out.push_back({"dataset " + d + " as strings", [d](const std::string& p) {
                     edit_h5(p, [&](hid_t f) { replace_with_strings(f, d); });
                   }});
    out.push_back({"dataset " + d + " one row short", [d](const std::string& p) {
                     edit_h5(p, [&](hid_t f) {
                       std::vector<hsize_t> dims = dataset_dims(f, d);
                       if (!dims.empty() && dims[0] > 0) --dims[0];
                       replace_dataset(f, d, dims, 0.5);
                     });
                   }});
    out.push_back({"dataset " + d + " one column more", [d](const std::string& p) {
                     edit_h5(p, [&](hid_t f) {
                       std::vector<hsize_t> dims = dataset_dims(f, d);
                       if (dims.empty()) dims.push_back(1);
                       ++dims.back();
                       replace_dataset(f, d, dims, 0.5);
                     });
                   }});
    out.push_back({"dataset " + d + " declares 10^9 rows", [d](const std::string& p) {
                     edit_h5(p, [&](hid_t f) {
                       std::vector<hsize_t> dims = dataset_dims(f, d);
                       if (dims.empty()) dims.push_back(1);
                       dims[0] = 1000000000;
                       replace_dataset(f, d, dims, 0.0, /*unwritten=*/true);
                     });
                   }});
  }
  for (const auto& [object, name] : c.attributes) {
    if (!take(object + "@" + name, "a")) continue;
    const std::string label = "attribute " + object + "@" + name;
    out.push_back({label + " deleted", [object = object, name = name](const std::string& p) {
                     edit_h5(p, [&](hid_t f) {
                       const hid_t o =
                           H5Oopen(f, object.empty() ? "/" : object.c_str(), H5P_DEFAULT);
                       H5Adelete(o, name.c_str());
                       H5Oclose(o);
                     });
                   }});
    for (double v : {std::nan(""), -1.0, 1e12, 1e300}) {
      out.push_back({label + " = " + std::to_string(v),
                     [object = object, name = name, v](const std::string& p) {
                       edit_h5(p, [&](hid_t f) { replace_attribute(f, object, name, v); });
                     }});
    }
    out.push_back({label + " = 'x'", [object = object, name = name](const std::string& p) {
                     edit_h5(p, [&](hid_t f) { replace_attribute(f, object, name, 0, "x"); });
                   }});
  }
  const std::vector<Mutation> bytes =
      byte_mutations(static_cast<size_t>(fs::file_size(path)), 8, 24, 6, seed);
  out.insert(out.end(), bytes.begin(), bytes.end());
  return out;
}

// Structured mutations of a JSON document: every member deleted or replaced by -1, 3.7, 1e300,
// 1e12, a string, null or an empty array; then truncations.
std::vector<Mutation> json_mutations(const std::string& path) {
  const json doc = json::parse(read_bytes(path));
  std::vector<json::json_pointer> pointers;
  std::function<void(const json&, const json::json_pointer&)> walk =
      [&](const json& j, const json::json_pointer& at) {
        if (!at.empty()) pointers.push_back(at);
        if (j.is_object()) {
          for (auto it = j.begin(); it != j.end(); ++it) walk(it.value(), at / it.key());
        } else if (j.is_array()) {
          for (size_t i = 0; i < j.size() && i < 3; ++i) walk(j[i], at / i);
        }
      };
  walk(doc, json::json_pointer());
  std::vector<Mutation> out;
  const std::vector<std::pair<std::string, json>> values = {
      {"-1", -1},   {"3.7", 3.7},      {"1e300", 1e300},     {"1e12", 1e12},
      {"'x'", "x"}, {"null", nullptr}, {"[]", json::array()}};
  for (const json::json_pointer& p : pointers) {
    out.push_back({p.to_string() + " deleted", [doc, p](const std::string& file) {
                     json j = doc;
                     json& parent = j.at(p.parent_pointer());
                     if (parent.is_array()) {
                       parent.erase(static_cast<size_t>(std::stoul(p.back())));
                     } else {
                       parent.erase(p.back());
                     }
                     write_bytes(file, j.dump(2));
                   }});
    if (!doc.at(p).is_primitive()) continue;
    for (const auto& [label, value] : values) {
      out.push_back({p.to_string() + " = " + label, [doc, p, value = value](const std::string& f) {
                       json j = doc;
                       j[p] = value;
                       write_bytes(f, j.dump(2));
                     }});
    }
  }
  const std::vector<Mutation> bytes =
      byte_mutations(static_cast<size_t>(fs::file_size(path)), 4, 0, 0, 1);
  out.insert(out.end(), bytes.begin(), bytes.end());
  return out;
}

// Each test in a scratch directory (ctest runs every test in its own process).
class FileFuzz : public ::testing::Test {
 protected:
  // Writes the binary's own output of `args` (a rollout or a trace of the bundled scene) to
  // `path`, the original that the test then mutates.
  void make_original(std::vector<std::string> args, const std::string& path) {
    args.push_back("--out");
    args.push_back(path);
    const RunResult r = run_binary(args, scratch_.file("setup.log"), 120);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }

  Scratch scratch_;
};

// The stored names of the links in /frames ("0000", "0001", ...) corrupted in place: their bytes
// (and the byte before, where a length or flags field sits) overwritten with 0xff, 0 or garbage.
std::vector<Mutation> link_name_mutations(const std::string& path) {
  const std::string bytes = read_bytes(path);
  std::vector<Mutation> out;
  for (const char* name : {"0000", "0001", "0013", "0023"}) {
    for (size_t at = bytes.find(name); at != std::string::npos && at > 0;
         at = bytes.find(name, at + 1)) {
      for (const auto& [label, fill] : std::vector<std::pair<std::string, std::string>>{
               {"0xff", "\xff\xff\xff\xff"}, {"zero", std::string(4, '\0')}, {"text", "a/.."}}) {
        out.push_back(
            {std::string("link name ") + name + " at " + std::to_string(at) + " -> " + label,
             [at, fill = fill](const std::string& p) {
               std::string b = read_bytes(p);
               b.replace(at, 4, fill);
               write_bytes(p, b);
             }});
      }
      out.push_back(
          {std::string("byte before link name ") + name + " at " + std::to_string(at) + " -> 0xff",
           [at](const std::string& p) {
             std::string b = read_bytes(p);
             b[at - 1] = static_cast<char>(0xff);
             write_bytes(p, b);
           }});
    }
  }
  return out;
}

TEST_F(FileFuzz, Scenes) {
  const std::string input = scratch_.file("scene.h5");
  const std::string out = scratch_.file("frames");
  const int runs = fuzz_file(
      kScene, input, h5_mutations(kScene, 1, 11),
      {{{"info", "{}"}, {}, 1},
       {{"render", "{}", "--out", out, "--frames", "0:2", "--no-video", "--size", "64x48"},
        {{out + "/frame_0000.png", out + "/view.json", out + "/contact_sheet.png"}},
        5}},
      scratch_.file("log"));
  EXPECT_GE(runs, 30);
}

// Corrupted link names in /frames once made HDF5 crash or double-free while listing the frames.
TEST_F(FileFuzz, ScenesWithCorruptFrameLinkNames) {
  const std::vector<Mutation> names = link_name_mutations(kScene);
  ASSERT_GE(names.size(), 16u) << "the frame link names were not found in the file";
  const int runs = fuzz_file(kScene, scratch_.file("scene.h5"), names, {{{"info", "{}"}, {}, 1}},
                             scratch_.file("log"), names.size());
  EXPECT_EQ(runs, static_cast<int>(names.size()));
}

TEST_F(FileFuzz, Rollouts) {
  const std::string rollout = scratch_.file("original.h5");
  make_original({"rollout", "--checkpoint", kCheckpoint, "--scene", kScene, "--frames", "6"},
                rollout);
  ASSERT_FALSE(HasFatalFailure());
  const std::string input = scratch_.file("rollout.h5");
  const std::string out = scratch_.file("frames");
  const int runs = fuzz_file(
      rollout, input, h5_mutations(rollout, 1, 12),
      {{{"info", "{}"}, {}, 1},
       {{"render", "{}", "--out", out, "--frames", "0:2", "--no-video", "--size", "64x48"},
        {{out + "/frame_0000.png", out + "/view.json"}},
        4}},
      scratch_.file("log"));
  EXPECT_GE(runs, 28);
}

TEST_F(FileFuzz, Traces) {
  const std::string trace = scratch_.file("original.h5");
  make_original(
      {"trace", "--checkpoint", kCheckpoint, "--scene", kScene, "--frame", "2", "--query", "0"},
      trace);
  ASSERT_FALSE(HasFatalFailure());
  const std::string input = scratch_.file("trace.h5");
  const std::string out = scratch_.file("frames");
  const int runs = fuzz_file(
      trace, input, h5_mutations(trace, 1, 13),
      {{{"info", "{}"}, {}, 1},
       {{"render", kScene, "--trace", "{}", "--out", out, "--no-video", "--size", "64x48"},
        {{out + "/frame_0002.png", out + "/view.json"}},
        4}},
      scratch_.file("log"));
  EXPECT_GE(runs, 28);
}

TEST_F(FileFuzz, Checkpoints) {
  const std::string input = scratch_.file("model.pt");
  const std::string out = scratch_.file("rollout.h5");
  const size_t size = static_cast<size_t>(fs::file_size(kCheckpoint));
  const int runs = fuzz_file(
      kCheckpoint, input, byte_mutations(size, 8, 48, 8, 14),
      {{{"info", "{}"}, {}, 1},
       {{"rollout", "--checkpoint", "{}", "--scene", kScene, "--out", out, "--frames", "5"},
        {{out}},
        6}},
      scratch_.file("log"));
  EXPECT_GE(runs, 28);
}

TEST_F(FileFuzz, Recipes) {
  // A recipe is read next to its checkpoint (sampling) and by train --recipe.
  const std::string checkpoint = scratch_.file("model.pt");
  fs::copy_file(kCheckpoint, checkpoint);
  const std::string original = kCheckpoint + ".recipe.json";
  const std::string out = scratch_.file("trace.h5");
  const int runs = fuzz_file(
      original, checkpoint + ".recipe.json", json_mutations(original),
      {{{"train", "--recipe", "{}", "--data", scratch_.file("no-data"), "--out",
         scratch_.file("train.pt")},
        {},
        1},
       {{"trace", "--checkpoint", checkpoint, "--scene", kScene, "--out", out}, {{out}}, 3}},
      scratch_.file("log"));
  EXPECT_GE(runs, 28);
}

TEST_F(FileFuzz, ViewSpecs) {
  const std::string out = scratch_.file("frames");
  const std::string view = scratch_.file("view.json");
  {
    // The view the renderer itself writes, as the viewer would save it.
    const RunResult r = run_binary({"render", kScene, "--out", scratch_.file("first"), "--frames",
                                    "0", "--no-video", "--size", "64x48"},
                                   scratch_.file("log"), kTimeoutS);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    fs::copy_file(scratch_.file("first/view.json"), scratch_.file("original.json"));
  }
  const int runs = fuzz_file(
      scratch_.file("original.json"), view, json_mutations(scratch_.file("original.json")),
      {{{"render", kScene, "--view", "{}", "--out", out, "--frames", "0", "--no-video"},
        {{out + "/frame_0000.png", out + "/view.json"}},
        1}},
      scratch_.file("log"));
  EXPECT_GE(runs, 28);
}

// Small meshes of every text format, and a binary PLY.
std::vector<std::pair<std::string, std::string>> mesh_files() {
  std::string binary_ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n";
  const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  binary_ply.append(reinterpret_cast<const char*>(v), sizeof v);
  const unsigned char n = 3;
  const int32_t f[3] = {0, 1, 2};
  binary_ply.append(reinterpret_cast<const char*>(&n), 1);
  binary_ply.append(reinterpret_cast<const char*>(f), sizeof f);
  return {
      {"tetra.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"},
      {"tetra.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"},
      {"tetra.ply",
       "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
       "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
       "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"},
      {"binary.ply", binary_ply},
      {"tri.stl",
       "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
       "endloop\nendfacet\nendsolid t\n"},
  };
}

// Text mutations of a mesh: every number replaced by a huge count, a negative index, NaN or
// garbage, one at a time; then truncations and bit flips.
std::vector<Mutation> mesh_mutations(const std::string& text, uint64_t seed) {
  std::vector<Mutation> out;
  std::vector<std::pair<size_t, size_t>> numbers;  // (start, length) of each number token
  for (size_t i = 0; i < text.size();) {
    if (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '-') {
      size_t j = i;
      while (j < text.size() && !std::isspace(static_cast<unsigned char>(text[j]))) ++j;
      numbers.emplace_back(i, j - i);
      i = j;
    } else {
      ++i;
    }
  }
  for (size_t k = 0; k < numbers.size() && k < 40; ++k) {
    for (const char* value : {"353535235358", "-7", "nan", "2000000000", "1e39", "#"}) {
      const auto [start, length] = numbers[k];
      std::string mutated = text;
      mutated.replace(start, length, value);
      out.push_back({"number " + std::to_string(k) + " -> " + value,
                     [mutated](const std::string& p) { write_bytes(p, mutated); }});
    }
  }
  const std::vector<Mutation> bytes = byte_mutations(text.size(), 6, 12, 0, seed);
  out.insert(out.end(), bytes.begin(), bytes.end());
  return out;
}

TEST_F(FileFuzz, Meshes) {
  int runs = 0;
  uint64_t seed = 20;
  for (const auto& [name, text] : mesh_files()) {
    const std::string original = scratch_.file("original_" + name);
    write_bytes(original, text);
    // Binary files are mutated byte-wise only.
    std::vector<Mutation> mutations = name == "binary.ply"
                                          ? byte_mutations(text.size(), 8, 24, 2, seed)
                                          : mesh_mutations(text, seed);
    runs += fuzz_file(original, scratch_.file(name), mutations, {{{"info", "{}"}, {}, 1}},
                      scratch_.file("log"), std::max<size_t>(4, mutation_budget() * 3 / 7));
    ++seed;
  }
  EXPECT_GE(runs, 60);
}

}  // namespace
}  // namespace dynscope::fuzz
