// MeshBuffer: a triangle mesh on the GPU with crease-angle normals, uploaded once.
#pragma once

#include <cstddef>

#include "render/gl_functions.h"
#include "render/render_scene.h"

namespace dynscope::render {

/// GPU copy of a MeshGeometry as unindexed triangles (position + normal per corner). Normals are
/// averaged over neighbouring faces within `kCreaseAngleDeg`, so boxes stay sharp and spheres
/// smooth. The owning context must be current for every call, including destruction.
class MeshBuffer {
 public:
  static constexpr double kCreaseAngleDeg = 40.0;

  /// Uploads `geometry`; throws ValueError if a face index is out of range.
  MeshBuffer(const GlFunctions& gl, const MeshGeometry& geometry);
  ~MeshBuffer();
  MeshBuffer(const MeshBuffer&) = delete;
  MeshBuffer& operator=(const MeshBuffer&) = delete;

  int num_triangles() const { return triangles_; }
  size_t bytes() const { return bytes_; }
  /// Draws the triangles (mesh.vert: location 0 position, 1 normal) with the bound program.
  void draw() const;

 private:
  const GlFunctions& gl_;
  GLuint vao_ = 0;
  GLuint vbo_ = 0;
  int triangles_ = 0;
  size_t bytes_ = 0;
};

/// Corner normals `[F*3,3]` of `geometry` with the crease rule above (exposed for tests).
std::vector<float> crease_normals(const MeshGeometry& geometry, double crease_angle_deg);

}  // namespace dynscope::render
