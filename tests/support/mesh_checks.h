// Mesh invariants shared by tests: closed, consistently oriented surfaces.
#pragma once

#include <map>
#include <utility>

#include "engine/scene/mesh.h"

namespace dynscope::test {

/// True if every directed edge appears exactly once and its reverse exactly once: the mesh is
/// closed and consistently oriented.
inline bool is_closed_oriented(const Mesh& m) {
  std::map<std::pair<int, int>, int> edges;
  for (Eigen::Index f = 0; f < m.num_faces(); ++f) {
    for (int e = 0; e < 3; ++e) ++edges[{m.faces(f, e), m.faces(f, (e + 1) % 3)}];
  }
  for (const auto& [edge, count] : edges) {
    if (count != 1) return false;
    const auto it = edges.find({edge.second, edge.first});
    if (it == edges.end() || it->second != 1) return false;
  }
  return true;
}

}  // namespace dynscope::test
