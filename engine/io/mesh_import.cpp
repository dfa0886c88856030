// Mesh import through assimp: triangulate, bake node transforms, merge, weld by position.
#include "engine/io/mesh_import.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <filesystem>
#include <unordered_map>

#include "engine/core/error.h"

namespace dynscope {
namespace {

struct PositionHash {
  size_t operator()(const Vec3& p) const {
    size_t h = 0;
    for (int i = 0; i < 3; ++i) {
      // +0.0 so that -0.0 and 0.0 hash alike (they compare equal).
      h = h * 1000003u ^ std::hash<double>()(p[i] + 0.0);
    }
    return h;
  }
};

struct PositionEqual {
  bool operator()(const Vec3& a, const Vec3& b) const { return a == b; }
};

}  // namespace

bool is_mesh_file(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (ext.size() < 2) return false;
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  Assimp::Importer importer;
  return importer.IsExtensionSupported(ext.c_str());
}

Mesh import_mesh(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw IoError(path, "no such file");
  if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path, "not a regular file");
  Assimp::Importer importer;
  // Points and lines are sorted into their own meshes and then removed: only surfaces matter.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                  aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (scene == nullptr) throw IoError(path, std::string("assimp: ") + importer.GetErrorString());

  // One mesh for the whole file. Vertices are welded by exact position across all meshes
  // (assimp joins only within a mesh and keeps copies that differ in normals or UVs, e.g. STL's
  // per-face normals), so shared corners become shared vertices.
  std::unordered_map<Vec3, int32_t, PositionHash, PositionEqual> index_of;
  std::vector<Vec3> vertices;
  std::vector<Eigen::Matrix<int32_t, 1, 3>> faces;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    std::vector<int32_t> remap(mesh->mNumVertices);
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      const Vec3 q(p.x, p.y, p.z);
      const auto [it, inserted] = index_of.try_emplace(q, static_cast<int32_t>(vertices.size()));
      if (inserted) vertices.push_back(q);
      remap[v] = it->second;
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;
      const Eigen::Matrix<int32_t, 1, 3> tri(remap[face.mIndices[0]], remap[face.mIndices[1]],
                                             remap[face.mIndices[2]]);
      // Welding can collapse a sliver triangle onto an edge; it has no area to keep.
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
      faces.push_back(tri);
    }
  }
  if (faces.empty()) throw IoError(path, "contains no triangles");

  // Vertices used by no kept triangle (from dropped points/lines) are removed; the others keep
  // their order.
  std::vector<int32_t> compact(vertices.size(), -1);
  for (const auto& tri : faces) {
    for (int c = 0; c < 3; ++c) compact[static_cast<size_t>(tri[c])] = 0;
  }
  Mesh out;
  int32_t used = 0;
  for (int32_t& k : compact) {
    if (k == 0) k = used++;
  }
  out.vertices.resize(used, 3);
  for (size_t v = 0; v < vertices.size(); ++v) {
    if (compact[v] >= 0) out.vertices.row(compact[v]) = vertices[v].transpose();
  }
  out.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) {
    for (int c = 0; c < 3; ++c) {
      out.faces(static_cast<Eigen::Index>(f), c) = compact[static_cast<size_t>(faces[f][c])];
    }
  }
  if (!out.vertices.allFinite()) throw IoError(path, "contains non-finite vertex coordinates");
  return out;
}

}  // namespace dynscope
