// PointSetBuffer: one upload per series; frames selected by attribute offsets at draw time.
#include "render/point_set_buffer.h"

#include "engine/core/error.h"

namespace dynscope::render {
namespace {

GLuint upload(const GlFunctions& gl, const std::vector<float>& data) {
  GLuint buffer = 0;
  gl.GenBuffers(1, &buffer);
  gl.BindBuffer(GL_ARRAY_BUFFER, buffer);
  gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data(),
                GL_STATIC_DRAW);
  return buffer;
}

}  // namespace

PointSetBuffer::PointSetBuffer(const GlFunctions& gl, const PointSeries& series) : gl_(gl) {
  series.validate("point series");
  num_frames_ = series.num_frames;
  num_points_ = series.num_points;
  gl_.GenVertexArrays(1, &vao_);
  positions_ = upload(gl_, series.positions);
  bytes_ = series.positions.size() * sizeof(float);
  if (!series.scalars.empty()) {
    scalars_ = upload(gl_, series.scalars);
    bytes_ += series.scalars.size() * sizeof(float);
  }
  if (!series.colors.empty()) {
    colors_ = upload(gl_, series.colors);
    bytes_ += series.colors.size() * sizeof(float);
  }
  gl_.BindVertexArray(vao_);
  // Colours do not change with the frame: bind them once.
  if (colors_) {
    gl_.BindBuffer(GL_ARRAY_BUFFER, colors_);
    gl_.EnableVertexAttribArray(1);
    gl_.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    gl_.VertexAttribDivisor(1, 1);
  }
  gl_.BindVertexArray(0);
  gl_.check("uploading a point series");
}

PointSetBuffer::~PointSetBuffer() {
  const GLuint buffers[] = {positions_, scalars_, colors_};
  for (GLuint b : buffers) {
    if (b) gl_.DeleteBuffers(1, &b);
  }
  if (vao_) gl_.DeleteVertexArrays(1, &vao_);
}

void PointSetBuffer::draw(int frame) const {
  if (!bind(frame, 1)) return;
  gl_.DrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, num_points_);
  gl_.BindVertexArray(0);
}

void PointSetBuffer::draw_sprites(int frame) const {
  // One vertex per point in one plain draw: drivers shade vertices in batches (llvmpipe runs an
  // instanced draw one instance at a time, 12x slower at 100k points).
  if (!bind(frame, 0)) return;
  gl_.DrawArrays(GL_POINTS, 0, num_points_);
  gl_.BindVertexArray(0);
}

bool PointSetBuffer::bind(int frame, GLuint divisor) const {
  if (frame < 0 || frame >= num_frames_) {
    throw ValueError(
        "frame", std::to_string(frame) + " is outside [0, " + std::to_string(num_frames_) + ")");
  }
  if (num_points_ == 0) return false;
  gl_.BindVertexArray(vao_);
  const size_t first = static_cast<size_t>(frame) * num_points_;
  gl_.BindBuffer(GL_ARRAY_BUFFER, positions_);
  gl_.EnableVertexAttribArray(0);
  gl_.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0,
                          reinterpret_cast<const void*>(first * 3 * sizeof(float)));
  gl_.VertexAttribDivisor(0, divisor);
  if (colors_) {
    gl_.VertexAttribDivisor(1, divisor);
  } else {
    gl_.VertexAttrib3f(1, 0.8f, 0.8f, 0.8f);
  }
  if (scalars_) {
    gl_.BindBuffer(GL_ARRAY_BUFFER, scalars_);
    gl_.EnableVertexAttribArray(2);
    gl_.VertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, 0,
                            reinterpret_cast<const void*>(first * sizeof(float)));
    gl_.VertexAttribDivisor(2, divisor);
  } else {
    gl_.VertexAttrib1f(2, 0.0f);
  }
  return true;
}

}  // namespace dynscope::render
