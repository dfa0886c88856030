// PointSetBuffer: a point series on the GPU (all frames in one VBO), drawn frame by frame by
// offset.
#pragma once

#include <cstddef>

#include "render/gl_functions.h"
#include "render/render_scene.h"

namespace dynscope::render {

/// GPU copy of a PointSeries: positions `[T,N,3]` and scalars `[T,N]` each in one buffer, colours
/// `[N,3]` in another. Drawing frame f only moves attribute offsets: no upload, no shader change.
/// The owning context must be current for every call, including destruction.
class PointSetBuffer {
 public:
  /// Uploads `series` (validated first; throws ValueError if inconsistent).
  PointSetBuffer(const GlFunctions& gl, const PointSeries& series);
  ~PointSetBuffer();
  PointSetBuffer(const PointSetBuffer&) = delete;
  PointSetBuffer& operator=(const PointSetBuffer&) = delete;

  int num_frames() const { return num_frames_; }
  int num_points() const { return num_points_; }
  bool has_scalars() const { return scalars_ != 0; }
  bool has_colors() const { return colors_ != 0; }
  /// Bytes held on the GPU.
  size_t bytes() const { return bytes_; }

  /// Draws frame `frame` as instanced 4-vertex strips (points.vert: location 0 centre, 1 colour,
  /// 2 scalar) with the currently bound program; throws ValueError if the frame is out of range.
  void draw(int frame) const;
  /// Draws frame `frame` as one point sprite per point (discs.vert, same attributes); throws
  /// ValueError if the frame is out of range.
  void draw_sprites(int frame) const;

 private:
  /// Binds frame `frame`'s attribute offsets, advanced per instance (divisor 1) or per vertex
  /// (0); false when there is nothing to draw.
  bool bind(int frame, GLuint divisor) const;

  const GlFunctions& gl_;
  int num_frames_ = 0;
  int num_points_ = 0;
  GLuint vao_ = 0;
  GLuint positions_ = 0;
  GLuint scalars_ = 0;
  GLuint colors_ = 0;
  size_t bytes_ = 0;
};

}  // namespace dynscope::render
