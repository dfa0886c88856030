// Tests of mesh import through assimp: formats, node transforms, merging, welding, errors.
#include "engine/io/mesh_import.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "tests/io/io_test_util.h"

namespace dynscope {
namespace {

using test::error_of;
using test::expect_contains;

const char* kCubeObj = R"(# unit cube, quads, counter-clockwise seen from outside
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
)";

std::string base64(const std::vector<uint8_t>& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const uint32_t b0 = bytes[i];
    const uint32_t b1 = i + 1 < bytes.size() ? bytes[i + 1] : 0;
    const uint32_t b2 = i + 2 < bytes.size() ? bytes[i + 2] : 0;
    const uint32_t n = (b0 << 16) | (b1 << 8) | b2;
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[n & 63] : '=';
  }
  return out;
}

// Every face normal points away from the mesh centroid (true for convex closed meshes).
void expect_outward(const Mesh& m) {
  const Vec3 centre = m.vertices.colwise().mean().transpose();
  for (Eigen::Index f = 0; f < m.num_faces(); ++f) {
    const Vec3 a = m.vertices.row(m.faces(f, 0)).transpose();
    const Vec3 b = m.vertices.row(m.faces(f, 1)).transpose();
    const Vec3 c = m.vertices.row(m.faces(f, 2)).transpose();
    EXPECT_GT((b - a).cross(c - a).dot((a + b + c) / 3 - centre), 0.0) << "face " << f;
  }
}

class MeshImportTest : public ::testing::Test {
 protected:
  test::TempDir dir_;
};

TEST_F(MeshImportTest, ObjQuadsAreTriangulatedAndKeepTheirWinding) {
  const std::string path = dir_.file("cube.obj");
  test::write_text(path, kCubeObj);
  const Mesh m = import_mesh(path);
  EXPECT_EQ(m.num_vertices(), 8);
  EXPECT_EQ(m.num_faces(), 12);
  EXPECT_NEAR(m.area(), 6.0, 1e-12);
  EXPECT_EQ(m.vertices.colwise().minCoeff(), Eigen::RowVector3d(0, 0, 0));
  EXPECT_EQ(m.vertices.colwise().maxCoeff(), Eigen::RowVector3d(1, 1, 1));
  expect_outward(m);
}

TEST_F(MeshImportTest, ObjObjectsAreMergedIntoOneMesh) {
  std::string text = std::string("o first\n") + kCubeObj + "o second\n";
  for (const char* v : {"3 0 0", "4 0 0", "4 1 0", "3 1 0", "3 0 1", "4 0 1", "4 1 1", "3 1 1"}) {
    text += std::string("v ") + v + "\n";
  }
  text += "f 9 12 11 10\nf 13 14 15 16\nf 9 10 14 13\nf 10 11 15 14\nf 11 12 16 15\nf 12 9 13 16\n";
  const std::string path = dir_.file("two.obj");
  test::write_text(path, text);
  const Mesh m = import_mesh(path);
  EXPECT_EQ(m.num_vertices(), 16);
  EXPECT_EQ(m.num_faces(), 24);
  EXPECT_NEAR(m.area(), 12.0, 1e-12);
  EXPECT_DOUBLE_EQ(m.vertices.col(0).maxCoeff(), 4.0);
}

