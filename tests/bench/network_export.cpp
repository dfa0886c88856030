// Writes the Physion-preset PointConv network with one input on the model benchmarks' synthetic
// scene, its outputs, forward times and page faults, for tests/bench/eager_network.py to read.
//   network_export OUT_DIR [--points 3000,10000] [--repeats 20]
// Writes OUT_DIR/network_<points>.pt per size. Threads: DYNSCOPE_BENCH_THREADS, default 1.
#include <sys/resource.h>
#include <torch/serialize.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "engine/model/conv_implementation.h"
#include "engine/model/dynamics_model.h"
#include "engine/model/model_config.h"
#include "engine/model/norm_stats.h"
#include "engine/model/torch_runtime.h"
#include "tests/bench/bench_state.h"

namespace dynscope {
namespace {

struct Options {
  std::filesystem::path out_dir;
  std::vector<int> points{3000, 10000};
  int repeats = 20;
  int threads = 1;
};

constexpr const char* kUsage =
    "usage: network_export OUT_DIR [--points N,N] [--repeats R]\n"
    "Writes OUT_DIR/network_<N>.pt per size (default 3000,10000): the Physion-preset PointConv\n"
    "network's weights, one input, its outputs and the minimum of R (default 20) forward passes,\n"
    "fused and unfused, for tests/bench/eager_network.py. Threads: DYNSCOPE_BENCH_THREADS\n"
    "(default 1).\n";

// A whole decimal number, or invalid_argument naming the option.
int parse_int(const std::string& text, const char* option) {
  size_t used = 0;
  int value = 0;
  try {
    value = std::stoi(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size()) {
    throw std::invalid_argument(std::string(option) + " expects whole numbers, got '" + text + "'");
  }
  return value;
}

Options parse_options(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "-h" || arg == "--help") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (arg == "--points" && has_value) {
      o.points.clear();
      std::stringstream list(argv[++i]);
      for (std::string item; std::getline(list, item, ',');)
        o.points.push_back(parse_int(item, "--points"));
    } else if (arg == "--repeats" && has_value) {
      o.repeats = parse_int(argv[++i], "--repeats");
    } else if (arg.rfind("--", 0) != 0 && o.out_dir.empty()) {
      o.out_dir = arg;
    } else {
      throw std::invalid_argument("unexpected argument '" + arg + "'\n" + kUsage);
    }
  }
  if (o.out_dir.empty()) {
    throw std::invalid_argument(std::string("no OUT_DIR\n") + kUsage);
  }
  if (o.repeats < 1 || o.points.empty() ||
      *std::min_element(o.points.begin(), o.points.end()) < kBenchObjects) {
    throw std::invalid_argument("--repeats must be >= 1 and every --points >= " +
                                std::to_string(kBenchObjects));
  }
  if (const char* env = std::getenv("DYNSCOPE_BENCH_THREADS")) {
    o.threads = std::max(1, std::atoi(env));
  }
  return o;
}

// Statistics away from the identity, so that the export exercises the input normalisation and
// the output scaling.
NormStats bench_stats() {
  NormStats s;
  s.velocity_mean = Vec3(0.0015, -0.0002, 0.0008);
  s.velocity_std = Vec3(0.004, 0.003, 0.005);
  s.target_mean = Vec3(0.0001, 0.0, -0.0003);
  s.target_std = Vec3(0.0007, 0.0005, 0.0009);
  s.z_mean = 0.12;
  s.z_std = 0.08;
  return s;
}

int64_t minor_faults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

// The minimum wall time of one function over its runs and its mean minor page faults per run.
struct Timing {
  double min_ms = std::numeric_limits<double>::infinity();
  double faults = 0;
};

// Times `repeats` runs of each function; the functions take turns, so that a change in machine
// load reaches all of them alike. One untimed warm-up run each.
std::vector<Timing> time_runs(const std::vector<std::function<void()>>& runs, int repeats) {
  using Clock = std::chrono::steady_clock;
  for (const auto& run : runs) run();
  std::vector<Timing> out(runs.size());
  for (int r = 0; r < repeats; ++r) {
    for (size_t i = 0; i < runs.size(); ++i) {
      const int64_t faults = minor_faults();
      const auto t = Clock::now();
      runs[i]();
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t).count();
      out[i].min_ms = std::min(out[i].min_ms, ms);
      out[i].faults += static_cast<double>(minor_faults() - faults) / repeats;
    }
  }
  return out;
}

