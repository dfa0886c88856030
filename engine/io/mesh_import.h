// Mesh import through assimp (OBJ, PLY, STL, glTF/GLB, FBX, ... every format assimp reads).
#pragma once

#include <string>

#include "engine/scene/mesh.h"

namespace dynscope {

/// Loads every mesh in the file, triangulated, with node transforms applied, merged into one
/// mesh (duplicate vertices joined). Throws IoError naming the file when assimp cannot read it
/// or the file holds no triangles.
Mesh import_mesh(const std::string& path);

/// True if assimp has an importer for the file's extension.
bool is_mesh_file(const std::string& path);

}  // namespace dynscope