TEST_F(MeshImportTest, PointsAndLinesAreDropped) {
  const std::string path = dir_.file("mixed.obj");
  test::write_text(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\np 4\nl 1 4\nf 1 2 3\n");
  const Mesh m = import_mesh(path);
  EXPECT_EQ(m.num_faces(), 1);
  EXPECT_EQ(m.num_vertices(), 3) << "the vertex used only by the point and line is dropped";
  EXPECT_NEAR(m.area(), 0.5, 1e-12);
}

TEST_F(MeshImportTest, AsciiPly) {
  const std::string path = dir_.file("tetra.ply");
  test::write_text(path,
                   "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                   "property float z\nelement face 4\nproperty list uchar int vertex_indices\n"
                   "end_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  const Mesh m = import_mesh(path);
  EXPECT_EQ(m.num_vertices(), 4);
  EXPECT_EQ(m.num_faces(), 4);
  EXPECT_NEAR(m.area(), 1.5 + std::sqrt(3.0) / 2.0, 1e-6);
  expect_outward(m);
}

TEST_F(MeshImportTest, AsciiStlVerticesAreWelded) {
  // STL repeats each corner per facet, with per-facet normals; shared corners are joined.
  const std::string path = dir_.file("square.stl");
  test::write_text(path,
                   "solid square\n"
                   "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\n"
                   "endloop\nendfacet\n"
                   "facet normal 0 0.1 0.99\nouter loop\nvertex 0 0 0\nvertex 1 1 0\n"
                   "vertex 0 1 0\nendloop\nendfacet\n"
                   "endsolid square\n");
  const Mesh m = import_mesh(path);
  EXPECT_EQ(m.num_vertices(), 4);
  EXPECT_EQ(m.num_faces(), 2);
  EXPECT_NEAR(m.area(), 1.0, 1e-12);
}

TEST_F(MeshImportTest, GltfNodeTransformsAreApplied) {
  // One triangle, instanced by two child nodes (translations) of a parent scaled by 2.
  std::vector<uint8_t> buffer;
  auto put = [&](const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    buffer.insert(buffer.end(), b, b + n);
  };
  const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint16_t indices[4] = {0, 1, 2, 0};
  put(positions, sizeof positions);
  put(indices, sizeof indices);
  const std::string gltf = R"({
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0]}],
    "nodes": [{"scale": [2, 2, 2], "children": [1, 2]},
              {"translation": [10, 0, 0], "mesh": 0},
              {"translation": [0, 0, 5], "mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,)" +
                           base64(buffer) + R"("}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                    {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                   "min": [0, 0, 0], "max": [1, 1, 0]},
                  {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]
  })";
  const std::string path = dir_.file("instanced.gltf");
  test::write_text(path, gltf);
  const Mesh m = import_mesh(path);
  EXPECT_EQ(m.num_vertices(), 6);
  EXPECT_EQ(m.num_faces(), 2);
  EXPECT_NEAR(m.area(), 4.0, 1e-9);
  std::vector<Vec3> corners;
  for (Eigen::Index i = 0; i < m.num_vertices(); ++i) corners.push_back(m.vertices.row(i));
  for (const Vec3& want : {Vec3(20, 0, 0), Vec3(22, 0, 0), Vec3(20, 2, 0), Vec3(0, 0, 10),
                           Vec3(2, 0, 10), Vec3(0, 2, 10)}) {
    EXPECT_TRUE(std::any_of(corners.begin(), corners.end(), [&](const Vec3& c) {
      return (c - want).norm() < 1e-6;
    })) << want.transpose();
  }
}

TEST_F(MeshImportTest, NonMeshFilesThrowIoErrorNamingTheFile) {
  const std::string text = dir_.file("notes.txt");
  test::write_text(text, "shopping list: eggs, flour, 3 lemons\n");
  expect_contains(error_of<IoError>([&] { import_mesh(text); }), {text + ": "});
  const std::string binary = dir_.file("garbage.stl");
  std::string bytes;
  for (int i = 0; i < 37; ++i) bytes.push_back(static_cast<char>((i * 131 + 7) % 256));
  test::write_text(binary, bytes);
  expect_contains(error_of<IoError>([&] { import_mesh(binary); }), {binary + ": "});
  const std::string lines = dir_.file("lines.obj");
  test::write_text(lines, "v 0 0 0\nv 1 0 0\nl 1 2\n");
  expect_contains(error_of<IoError>([&] { import_mesh(lines); }), {lines + ": "});
  const std::string missing = dir_.file("missing.obj");
  expect_contains(error_of<IoError>([&] { import_mesh(missing); }), {missing, "no such file"});
}

// The OFF file of assimp's corpus that made the importer reserve 3.5e11 vertices (309 bytes).
const char* kHugeOff = R"(OFF
353535235358 6 0
-0.5 -0.5 0.5
0.5 -0.5 0.5
-0.5 0.5 0.5
0.5 0.5 0.5
-0.5 0.5 -0.5
0.5 0.5 -0.5
-0.5 -0.5 -0.5
0.5 -0.5 -0.5
4 0 1 3 2
4 2 3 5 4
4 4 5 7 6
4 6 7 1 0
4 1 7 5 3
4 6 0 2 4
)";

