// Mesh import through assimp (OBJ, PLY, STL, glTF/GLB, FBX, ... every format assimp reads).
#pragma once

#include <string>

#include "engine/scene/mesh.h"

namespace dynscope {

/// Loads every mesh in the file, triangulated, with node transforms applied, merged into one
/// mesh in the file's own units and axes: several objects (e.g. OBJ `o` groups) become one
/// Mesh, because a file is imported as one object. Vertices at exactly the same position are
/// joined across the whole file, points and lines are dropped, and so are triangles that
/// joining collapses. Throws IoError naming the file when assimp cannot read it or the file
/// holds no triangles.
Mesh import_mesh(const std::string& path);

/// True if assimp has an importer for the file's extension.
bool is_mesh_file(const std::string& path);

}  // namespace dynscope
