// ViewThread: draws the 3D view on its own thread with its own off-screen context, so the thread
// that runs the UI never waits for the vertex stage of a software rasteriser.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "render/camera.h"
#include "render/image.h"
#include "render/render_scene.h"
#include "render/renderer.h"

namespace dynscope::render {

/// One view of a request: `scene` seen by `camera`, drawn into `rect` (Renderer::render with a
/// viewport).
struct ViewItem {
  RenderScene scene;
  Camera camera;
  Rect rect;
};

/// One whole image: width x height pixels holding `items` (none: cleared to `clear`).
struct ViewRequest {
  int width = 0;
  int height = 0;
  Color clear = Color(1.0f, 1.0f, 1.0f);
  std::vector<ViewItem> items;
};

/// True when `a` and `b` draw the same image: the same sizes, cameras, rectangles and scenes
/// (point series and meshes compared by identity, as the renderer caches them; everything else by
/// value). Costs O(layers + line segments + boxes), never O(points).
bool same_view(const ViewRequest& a, const ViewRequest& b);

/// A thread with its own OSMesa context and Renderer that draws the newest submitted request and
/// hands back the image (RGBA8, rows top to bottom). Requests are numbered from 1; a request
/// submitted while another waits replaces it (the newest wins), and a request that draws the same
/// as the last one submitted is not drawn again, so an idle view costs nothing. Scenes are plain
/// data whose point series and meshes are shared and immutable once drawn (RenderScene), so a
/// request can be handed over without copying points. submit, take, wait and the counters may be
/// called from any one thread.
class ViewThread {
 public:
  /// Starts the thread and waits until its context and Renderer (`samples` as Renderer) exist.
  /// Throws Error if either cannot be created there.
  explicit ViewThread(int samples = 4);
  /// Stops the thread after the image it is drawing, if any.
  ~ViewThread();
  ViewThread(const ViewThread&) = delete;
  ViewThread& operator=(const ViewThread&) = delete;

  /// Queues `request` and returns its number; a request that draws the same as the previous one
  /// is dropped and the previous number returned. Throws ValueError for a size below 1 pixel.
  uint64_t submit(ViewRequest request);
  /// Moves the newest finished image not taken yet into `image` and its request number into
  /// `number`; false when there is none. A request that failed to draw is rethrown here once
  /// (its number is then done, without an image).
  bool take(Image& image, uint64_t& number);
  /// Blocks until request `number` or a newer one is finished (or failed).
  void wait(uint64_t number);
  /// Number of the last request submitted (0: none).
  uint64_t submitted() const;
  /// Images drawn so far (requests dropped as unchanged or replaced while waiting are not drawn).
  int64_t images_drawn() const;
  /// Point-series and mesh uploads of the thread's Renderer so far.
  int64_t upload_count() const;

 private:
  void run(int samples);

  mutable std::mutex mutex_;
  std::condition_variable wake_;  // the thread: a request is pending or stop
  std::condition_variable done_;  // callers: a request finished, or the thread started
  bool started_ = false;
  bool stop_ = false;
  std::exception_ptr start_error_;
  ViewRequest last_;          // the newest request submitted (compared by same_view)
  bool has_pending_ = false;  // `last_` still waits to be drawn
  uint64_t submitted_ = 0;    // number of `last_`
  uint64_t finished_ = 0;     // number of the newest request drawn or failed
  Image image_;               // its image (empty after take or failure)
  bool image_ready_ = false;  // `image_` not taken yet
  std::exception_ptr error_;  // its failure, not yet rethrown
  int64_t images_drawn_ = 0;
  int64_t uploads_ = 0;
  std::thread thread_;
};

}  // namespace dynscope::render
