// Renderer: GL state, programs, buffer caches and the draw order of a RenderScene.
#include "render/renderer.h"

#include <algorithm>

#include "engine/core/error.h"
#include "engine/core/log.h"
#include "render/mesh_buffer.h"
#include "render/point_set_buffer.h"

namespace dynscope::render {

/// An off-screen framebuffer with colour and depth renderbuffers.
struct Renderer::Target {
  GLuint fbo = 0, color = 0, depth = 0;
  int width = 0, height = 0, samples = 0;
};

namespace {

// Key light from above, slightly in front and to the left of the default (iso) view.
const Eigen::Vector3f kLightWorld = Eigen::Vector3f(-0.35f, -0.55f, 1.0f).normalized();

}  // namespace

Renderer::Renderer(GlContext& context, int samples) : context_(context) {
  context_.make_current();
  gl_.load(context_);
  log_debug("renderer: ", gl_.describe());
  if (samples > 1) {
    GLint max_samples = 1;
    gl_.GetIntegerv(GL_MAX_SAMPLES, &max_samples);
    samples_ = std::min(samples, static_cast<int>(max_samples));
    if (samples_ < 2) samples_ = 0;
  }
  GLfloat range[2] = {1.0f, 1.0f};
  gl_.GetFloatv(GL_ALIASED_LINE_WIDTH_RANGE, range);
  max_line_width_ = std::max(1.0f, range[1]);
  for (const ProgramSources& p : renderer_programs()) {
    programs_.emplace(p.name, ShaderProgram::from_embedded(gl_, p.vertex, p.fragment));
  }
  gl_.GenVertexArrays(1, &empty_vao_);
  gl_.GenVertexArrays(1, &line_vao_);
  gl_.GenBuffers(1, &line_vbo_);
  gl_.BindVertexArray(line_vao_);
  gl_.BindBuffer(GL_ARRAY_BUFFER, line_vbo_);
  gl_.EnableVertexAttribArray(0);
  gl_.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  gl_.EnableVertexAttribArray(1);
  gl_.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                          reinterpret_cast<const void*>(3 * sizeof(float)));
  gl_.GenVertexArrays(1, &box_vao_);
  gl_.GenBuffers(1, &box_vbo_);
  gl_.BindVertexArray(box_vao_);
  gl_.BindBuffer(GL_ARRAY_BUFFER, box_vbo_);
  for (GLuint a = 0; a < 3; ++a) {
    gl_.EnableVertexAttribArray(a);
    gl_.VertexAttribPointer(a, 3, GL_FLOAT, GL_FALSE, 9 * sizeof(float),
                            reinterpret_cast<const void*>(a * 3 * sizeof(float)));
    gl_.VertexAttribDivisor(a, 1);
  }
  gl_.BindVertexArray(0);
  msaa_ = std::make_unique<Target>();
  pick_ = std::make_unique<Target>();
  gl_.check("renderer setup");
}

Renderer::~Renderer() {
  try {
    context_.make_current();
  } catch (const std::exception&) {
    return;  // The context is gone; its objects went with it.
  }
  point_buffers_.clear();
  mesh_buffers_.clear();
  programs_.clear();
  for (auto& [name, texture] : colormaps_) gl_.DeleteTextures(1, &texture);
  for (Target* t : {msaa_.get(), pick_.get()}) {
    if (t->fbo) gl_.DeleteFramebuffers(1, &t->fbo);
    if (t->color) gl_.DeleteRenderbuffers(1, &t->color);
    if (t->depth) gl_.DeleteRenderbuffers(1, &t->depth);
  }
  const GLuint vaos[] = {empty_vao_, line_vao_, box_vao_};
  gl_.DeleteVertexArrays(3, vaos);
  const GLuint buffers[] = {line_vbo_, box_vbo_};
  gl_.DeleteBuffers(2, buffers);
}