// The input tensors the forward pass reads: p(t), v(t), v(t−1), and per level l its points and
// each list's index (−1 where masked) and mask, as "level.<l>.<list>.index" / ".mask".
c10::Dict<std::string, at::Tensor> input_tensors(const ModelInput& in) {
  c10::Dict<std::string, at::Tensor> d;
  d.insert("position", in.position);
  d.insert("velocity", in.velocity);
  d.insert("prev_velocity", in.prev_velocity);
  for (int l = 0; l < in.hierarchy.num_levels(); ++l) {
    const LevelTensors& level = in.hierarchy.levels[static_cast<size_t>(l)];
    const std::string prefix = "level." + std::to_string(l) + ".";
    d.insert(prefix + "points", level.points);
    const std::pair<const char*, const NeighborTensors*> lists[] = {
        {"same", &level.same},
        {"relational", &level.relational},
        {"down", &level.down},
        {"up", &level.up}};
    for (const auto& [name, list] : lists) {
      d.insert(prefix + name + ".index", list->index);
      d.insert(prefix + name + ".mask", list->mask);
    }
  }
  return d;
}

std::string context_text() {
  std::string text;
  for (const auto& [key, value] : torch_context()) text += key + " " + value + "\n";
  return text;
}

void write_file(const std::filesystem::path& path, const std::vector<char>& bytes) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw std::runtime_error(tmp.string() + ": write failed");
  }
  std::filesystem::rename(tmp, path);
}

void export_network(const Options& o, int n) {
  ModelConfig config = ModelConfig::preset("physion");
  config.kind = ModelKind::kPointConv;
  torch::manual_seed(1);
  DynamicsModel model(config);
  model->set_stats(bench_stats());
  model->eval();
  const PointState state = make_bench_state(n);
  const ModelInput input = make_model_input(state, model->build_hierarchy(state));
  torch::NoGradGuard no_grad;

  c10::Dict<std::string, at::Tensor> outputs;
  for (const auto& [impl, name] : {std::pair{ConvImplementation::kFused, "fused"},
                                   std::pair{ConvImplementation::kUnfused, "unfused"}}) {
    set_conv_implementation(impl);
    outputs.insert(std::string("network.") + name, model->forward(input));
    outputs.insert(std::string("positions.") + name, model->predict_positions(input));
  }
  auto run_with = [&](ConvImplementation impl) {
    return [&model, &input, impl] {
      set_conv_implementation(impl);
      model->predict_positions(input);
    };
  };
  const std::vector<Timing> t = time_runs(
      {run_with(ConvImplementation::kFused), run_with(ConvImplementation::kUnfused)}, o.repeats);
  set_conv_implementation(ConvImplementation::kFused);

  c10::Dict<std::string, at::Tensor> state_dict;
  for (const auto& p : model->named_parameters()) state_dict.insert(p.key(), p.value());
  for (const auto& b : model->named_buffers()) state_dict.insert(b.key(), b.value());
  c10::Dict<std::string, double> time_ms;
  time_ms.insert("fused", t[0].min_ms);
  time_ms.insert("unfused", t[1].min_ms);
  c10::Dict<std::string, double> faults;
  faults.insert("fused", t[0].faults);
  faults.insert("unfused", t[1].faults);
  int64_t level_points = 0;
  for (const LevelTensors& level : input.hierarchy.levels) level_points += level.points.size(0);

  c10::impl::GenericDict file(c10::StringType::get(), c10::AnyType::get());
  file.insert("format", std::string("dynscope-network-export-1"));
  file.insert("config", config.to_json());
  file.insert("points", static_cast<int64_t>(n));
  file.insert("threads", static_cast<int64_t>(o.threads));
  file.insert("repeats", static_cast<int64_t>(o.repeats));
  file.insert("context", context_text());
  file.insert("state_dict", state_dict);
  file.insert("input", input_tensors(input));
  file.insert("output", outputs);
  file.insert("time_ms", time_ms);
  file.insert("minor_faults_per_pass", faults);
  const std::filesystem::path path = o.out_dir / ("network_" + std::to_string(n) + ".pt");
  write_file(path, torch::pickle_save(c10::IValue(file)));
  std::printf(
      "%-6d points (%lld on all levels): fused %8.2f ms (%.0f faults/pass)  unfused %8.2f ms "
      "(%.0f faults/pass)  -> %s\n",
      n, static_cast<long long>(level_points), t[0].min_ms, t[0].faults, t[1].min_ms, t[1].faults,
      path.c_str());
}

int run(int argc, char** argv) {
  const Options o = parse_options(argc, argv);
  set_torch_threads(o.threads);
  std::filesystem::create_directories(o.out_dir);
  std::fputs(context_text().c_str(), stdout);
  std::printf("network_export: physion pointconv, %d thread(s), min of %d forward passes\n",
              o.threads, o.repeats);
  for (int n : o.points) export_network(o, n);
  return 0;
}

}  // namespace
}  // namespace dynscope

int main(int argc, char** argv) {
  try {
    return dynscope::run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "network_export: error: %s\n", e.what());
    return 1;
  }
}
