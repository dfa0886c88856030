// Tests of `dynscope info` on the bundled scene and mesh, and on bad input.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/run_command.h"

namespace dynscope {
namespace {

using test::run_dynscope;

const std::string kSource = DYNSCOPE_SOURCE_DIR;

TEST(InfoCommand, DescribesABundledSceneAsJson) {
  const auto r = run_dynscope("info --json " + kSource + "/assets/scenes/collide_0000.h5");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["kind"], "scene");
  EXPECT_EQ(j["scenario"], "collide");
  EXPECT_GT(j["num_frames"].get<int>(), 1);
  EXPECT_DOUBLE_EQ(j["voxel"].get<double>(), 0.05);  // Physion-scale default
  int targets = 0, zones = 0;
  int64_t points = 0;
  for (const auto& o : j["objects"]) {
    targets += o["role"] == "target";
    zones += o["role"] == "zone";
    EXPECT_GT(o["faces"].get<int>(), 0);
    points += o["points"].get<int64_t>();
  }
  EXPECT_EQ(targets, 1);
  EXPECT_EQ(zones, 1);
  EXPECT_EQ(points, j["num_points"].get<int64_t>());
  EXPECT_TRUE(j["labels"].contains("target_contacting_zone"));
}

TEST(InfoCommand, TableNamesRolesFramesAndPointCounts) {
  const auto r = run_dynscope("info " + kSource + "/assets/scenes/movi-a_0000.h5");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* word :
       {"scenario   movi-a", "frames     24", "dt 0.08333", "voxel 0.2", "role"}) {
    EXPECT_NE(r.output.find(word), std::string::npos) << word << "\n" << r.output;
  }
}

TEST(InfoCommand, SmallerVoxelGivesMorePoints) {
  const std::string scene = kSource + "/assets/scenes/movi-a_0000.h5";
  const auto coarse =
      nlohmann::json::parse(run_dynscope("info --json --voxel 0.4 " + scene).output);
  const auto fine = nlohmann::json::parse(run_dynscope("info --json --voxel 0.2 " + scene).output);
  EXPECT_GT(fine["num_points"].get<int64_t>(), 2 * coarse["num_points"].get<int64_t>());
}

TEST(InfoCommand, DescribesAMesh) {
  const auto r = run_dynscope("info --json " + kSource + "/assets/meshes/torus.obj");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["kind"], "mesh");
  EXPECT_EQ(j["vertices"], 512);
  EXPECT_EQ(j["faces"], 1024);  // 512 quads, triangulated
  // Torus area 4π²Rr = 1.184 for R = 0.3, r = 0.1; the 32×16 polygon is slightly smaller.
  EXPECT_NEAR(j["area"].get<double>(), 1.184, 0.02);
}

// --system reads the process's own mappings: the BLAS named must be a file this machine has, and
// it must agree with what libblas.so.3 resolves to (the library LibTorch links).
TEST(InfoCommand, SystemNamesTheMappedBlasThreadsLibTorchAndGl) {
  const auto r = run_dynscope("info --system --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  for (const char* key : {"cores", "compute_threads", "openmp_threads", "allocator", "blas",
                          "libtorch", "cuda", "torch_intraop_threads", "kernel_isa",
                          "kernel_blocking", "gl_headless"}) {
    EXPECT_TRUE(j.contains(key)) << key << " missing in " << r.output;
  }
  const std::string blas = j["blas"];
  ASSERT_TRUE(std::filesystem::exists(blas)) << blas;
  const auto linked = std::filesystem::canonical("/usr/lib/x86_64-linux-gnu/libblas.so.3");
  if (blas.find("libblas") != std::string::npos) {
    EXPECT_EQ(std::filesystem::canonical(blas), linked);
  }
  EXPECT_EQ(j.contains("warning"), blas.find("/blas/libblas.so") != std::string::npos);
  EXPECT_EQ(j["compute_threads"], "1") << "the default budget is one thread";
  // 16-row blocks of sums only where the kernels run their AVX-512 clone.
  EXPECT_EQ(j["kernel_blocking"], j["kernel_isa"] == "x86-64-v4" ? "wide" : "narrow");
  EXPECT_EQ(j["allocator"].get<std::string>().rfind("dynscope", 0), 0u)
      << "a process that runs the model keeps freed memory: " << j["allocator"];
  const auto none = run_dynscope("info");
  EXPECT_NE(none.exit_code, 0);
  EXPECT_NE(none.output.find("--system"), std::string::npos) << none.output;
}

TEST(InfoCommand, BadInputGivesOneClearLineAndNonZeroExit) {
  const auto missing = run_dynscope("info /nonexistent/scene.h5");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("/nonexistent/scene.h5: no such file"), std::string::npos)
      << missing.output;

  const std::string text = std::filesystem::temp_directory_path() / "dynscope_info_text.txt";
  std::ofstream(text) << "not a scene, not a mesh\n";
  const auto wrong = run_dynscope("info " + text);
  std::remove(text.c_str());
  EXPECT_NE(wrong.exit_code, 0);
  EXPECT_NE(wrong.output.find("dynscope: error: " + text), std::string::npos) << wrong.output;

  const auto no_arg = run_dynscope("info");
  EXPECT_NE(no_arg.exit_code, 0);
  const auto bad_voxel = run_dynscope("info --voxel -1 " + kSource + "/assets/meshes/torus.obj");
  EXPECT_NE(bad_voxel.exit_code, 0);
}

}  // namespace
}  // namespace dynscope