const PointSetBuffer& Renderer::point_buffer(const std::shared_ptr<const PointSeries>& series) {
  auto& entry = point_buffers_[series.get()];
  // An expired weak_ptr means a different series now lives at this address: upload again.
  if (!entry.buffer || entry.source.expired()) {
    entry.buffer = std::make_unique<PointSetBuffer>(gl_, *series);
    entry.source = series;
    ++uploads_;
  }
  return *entry.buffer;
}

const MeshBuffer& Renderer::mesh_buffer(const std::shared_ptr<const MeshGeometry>& geometry) {
  auto& entry = mesh_buffers_[geometry.get()];
  if (!entry.buffer || entry.source.expired()) {
    entry.buffer = std::make_unique<MeshBuffer>(gl_, *geometry);
    entry.source = geometry;
    ++uploads_;
  }
  return *entry.buffer;
}

void Renderer::evict_expired() {
  for (auto it = point_buffers_.begin(); it != point_buffers_.end();) {
    it = it->second.source.expired() ? point_buffers_.erase(it) : std::next(it);
  }
  for (auto it = mesh_buffers_.begin(); it != mesh_buffers_.end();) {
    it = it->second.source.expired() ? mesh_buffers_.erase(it) : std::next(it);
  }
}

GLuint Renderer::colormap_texture(const std::string& name) {
  auto it = colormaps_.find(name);
  if (it != colormaps_.end()) return it->second;
  const std::vector<uint8_t> table = colormap_table(name);
  GLuint texture = 0;
  gl_.GenTextures(1, &texture);
  gl_.BindTexture(GL_TEXTURE_2D, texture);
  gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, 256, 1, 0, GL_RGBA, GL_UNSIGNED_BYTE, table.data());
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  colormaps_[name] = texture;
  return texture;
}

void Renderer::ensure_target(Target& t, int width, int height, int samples) {
  if (t.fbo && t.width == width && t.height == height && t.samples == samples) return;
  if (!t.fbo) {
    gl_.GenFramebuffers(1, &t.fbo);
    gl_.GenRenderbuffers(1, &t.color);
    gl_.GenRenderbuffers(1, &t.depth);
  }
  t.width = width;
  t.height = height;
  t.samples = samples;
  gl_.BindRenderbuffer(GL_RENDERBUFFER, t.color);
  gl_.RenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, width, height);
  gl_.BindRenderbuffer(GL_RENDERBUFFER, t.depth);
  gl_.RenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, width, height);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, t.fbo);
  gl_.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, t.color);
  gl_.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t.depth);
  const GLenum status = gl_.CheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    throw Error("renderer: off-screen framebuffer " + std::to_string(width) + "x" +
                std::to_string(height) + " with " + std::to_string(samples) +
                " samples is incomplete (status " + std::to_string(status) + ")");
  }
}

int find_rect(int x, int y, const std::vector<Rect>& rects) {
  for (size_t i = 0; i < rects.size(); ++i) {
    if (rects[i].contains(x, y)) return static_cast<int>(i);
  }
  return -1;
}

void Renderer::render(const RenderScene& scene, const Camera& camera) {
  render(scene, camera, Rect{0, 0, context_.width(), context_.height()});
}

