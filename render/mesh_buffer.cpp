// MeshBuffer: expands indexed triangles into corners with crease-angle normals and uploads them.
#include "render/mesh_buffer.h"

#include <cmath>

#include "engine/core/error.h"

namespace dynscope::render {

std::vector<float> crease_normals(const MeshGeometry& geometry, double crease_angle_deg) {
  const auto& v = geometry.vertices;
  const auto& f = geometry.faces;
  const size_t num_vertices = v.size() / 3, num_faces = f.size() / 3;
  for (uint32_t index : f) {
    if (index >= num_vertices) {
      throw ValueError("mesh", "face index " + std::to_string(index) + " >= vertex count " +
                                   std::to_string(num_vertices));
    }
  }
  auto vertex = [&](uint32_t i) { return Eigen::Vector3d(v[3 * i], v[3 * i + 1], v[3 * i + 2]); };
  // Area-weighted face normals (the cross product's length is twice the area).
  std::vector<Eigen::Vector3d> face_normal(num_faces);
  std::vector<std::vector<uint32_t>> faces_of_vertex(num_vertices);
  for (size_t t = 0; t < num_faces; ++t) {
    const Eigen::Vector3d a = vertex(f[3 * t]), b = vertex(f[3 * t + 1]), c = vertex(f[3 * t + 2]);
    face_normal[t] = (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) faces_of_vertex[f[3 * t + k]].push_back(static_cast<uint32_t>(t));
  }
  const double cos_crease = std::cos(crease_angle_deg * 3.14159265358979323846 / 180.0);
  std::vector<float> normals(num_faces * 9);
  for (size_t t = 0; t < num_faces; ++t) {
    const Eigen::Vector3d own = face_normal[t].normalized();
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (uint32_t other : faces_of_vertex[f[3 * t + k]]) {
        if (face_normal[other].normalized().dot(own) >= cos_crease) sum += face_normal[other];
      }
      const Eigen::Vector3d n = sum.norm() > 0 ? sum.normalized() : own;
      for (int d = 0; d < 3; ++d) normals[t * 9 + k * 3 + d] = static_cast<float>(n[d]);
    }
  }
  return normals;
}

MeshBuffer::MeshBuffer(const GlFunctions& gl, const MeshGeometry& geometry) : gl_(gl) {
  const std::vector<float> normals = crease_normals(geometry, kCreaseAngleDeg);
  triangles_ = static_cast<int>(geometry.faces.size() / 3);
  std::vector<float> interleaved;
  interleaved.reserve(static_cast<size_t>(triangles_) * 18);
  for (size_t corner = 0; corner < geometry.faces.size(); ++corner) {
    const uint32_t i = geometry.faces[corner];
    for (int d = 0; d < 3; ++d) interleaved.push_back(geometry.vertices[3 * i + d]);
    for (int d = 0; d < 3; ++d) interleaved.push_back(normals[corner * 3 + d]);
  }
  bytes_ = interleaved.size() * sizeof(float);
  gl_.GenVertexArrays(1, &vao_);
  gl_.GenBuffers(1, &vbo_);
  gl_.BindVertexArray(vao_);
  gl_.BindBuffer(GL_ARRAY_BUFFER, vbo_);
  gl_.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(bytes_), interleaved.data(),
                 GL_STATIC_DRAW);
  gl_.EnableVertexAttribArray(0);
  gl_.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  gl_.EnableVertexAttribArray(1);
  gl_.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                          reinterpret_cast<const void*>(3 * sizeof(float)));
  gl_.BindVertexArray(0);
  gl_.check("uploading a mesh");
}

MeshBuffer::~MeshBuffer() {
  if (vbo_) gl_.DeleteBuffers(1, &vbo_);
  if (vao_) gl_.DeleteVertexArrays(1, &vao_);
}

void MeshBuffer::draw() const {
  if (triangles_ == 0) return;
  gl_.BindVertexArray(vao_);
  gl_.DrawArrays(GL_TRIANGLES, 0, triangles_ * 3);
  gl_.BindVertexArray(0);
}

}  // namespace dynscope::render
