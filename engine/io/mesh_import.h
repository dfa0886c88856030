// Mesh import through assimp (OBJ, PLY, STL, glTF/GLB, FBX, ... every format assimp reads).
#pragma once

#include <cstdint>
#include <string>

#include "engine/scene/mesh.h"

namespace dynscope {

/// Limits of one mesh import, checked before the importer allocates.
struct MeshImportOptions {
  /// Memory the import may need, in bytes: larger files, and files whose header declares more
  /// vertices or faces than fit in it (e.g. an OFF or PLY count of 10^11), are refused.
  uint64_t max_memory_bytes = uint64_t{1} << 30;
  /// Import in a child process (POSIX fork) limited to max_memory_bytes and max_seconds, so a
  /// crash, hang or allocation storm inside the importer becomes an IoError instead of ending
  /// the caller (the viewer survives any file).
  bool isolate = true;
  /// Wall-clock limit of an isolated import, in seconds.
  double max_seconds = 10.0;
};

/// Loads every mesh in the file, triangulated, with node transforms applied, merged into one
/// mesh in the file's own units and axes: several objects (e.g. OBJ `o` groups) become one
/// Mesh, because a file is imported as one object. Vertices at exactly the same position are
/// joined across the whole file, points and lines are dropped, and so are triangles that
/// joining collapses. Throws IoError naming the file when assimp cannot read it, when the file
/// holds no triangles, when its declared counts exceed what the file can hold or the memory
/// ceiling of `options`, or when the imported data is inconsistent (indices out of range,
/// non-finite coordinates).
Mesh import_mesh(const std::string& path, const MeshImportOptions& options = {});

/// True if assimp has an importer for the file's extension.
bool is_mesh_file(const std::string& path);

}  // namespace dynscope
