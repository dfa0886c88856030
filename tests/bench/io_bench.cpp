// Scene file benchmarks: opening a scene must cost the same per frame at any frame count.
//
// BM_ReadScene/N: read_scene of a one-object scene with N frame groups (written once, outside the
// timing). The us_per_frame counter is the number to compare across N: it stays flat when listing
// the frame groups is linear.
// BM_ListFramesByIndex/N and BM_ListFramesIterate/N list the N links of /frames of the same files
// the two ways: H5Lget_name_by_idx twice per link (what h5::Group::children() did; HDF5 rebuilds
// its sorted link table on every call) and one H5Literate pass (what it does now).
#include <benchmark/benchmark.h>
#include <hdf5.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "engine/io/scene_file.h"
#include "engine/scene/mesh.h"

namespace dynscope {
namespace {

std::string scene_with_frames(int frames) {
  const std::string path =
      (std::filesystem::temp_directory_path() /
       ("dynscope_io_bench_" + std::to_string(getpid()) + "_" + std::to_string(frames) + ".h5"))
          .string();
  Scene scene;
  scene.scenario = "drop";
  scene.dt_s = 1.0 / 24.0;
  Object box;
  box.id = 1;
  box.mesh = make_box_mesh(Vec3(0.5, 0.5, 0.5));
  scene.objects = {box};
  scene.trajectories.resize(1);
  for (int t = 0; t < frames; ++t) {
    Pose pose;
    pose.position = Vec3(0, 0, 0.001 * t);
    scene.trajectories[0].poses.push_back(pose);
  }
  write_scene(scene, path);
  return path;
}

void BM_ReadScene(benchmark::State& state) {
  const int frames = static_cast<int>(state.range(0));
  const std::string path = scene_with_frames(frames);
  for (auto _ : state) {
    const Scene scene = read_scene(path);
    benchmark::DoNotOptimize(scene.trajectories.data());
  }
  std::filesystem::remove(path);
  // Rate inverted: seconds per (frame x 1e-6), i.e. microseconds per frame.
  state.counters["us_per_frame"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * frames * 1e-6,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
// Lists the link names of /frames in `path` by index (the replaced way) or in one iteration.
size_t list_frames(const std::string& path, bool by_index) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t frames = H5Gopen2(file, "frames", H5P_DEFAULT);
  std::vector<std::string> names;
  if (by_index) {
    H5G_info_t info;
    H5Gget_info(frames, &info);
    for (hsize_t i = 0; i < info.nlinks; ++i) {
      const ssize_t len =
          H5Lget_name_by_idx(frames, ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
      std::string name(static_cast<size_t>(len) + 1, '\0');
      H5Lget_name_by_idx(frames, ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size(),
                         H5P_DEFAULT);
      names.push_back(name);
    }
  } else {
    hsize_t next = 0;
    H5Literate(
        frames, H5_INDEX_NAME, H5_ITER_NATIVE, &next,
        [](hid_t, const char* name, const H5L_info_t*, void* out) -> herr_t {
          static_cast<std::vector<std::string>*>(out)->emplace_back(name);
          return 0;
        },
        &names);
    std::sort(names.begin(), names.end());
  }
  H5Gclose(frames);
  H5Fclose(file);
  return names.size();
}

void list_benchmark(benchmark::State& state, bool by_index) {
  const int frames = static_cast<int>(state.range(0));
  const std::string path = scene_with_frames(frames);
  for (auto _ : state) benchmark::DoNotOptimize(list_frames(path, by_index));
  std::filesystem::remove(path);
  state.counters["us_per_frame"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * frames * 1e-6,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_ListFramesByIndex(benchmark::State& state) { list_benchmark(state, true); }
void BM_ListFramesIterate(benchmark::State& state) { list_benchmark(state, false); }
BENCHMARK(BM_ListFramesByIndex)->Arg(300)->Arg(1000)->Arg(3000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ListFramesIterate)->Arg(300)->Arg(1000)->Arg(3000)->Unit(benchmark::kMillisecond);

BENCHMARK(BM_ReadScene)
    ->Arg(300)
    ->Arg(1000)
    ->Arg(3000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace dynscope

BENCHMARK_MAIN();