void Renderer::render(const RenderScene& scene, const Camera& camera, const Rect& viewport) {
  scene.validate();
  camera.validate();
  const int w = context_.width(), h = context_.height();
  const Rect& r = viewport;
  if (r.width <= 0 || r.height <= 0 || r.x < 0 || r.y < 0 || r.x + r.width > w ||
      r.y + r.height > h) {
    throw ValueError("viewport", std::to_string(r.width) + "x" + std::to_string(r.height) + "+" +
                                     std::to_string(r.x) + "+" + std::to_string(r.y) +
                                     " is outside the " + std::to_string(w) + "x" +
                                     std::to_string(h) + " window");
  }
  evict_expired();
  const bool partial = !(r == Rect{0, 0, w, h});
  if (samples_ > 1) {
    ensure_target(*msaa_, w, h, samples_);
    gl_.BindFramebuffer(GL_FRAMEBUFFER, msaa_->fbo);
  } else {
    gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  // The scissor limits the clear, the drawing and the multisample resolve to the viewport.
  if (partial) {
    gl_.Enable(GL_SCISSOR_TEST);
    gl_.Scissor(r.x, r.y, r.width, r.height);
  }
  draw_scene(scene, camera, w, h);
  if (samples_ > 1) {
    // Resolve the multisampled image into the context's own framebuffer.
    gl_.BindFramebuffer(GL_READ_FRAMEBUFFER, msaa_->fbo);
    gl_.BindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
    gl_.BlitFramebuffer(r.x, r.y, r.x + r.width, r.y + r.height, r.x, r.y, r.x + r.width,
                        r.y + r.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  if (partial) gl_.Disable(GL_SCISSOR_TEST);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl_.check("render");
}

void Renderer::clear(const Color& color) {
  gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl_.Viewport(0, 0, context_.width(), context_.height());
  gl_.ClearColor(color.x(), color.y(), color.z(), 1.0f);
  gl_.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  gl_.check("clear");
}

Image Renderer::render_image(const RenderScene& scene, const Camera& camera) {
  render(scene, camera);
  return context_.read_pixels();
}

void Renderer::draw_scene(const RenderScene& scene, const Camera& camera, int w, int h) {
  gl_.Viewport(0, 0, w, h);
  gl_.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl_.DepthMask(GL_TRUE);
  gl_.ClearColor(scene.background.x(), scene.background.y(), scene.background.z(), 1.0f);
  gl_.ClearDepth(1.0);
  gl_.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(GL_LEQUAL);
  gl_.Disable(GL_CULL_FACE);
  gl_.Enable(GL_BLEND);
  // Colour blends by alpha; destination alpha stays 1 so images are opaque.
  gl_.BlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);

  const Eigen::Matrix4f view = camera.view_matrix();
  const Eigen::Matrix4f proj = camera.projection_matrix(static_cast<double>(w) / h);
  const Eigen::Vector3f light = (view.block<3, 3>(0, 0) * kLightWorld).normalized();

  if (scene.grid.visible) {
    // The grid is drawn first without depth writes: a backdrop that objects always cover.
    const ShaderProgram& p = programs_.at("grid");
    p.use();
    p.set_matrix("u_view", view.data());
    p.set_matrix("u_proj", proj.data());
    p.set("u_center", scene.grid.center.x(), scene.grid.center.y());
    p.set("u_extent", scene.grid.extent);
    p.set("u_height", scene.grid.height);
    p.set("u_spacing", scene.grid.spacing);
    p.set("u_line_color", scene.grid.line_color.x(), scene.grid.line_color.y(),
          scene.grid.line_color.z());
    gl_.DepthMask(GL_FALSE);
    gl_.BindVertexArray(empty_vao_);
    gl_.DrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    gl_.DepthMask(GL_TRUE);
  }
  draw_meshes(scene, false, view, proj, light);
  const bool discs = scene.resolved_point_style() == PointStyle::kDiscs;
  if (discs) gl_.Enable(GL_PROGRAM_POINT_SIZE);
  for (const PointLayer& layer : scene.points) {
    if (layer.opacity >= 1.0f) draw_points(layer, discs, view, proj, light, h);
  }
  draw_lines_and_boxes(scene, view, proj);
  // Translucent layers last, without depth writes, so they never hide what is behind them; and
  // strictly in front only, so a translucent copy at the same depth as an opaque surface (the
  // truth ghost over the prediction at an observed frame) does not tint it.
  gl_.DepthMask(GL_FALSE);
  gl_.DepthFunc(GL_LESS);
  draw_meshes(scene, true, view, proj, light);
  for (const PointLayer& layer : scene.points) {
    if (layer.opacity < 1.0f) draw_points(layer, discs, view, proj, light, h);
  }
  if (discs) gl_.Disable(GL_PROGRAM_POINT_SIZE);
  gl_.DepthFunc(GL_LEQUAL);
  gl_.DepthMask(GL_TRUE);
  gl_.BindVertexArray(0);
}

void Renderer::draw_meshes(const RenderScene& scene, bool translucent, const Eigen::Matrix4f& view,
                           const Eigen::Matrix4f& proj, const Eigen::Vector3f& light) {
  const ShaderProgram& p = programs_.at("mesh");
  bool bound = false;
  for (const MeshInstance& m : scene.meshes) {
    if ((m.opacity < 1.0f) != translucent) continue;
    if (!bound) {
      p.use();
      p.set_matrix("u_view", view.data());
      p.set_matrix("u_proj", proj.data());
      p.set("u_light_view", light.x(), light.y(), light.z());
      bound = true;
    }
    p.set_matrix("u_model", m.model.data());
    p.set("u_color", m.color.x(), m.color.y(), m.color.z());
    p.set("u_opacity", m.opacity);
    p.set("u_flat", m.smooth ? 0 : 1);
    mesh_buffer(m.geometry).draw();
  }
}

void Renderer::draw_points(const PointLayer& layer, bool discs, const Eigen::Matrix4f& view,
                           const Eigen::Matrix4f& proj, const Eigen::Vector3f& light, int height) {
  const PointSetBuffer& buffer = point_buffer(layer.series);
  const ShaderProgram& p = programs_.at(discs ? "discs" : "points");
  p.use();
  if (discs) p.set("u_viewport_height", static_cast<float>(height));
  p.set_matrix("u_view", view.data());
  p.set_matrix("u_proj", proj.data());
  p.set("u_light_view", light.x(), light.y(), light.z());
  p.set("u_radius", layer.radius);
  p.set("u_opacity", layer.opacity);
  p.set("u_color", layer.color.x(), layer.color.y(), layer.color.z());
  int mode = 0;
  if (layer.coloring == PointColoring::kPerPoint) mode = 1;
  if (layer.coloring == PointColoring::kScalar) {
    mode = 2;
    gl_.ActiveTexture(GL_TEXTURE0);
    gl_.BindTexture(GL_TEXTURE_2D, colormap_texture(layer.colormap));
    p.set("u_colormap", 0);
    p.set("u_range", layer.range_min, layer.range_max);
  }
  p.set("u_color_mode", mode);
  if (discs) {
    buffer.draw_sprites(layer.frame);
  } else {
    buffer.draw(layer.frame);
  }
}

void Renderer::draw_lines_and_boxes(const RenderScene& scene, const Eigen::Matrix4f& view,
                                    const Eigen::Matrix4f& proj) {
  const ShaderProgram& lines = programs_.at("lines");
  std::vector<float> data;
  for (const LineSet& l : scene.lines) {
    const size_t vertices = l.positions.size() / 3;
    if (vertices == 0) continue;
    data.resize(vertices * 6);
    for (size_t v = 0; v < vertices; ++v) {
      for (int k = 0; k < 3; ++k) {
        data[v * 6 + k] = l.positions[v * 3 + k];
        data[v * 6 + 3 + k] = l.colors.empty() ? l.color[k] : l.colors[v * 3 + k];
      }
    }
    lines.use();
    lines.set_matrix("u_view", view.data());
    lines.set_matrix("u_proj", proj.data());
    lines.set("u_opacity", l.opacity);
    gl_.LineWidth(std::clamp(l.width, 1.0f, max_line_width_));
    gl_.BindVertexArray(line_vao_);
    gl_.BindBuffer(GL_ARRAY_BUFFER, line_vbo_);
    gl_.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(float)),
                   data.data(), GL_STREAM_DRAW);
    gl_.DrawArrays(GL_LINES, 0, static_cast<GLsizei>(vertices));
  }
  if (!scene.boxes.empty()) {
    data.resize(scene.boxes.size() * 9);
    for (size_t b = 0; b < scene.boxes.size(); ++b) {
      const WireBox& box = scene.boxes[b];
      for (int k = 0; k < 3; ++k) {
        data[b * 9 + k] = box.min[k];
        data[b * 9 + 3 + k] = box.max[k];
        data[b * 9 + 6 + k] = box.color[k];
      }
    }
    const ShaderProgram& p = programs_.at("boxes");
    p.use();
    p.set_matrix("u_view", view.data());
    p.set_matrix("u_proj", proj.data());
    p.set("u_opacity", 1.0f);
    gl_.LineWidth(std::clamp(scene.box_line_width, 1.0f, max_line_width_));
    gl_.BindVertexArray(box_vao_);
    gl_.BindBuffer(GL_ARRAY_BUFFER, box_vbo_);
    gl_.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(float)),
                   data.data(), GL_STREAM_DRAW);
    gl_.DrawArraysInstanced(GL_LINES, 0, 24, static_cast<GLsizei>(scene.boxes.size()));
  }
  gl_.LineWidth(1.0f);
}

