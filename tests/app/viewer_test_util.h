// Helpers shared by the viewer tests: one OSMesa context per binary, the bundled collide scene.
#pragma once

#include <memory>
#include <string>

#include "app/viewer/null_platform.h"
#include "app/viewer/platform.h"
#include "app/viewer/viewer_app.h"
#include "render/context_factory.h"

namespace dynscope::app::viewer::testing {

constexpr int kWidth = 960;
constexpr int kHeight = 600;

/// The test binary's OSMesa context (created on first use), resized to width x height.
inline render::GlContext& osmesa(int width = kWidth, int height = kHeight) {
  static std::unique_ptr<render::GlContext> context =
      render::create_context("osmesa", width, height);
  context->make_current();
  context->resize(width, height);
  return *context;
}

/// assets/scenes/collide_0000.h5 (3 objects: target, zone, probe; 60 frames).
inline std::string collide_scene() {
  return std::string(DYNSCOPE_SOURCE_DIR) + "/assets/scenes/collide_0000.h5";
}

/// A headless viewer of kWidth x kHeight: ImGui session, null platform and the app (with
/// `services`, which must outlive it, for the model).
struct HeadlessViewer {
  explicit HeadlessViewer(ModelServices* services = nullptr)
      : platform(kWidth, kHeight), app(osmesa(), platform, services) {}
  ImGuiSession session;
  NullPlatform platform;
  ViewerApp app;
};

}  // namespace dynscope::app::viewer::testing
