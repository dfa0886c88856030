// Shared fixtures for the model tests: small random multi-object scenes and tiny configurations.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/rng.h"
#include "engine/core/types.h"
#include "engine/model/hierarchy.h"
#include "engine/model/model_config.h"
#include "engine/model/point_state.h"

namespace dynscope::testing {

/// Points of `objects` boxes of edge 0.25 side by side along x with 0.05 gaps (so relational
/// neighbourhoods of radius 0.1 are not empty), `per_object` uniform random points each.
struct TestScene {
  Points points = Points(0, 3);
  std::vector<int32_t> ids;
};

inline TestScene make_scene(int objects, int per_object, uint64_t seed) {
  Rng rng(seed);
  TestScene s;
  s.points.resize(objects * per_object, 3);
  for (int o = 0; o < objects; ++o) {
    for (int i = 0; i < per_object; ++i) {
      const Eigen::Index r = o * per_object + i;
      s.points.row(r) << 0.3 * o + rng.uniform(0.0, 0.25), rng.uniform(0.0, 0.25),
          0.1 + rng.uniform(0.0, 0.25);
      s.ids.push_back(10 + o);
    }
  }
  return s;
}

/// A state at `scene` with random per-object velocities plus small per-point noise.
inline PointState make_state(const TestScene& scene, uint64_t seed) {
  Rng rng(seed);
  PointState st;
  const Eigen::Index n = scene.points.rows();
  st.position = scene.points;
  st.velocity.resize(n, 3);
  st.prev_velocity.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double o = scene.ids[static_cast<size_t>(i)];
    st.velocity.row(i) << 0.01 * o * 0.1 + 0.001 * rng.normal(), -0.02,
        -0.05 + 0.001 * rng.normal();
    st.prev_velocity.row(i) << 0.01 * o * 0.1, -0.02 + 0.001 * rng.normal(), -0.04;
  }
  st.object_ids = scene.ids;
  return st;
}

/// Hierarchy options for make_scene's boxes: 3 levels, voxel 0.08, radius 0.1, K = 8.
inline HierarchyOptions small_hierarchy_options() {
  HierarchyOptions o;
  o.levels = 3;
  o.voxel = 0.08;
  o.radius = 0.1;
  o.k = 8;
  o.k_relational = 8;
  return o;
}

/// Tiny configuration so that tests run in milliseconds.
inline ModelConfig tiny_config(ModelKind kind = ModelKind::kPointConv) {
  ModelConfig c;
  c.kind = kind;
  c.width = 8;
  c.width_growth = 2.0;
  c.levels = 3;
  c.bottleneck_blocks = 1;
  c.c_mid = 4;
  c.k = 8;
  c.k_relational = 8;
  c.pos_channels = 4;
  c.voxel = 0.08;
  c.radius = 0.1;
  return c;
}

}  // namespace dynscope::testing

#include "engine/scene/mesh.h"

namespace dynscope::testing {

/// Two unit boxes side by side along x with a `gap` between them (ids 1 and 2), as one vertex
/// array with faces indexing it.
struct TestMesh {
  Points vertices = Points(0, 3);
  Faces faces = Faces(0, 3);
  std::vector<int32_t> ids;
};

inline TestMesh make_two_boxes(double gap) {
  const Mesh box = make_box_mesh(Vec3(1.0, 1.0, 1.0));
  TestMesh m;
  const Eigen::Index v = box.num_vertices(), f = box.num_faces();
  m.vertices.resize(2 * v, 3);
  m.faces.resize(2 * f, 3);
  for (int b = 0; b < 2; ++b) {
    m.vertices.middleRows(b * v, v) = box.vertices;
    m.vertices.middleRows(b * v, v).col(0).array() += b * (1.0 + gap);
    m.vertices.middleRows(b * v, v).col(2).array() += 0.5;
    m.faces.middleRows(b * f, f) = box.faces.array() + static_cast<int32_t>(b * v);
    m.ids.insert(m.ids.end(), static_cast<size_t>(v), b + 1);
  }
  return m;
}

}  // namespace dynscope::testing