PickResult Renderer::pick(const RenderScene& scene, const Camera& camera, int x, int y) {
  scene.validate();
  camera.validate();
  const int w = context_.width(), h = context_.height();
  if (x < 0 || y < 0 || x >= w || y >= h) return {};
  ensure_target(*pick_, w, h, 0);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, pick_->fbo);
  gl_.Viewport(0, 0, w, h);
  gl_.Disable(GL_BLEND);
  gl_.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl_.DepthMask(GL_TRUE);
  gl_.ClearColor(0.0f, 0.0f, 0.0f, 0.0f);
  gl_.ClearDepth(1.0);
  gl_.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(GL_LEQUAL);
  const Eigen::Matrix4f view = camera.view_matrix();
  const Eigen::Matrix4f proj = camera.projection_matrix(static_cast<double>(w) / h);
  const Eigen::Vector3f light = Eigen::Vector3f::UnitZ();
  // Opaque meshes only fill depth, so points hidden behind them cannot be picked.
  gl_.ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  draw_meshes(scene, false, view, proj, light);
  gl_.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  // Picking sees what is drawn: discs where the image shows discs.
  const bool discs = scene.resolved_point_style() == PointStyle::kDiscs;
  const ShaderProgram& p = programs_.at(discs ? "pick_discs" : "pick");
  if (discs) gl_.Enable(GL_PROGRAM_POINT_SIZE);
  for (size_t i = 0; i < scene.points.size(); ++i) {
    const PointLayer& layer = scene.points[i];
    if (!layer.pickable || layer.opacity < 1.0f) continue;
    const PointSetBuffer& buffer = point_buffer(layer.series);
    p.use();
    p.set_matrix("u_view", view.data());
    p.set_matrix("u_proj", proj.data());
    p.set("u_radius", layer.radius);
    p.set("u_color_mode", 0);
    p.set("u_layer", static_cast<int>(i));
    if (discs) {
      p.set("u_viewport_height", static_cast<float>(h));
      buffer.draw_sprites(layer.frame);
    } else {
      buffer.draw(layer.frame);
    }
  }
  if (discs) gl_.Disable(GL_PROGRAM_POINT_SIZE);
  uint8_t pixel[4] = {0, 0, 0, 0};
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 1);
  gl_.BindFramebuffer(GL_READ_FRAMEBUFFER, pick_->fbo);
  gl_.ReadPixels(x, h - 1 - y, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, pixel);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl_.check("pick");
  const int id = pixel[0] | (pixel[1] << 8) | (pixel[2] << 16);
  if (id == 0) return {};
  return PickResult{pixel[3], id - 1};
}

}  // namespace dynscope::render
