// ViewThread: the 3D view drawn on its own thread and context (see view_thread.h).
#include "render/view_thread.h"

#include <memory>
#include <utility>

#include "engine/core/error.h"
#include "render/context_factory.h"

namespace dynscope::render {
namespace {

bool same_grid(const GroundGrid& a, const GroundGrid& b) {
  return a.visible == b.visible && a.height == b.height && a.center == b.center &&
         a.extent == b.extent && a.spacing == b.spacing && a.line_color == b.line_color;
}

bool same_mesh(const MeshInstance& a, const MeshInstance& b) {
  return a.geometry == b.geometry && a.model == b.model && a.color == b.color &&
         a.smooth == b.smooth && a.opacity == b.opacity;
}

bool same_points(const PointLayer& a, const PointLayer& b) {
  return a.series == b.series && a.frame == b.frame && a.coloring == b.coloring &&
         a.color == b.color && a.colormap == b.colormap && a.range_min == b.range_min &&
         a.range_max == b.range_max && a.radius == b.radius && a.opacity == b.opacity;
}

bool same_lines(const LineSet& a, const LineSet& b) {
  return a.positions == b.positions && a.colors == b.colors && a.color == b.color &&
         a.width == b.width && a.opacity == b.opacity;
}

bool same_box(const WireBox& a, const WireBox& b) {
  return a.min == b.min && a.max == b.max && a.color == b.color;
}

template <typename T, typename Same>
bool same_all(const std::vector<T>& a, const std::vector<T>& b, const Same& same) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!same(a[i], b[i])) return false;
  }
  return true;
}

bool same_scene(const RenderScene& a, const RenderScene& b) {
  return a.background == b.background && same_grid(a.grid, b.grid) &&
         a.box_line_width == b.box_line_width && a.point_style == b.point_style &&
         same_all(a.meshes, b.meshes, same_mesh) && same_all(a.points, b.points, same_points) &&
         same_all(a.lines, b.lines, same_lines) && same_all(a.boxes, b.boxes, same_box);
}

bool same_camera(const Camera& a, const Camera& b) {
  return a.target == b.target && a.distance == b.distance && a.yaw_deg == b.yaw_deg &&
         a.pitch_deg == b.pitch_deg && a.fov_deg == b.fov_deg;
}

bool same_item(const ViewItem& a, const ViewItem& b) {
  return a.rect == b.rect && same_camera(a.camera, b.camera) && same_scene(a.scene, b.scene);
}

}  // namespace

bool same_view(const ViewRequest& a, const ViewRequest& b) {
  return a.width == b.width && a.height == b.height && a.clear == b.clear &&
         same_all(a.items, b.items, same_item);
}

ViewThread::ViewThread(int samples) {
  thread_ = std::thread([this, samples] { run(samples); });
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return started_; });
  if (start_error_) {
    lock.unlock();
    thread_.join();
    std::rethrow_exception(start_error_);
  }
}

ViewThread::~ViewThread() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

uint64_t ViewThread::submit(ViewRequest request) {
  check_image_size("view size", request.width, request.height);
  std::lock_guard<std::mutex> lock(mutex_);
  if (submitted_ > 0 && same_view(request, last_)) return submitted_;
  last_ = std::move(request);
  has_pending_ = true;
  ++submitted_;
  wake_.notify_one();
  return submitted_;
}

bool ViewThread::take(Image& image, uint64_t& number) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (error_) {
    std::exception_ptr e = std::exchange(error_, nullptr);
    std::rethrow_exception(e);
  }
  if (!image_ready_) return false;
  image = std::move(image_);
  image_ = Image();
  image_ready_ = false;
  number = finished_;
  return true;
}

void ViewThread::wait(uint64_t number) {
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [&] { return finished_ >= number || stop_; });
}

uint64_t ViewThread::submitted() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return submitted_;
}

int64_t ViewThread::images_drawn() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return images_drawn_;
}

int64_t ViewThread::upload_count() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return uploads_;
}

void ViewThread::run(int samples) {
  std::unique_ptr<GlContext> context;
  std::unique_ptr<Renderer> renderer;
  try {
    context = create_context("osmesa", 1, 1);
    renderer = std::make_unique<Renderer>(*context, samples);
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex_);
    start_error_ = std::current_exception();
    started_ = true;
    done_.notify_all();
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    started_ = true;
  }
  done_.notify_all();

  for (;;) {
    ViewRequest request;
    uint64_t number = 0;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || has_pending_; });
      if (stop_) break;
      // Copies only the plain description: point series and meshes are shared pointers.
      request = last_;
      number = submitted_;
      has_pending_ = false;
    }
    Image image;
    std::exception_ptr error;
    try {
      context->resize(request.width, request.height);
      context->make_current();
      if (request.items.empty()) renderer->clear(request.clear);
      for (const ViewItem& item : request.items) {
        renderer->render(item.scene, item.camera, item.rect);
      }
      image = context->read_pixels();
    } catch (...) {
      error = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      finished_ = number;
      uploads_ = renderer->upload_count();
      if (error) {
        error_ = error;
        image_ready_ = false;
        image_ = Image();
      } else {
        image_ = std::move(image);
        image_ready_ = true;
        ++images_drawn_;
      }
    }
    done_.notify_all();
  }
  // The context must be current on this thread while the Renderer frees its GL objects.
  try {
    context->make_current();
  } catch (...) {
  }
  renderer.reset();
}

}  // namespace dynscope::render
