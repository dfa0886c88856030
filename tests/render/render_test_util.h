// Helpers shared by the render tests: one OSMesa context per test binary and small scenes.
#pragma once

#include <memory>

#include "engine/scene/scene.h"
#include "render/context_factory.h"
#include "render/renderer.h"

namespace dynscope::render::testing {

/// The test binary's OSMesa context (created on first use), resized to width x height.
inline GlContext& osmesa(int width = 320, int height = 240) {
  static std::unique_ptr<GlContext> context = create_context("osmesa", width, height);
  context->make_current();
  context->resize(width, height);
  return *context;
}

/// A rigid object with `mesh` at `position` (identity rotation) for `frames` frames.
inline void add_object(Scene& scene, int32_t id, const std::string& name, const Mesh& mesh,
                       const Vec3& position, const Vec3& color, int frames = 1) {
  Object o;
  o.id = id;
  o.name = name;
  o.mesh = mesh;
  o.color = color;
  scene.objects.push_back(o);
  Trajectory t;
  for (int f = 0; f < frames; ++f) t.poses.push_back(Pose{position, Quat::Identity()});
  scene.trajectories.push_back(t);
}

/// Box, sphere and cylinder resting on z = 0 (the golden "scene frame").
inline Scene shapes_scene(int frames = 1) {
  Scene s;
  s.scenario = "drop";
  add_object(s, 0, "box", make_box_mesh(Vec3(0.4, 0.4, 0.4)), Vec3(-0.45, 0.0, 0.2),
             Vec3(0.85, 0.2, 0.2), frames);
  add_object(s, 1, "sphere", make_sphere_mesh(0.22, 16, 32), Vec3(0.15, 0.35, 0.22),
             Vec3(0.95, 0.8, 0.2), frames);
  add_object(s, 2, "cylinder", make_cylinder_mesh(0.15, 0.5, 32), Vec3(0.4, -0.3, 0.25),
             Vec3(0.2, 0.45, 0.85), frames);
  return s;
}

}  // namespace dynscope::render::testing