TEST_F(MeshImportTest, DeclaredCountsBeyondTheFileAreRefusedBeforeImport) {
  const std::string off = dir_.file("huge.off");
  test::write_text(off, kHugeOff);
  expect_contains(error_of<IoError>([&] { import_mesh(off); }),
                  {off, "header declares 353535235358 vertices", "corrupt or truncated"});

  // Binary PLY: 10^9 float vertices cannot fit in a few dozen bytes.
  const std::string ply = dir_.file("huge.ply");
  test::write_text(ply,
                   "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\n"
                   "property float x\nproperty float y\nproperty float z\nelement face 1\n"
                   "property list uchar int vertex_indices\nend_header\n0123456789abcdef");
  expect_contains(error_of<IoError>([&] { import_mesh(ply); }),
                  {ply, "header declares", "only 16 follow"});

  // A PLY header cut short (assimp's reader can spin on it).
  const std::string cut = dir_.file("cut.ply");
  test::write_text(cut, "ply\nformat ascii 1.0\nelement vertex 3\nproperty fl");
  expect_contains(error_of<IoError>([&] { import_mesh(cut); }), {cut, "without end_header"});

  // Elements without properties take no bytes: the memory ceiling bounds them instead.
  const std::string empty = dir_.file("empty_elements.ply");
  test::write_text(empty,
                   "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
                   "end_header\n");
  expect_contains(error_of<IoError>([&] { import_mesh(empty); }),
                  {empty, "more than the mesh import limit"});
}

TEST_F(MeshImportTest, MemoryCeilingIsConfigurable) {
  const std::string path = dir_.file("cube.off");
  test::write_text(path, std::string(kHugeOff).replace(4, 12, "8"));  // the honest header
  EXPECT_EQ(import_mesh(path).num_faces(), 12);
  MeshImportOptions tight;
  tight.max_memory_bytes = 1000;  // 8 vertices + 6 faces need more than this
  expect_contains(error_of<IoError>([&] { import_mesh(path, tight); }),
                  {path, "more than the mesh import limit"});
  tight.max_memory_bytes = 100;  // smaller than the file itself
  expect_contains(error_of<IoError>([&] { import_mesh(path, tight); }),
                  {path, "more than the mesh import limit"});
}

TEST_F(MeshImportTest, FaceIndexPastTheVerticesIsAnError) {
  const std::string path = dir_.file("bad_index.ply");
  test::write_text(path,
                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                   "property float y\nproperty float z\nelement face 1\n"
                   "property list uchar int vertex_indices\nend_header\n"
                   "0 0 0\n1 0 0\n0 1 0\n3 0 1 2000000000\n");
  expect_contains(error_of<IoError>([&] { import_mesh(path); }), {path + ": "});
}

TEST_F(MeshImportTest, IsolatedImportIsBoundedInTimeAndMatchesTheInProcessOne) {
  const std::string path = dir_.file("cube.obj");
  test::write_text(path, kCubeObj);
  MeshImportOptions here;
  here.isolate = false;
  const Mesh isolated = import_mesh(path);
  const Mesh local = import_mesh(path, here);
  EXPECT_EQ(isolated.vertices, local.vertices);
  EXPECT_EQ(isolated.faces, local.faces);
  MeshImportOptions no_time;
  no_time.max_seconds = 0.0;
  expect_contains(error_of<IoError>([&] { import_mesh(path, no_time); }),
                  {path, "did not finish within"});
}

TEST(MeshFile, RecognisesAssimpExtensions) {
  EXPECT_TRUE(is_mesh_file("a/b/cube.obj"));
  EXPECT_TRUE(is_mesh_file("CUBE.STL"));
  EXPECT_TRUE(is_mesh_file("scene.glb"));
  EXPECT_TRUE(is_mesh_file("tetra.ply"));
  EXPECT_FALSE(is_mesh_file("scene.h5"));
  EXPECT_FALSE(is_mesh_file("notes.txt"));
  EXPECT_FALSE(is_mesh_file("no_extension"));
}

}  // namespace
}  // namespace dynscope
