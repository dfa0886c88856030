// Renderer: draws a RenderScene through a Camera into the current context (the mjr_render half).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "render/camera.h"
#include "render/gl_context.h"
#include "render/gl_functions.h"
#include "render/image.h"
#include "render/render_scene.h"
#include "render/shader_program.h"

namespace dynscope::render {

class MeshBuffer;
class PointSetBuffer;

/// A rectangle of the framebuffer in pixels, origin bottom-left (GL's convention, MuJoCo mjrRect).
struct Rect {
  int x = 0, y = 0;
  int width = 0, height = 0;
  /// True if pixel (px, py) (same origin) lies inside.
  bool contains(int px, int py) const {
    return px >= x && px < x + width && py >= y && py < y + height;
  }
  bool operator==(const Rect& o) const {
    return x == o.x && y == o.y && width == o.width && height == o.height;
  }
};

/// Index of the first of `rects` containing pixel (x, y) (origin bottom-left), or -1.
int find_rect(int x, int y, const std::vector<Rect>& rects);

/// What a pixel shows in the picking pass.
struct PickResult {
  int layer = -1;  ///< Index into RenderScene::points, -1 for none.
  int point = -1;  ///< Point index within that layer's series, -1 for none.
  bool hit() const { return layer >= 0; }
};

/// Draws RenderScenes with one GL context. Point series and mesh geometries are uploaded the first
/// time they are drawn and reused while their shared_ptr lives (scrubbing frames only changes
/// offsets and uniforms); they are treated as immutable once drawn. All calls need the context
/// current on the calling thread.
class Renderer {
 public:
  /// Loads the GL table from `context` (made current), compiles every program and sets up
  /// `samples`-times multisampling (0 or 1: none). Throws Error if GL or a shader fails.
  explicit Renderer(GlContext& context, int samples = 4);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Draws `scene` seen by `camera` into the context's default framebuffer (its full size).
  /// Throws ValueError if the scene is inconsistent.
  void render(const RenderScene& scene, const Camera& camera);
  /// Draws `scene` with the whole window's projection but clears and writes only `viewport`
  /// (scissored, multisample resolve included), so side-by-side views share one camera frame.
  /// Throws ValueError if the scene is inconsistent or the rectangle lies outside the window.
  void render(const RenderScene& scene, const Camera& camera, const Rect& viewport);
  /// Clears the whole default framebuffer to `color` (nothing to draw).
  void clear(const Color& color);
  /// render() followed by the context's read_pixels().
  Image render_image(const RenderScene& scene, const Camera& camera);
  /// Which pickable, opaque point is visible at pixel (x, y) (origin top-left) when `scene` is
  /// drawn with `camera`; meshes occlude points. Draws off-screen only.
  PickResult pick(const RenderScene& scene, const Camera& camera, int x, int y);

  const GlFunctions& gl() const { return gl_; }
  GlContext& context() { return context_; }
  /// Number of point-series and mesh uploads so far (tests check that scrubbing adds none).
  int64_t upload_count() const { return uploads_; }
  /// Point series and meshes currently held on the GPU.
  size_t cached_buffers() const { return point_buffers_.size() + mesh_buffers_.size(); }

 private:
  struct Target;
  template <typename Buffer, typename Source>
  struct CacheEntry {
    std::weak_ptr<const Source> source;
    std::unique_ptr<Buffer> buffer;
  };

  const PointSetBuffer& point_buffer(const std::shared_ptr<const PointSeries>& series);
  const MeshBuffer& mesh_buffer(const std::shared_ptr<const MeshGeometry>& geometry);
  void evict_expired();
  GLuint colormap_texture(const std::string& name);
  void ensure_target(Target& target, int width, int height, int samples);
  void draw_scene(const RenderScene& scene, const Camera& camera, int width, int height);
  void draw_points(const PointLayer& layer, bool discs, const Eigen::Matrix4f& view,
                   const Eigen::Matrix4f& proj, const Eigen::Vector3f& light, int height);
  void draw_meshes(const RenderScene& scene, bool translucent, const Eigen::Matrix4f& view,
                   const Eigen::Matrix4f& proj, const Eigen::Vector3f& light);
  void draw_lines_and_boxes(const RenderScene& scene, const Eigen::Matrix4f& view,
                            const Eigen::Matrix4f& proj);

  GlContext& context_;
  GlFunctions gl_;
  int samples_ = 0;
  float max_line_width_ = 1.0f;
  std::map<std::string, ShaderProgram> programs_;
  std::map<std::string, GLuint> colormaps_;
  std::unordered_map<const void*, CacheEntry<PointSetBuffer, PointSeries>> point_buffers_;
  std::unordered_map<const void*, CacheEntry<MeshBuffer, MeshGeometry>> mesh_buffers_;
  std::unique_ptr<Target> msaa_;
  std::unique_ptr<Target> pick_;
  GLuint empty_vao_ = 0;
  GLuint line_vao_ = 0, line_vbo_ = 0;
  GLuint box_vao_ = 0, box_vbo_ = 0;
  int64_t uploads_ = 0;
};

}  // namespace dynscope::render
