// Mesh interaction lists: deduplicated interaction points and their three neighbourhoods.
#include "engine/model/mesh_interaction.h"

#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "engine/core/error.h"
#include "engine/geometry/interaction_points.h"
#include "engine/geometry/kdtree_index.h"

namespace dynscope {

namespace {

// Fills row `row` of `list` with the list.k() nearest of `candidates` to `query`, nearest first
// (ties: lower index). Only the kept ones are ordered: a selection, then a sort of those.
void fill_row(NeighborList& list, Eigen::Index row, const Vec3& query, const Points& source,
              const std::vector<int32_t>& candidates,
              std::vector<std::pair<double, int32_t>>& scratch) {
  scratch.clear();
  for (int32_t c : candidates)
    scratch.emplace_back(squared_distance(source.row(c).transpose(), query), c);
  const size_t n = std::min(scratch.size(), static_cast<size_t>(list.k()));
  const auto kept = scratch.begin() + static_cast<std::ptrdiff_t>(n);
  if (kept != scratch.end()) std::nth_element(scratch.begin(), kept, scratch.end());
  std::sort(scratch.begin(), kept);
  for (size_t j = 0; j < n; ++j) {
    list.index(row, static_cast<Eigen::Index>(j)) = scratch[j].second;
    list.mask(row, static_cast<Eigen::Index>(j)) = 1;
  }
}

NeighborList empty_list(Eigen::Index rows, Eigen::Index k) {
  NeighborList l;
  l.index = IndexMatrix::Constant(rows, k, -1);
  l.mask = MaskMatrix::Zero(rows, k);
  return l;
}

}  // namespace

MeshInteraction build_mesh_interaction(const Points& vertices,
                                       const std::vector<int32_t>& vertex_object_ids,
                                       const Faces& faces, double threshold, int lattice, int k) {
  if (static_cast<Eigen::Index>(vertex_object_ids.size()) != vertices.rows()) {
    throw ValueError("vertex_object_ids", "has " + std::to_string(vertex_object_ids.size()) +
                                              " entries for " + std::to_string(vertices.rows()) +
                                              " vertices");
  }
  if (k < 1) throw ValueError("k", "must be >= 1, got " + std::to_string(k));
  if (faces.size() > 0 && (faces.minCoeff() < 0 || faces.maxCoeff() >= vertices.rows())) {
    throw ValueError("faces", "index out of range [0, " + std::to_string(vertices.rows()) + ")");
  }
  const auto n_faces = static_cast<size_t>(faces.rows());
  std::vector<int32_t> face_object(n_faces);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    face_object[static_cast<size_t>(f)] = vertex_object_ids[static_cast<size_t>(faces(f, 0))];
  }
  const InteractionPoints ip =
      find_interaction_points(vertices, faces, face_object, threshold, lattice);

  MeshInteraction out;
  // The same lattice sample may pair with several others; it is one interaction point, numbered
  // in the order of its first pair. Samples seen before are known by their number; a new one is
  // compared with the points already on its face, which merges the coinciding samples of a
  // degenerate face. Per face: its interaction points (ascending) and the faces paired with it.
  const auto per_face = static_cast<size_t>((lattice + 1) * (lattice + 2) / 2);
  std::vector<int32_t> point_of_sample(n_faces * per_face, -1);
  std::vector<std::vector<int32_t>> on_face(n_faces), paired(n_faces);
  std::vector<Vec3> pts;
  auto add = [&](int32_t sample, int32_t face, const Eigen::RowVector3d& p) {
    int32_t& known = point_of_sample[static_cast<size_t>(sample)];
    if (known >= 0) return;
    std::vector<int32_t>& here = on_face[static_cast<size_t>(face)];
    for (int32_t i : here) {
      if (pts[static_cast<size_t>(i)] == p.transpose()) {
        known = i;
        return;
      }
    }
    known = static_cast<int32_t>(pts.size());
    here.push_back(known);
    pts.push_back(p.transpose());
    out.face.push_back(face);
    out.object_ids.push_back(face_object[static_cast<size_t>(face)]);
  };
  for (size_t p = 0; p < ip.size(); ++p) {
    add(ip.sample_a[p], ip.face_a[p], ip.point_a.row(static_cast<Eigen::Index>(p)));
    add(ip.sample_b[p], ip.face_b[p], ip.point_b.row(static_cast<Eigen::Index>(p)));
  }
  const auto n_ip = static_cast<Eigen::Index>(pts.size());
  out.points.resize(n_ip, 3);
  for (Eigen::Index i = 0; i < n_ip; ++i) out.points.row(i) = pts[static_cast<size_t>(i)];

  for (const auto& [fa, fb] : ip.face_pairs) {
    paired[static_cast<size_t>(fa)].push_back(fb);
    paired[static_cast<size_t>(fb)].push_back(fa);
  }

  // Layers 1 and 2, face by face: the receivers on one face share their sender candidates.
  out.face_vertices = empty_list(n_ip, 3);
  out.senders = empty_list(n_ip, k);
  std::vector<int32_t> candidates;
  std::vector<std::pair<double, int32_t>> scratch;
  for (size_t f = 0; f < n_faces; ++f) {
    if (on_face[f].empty()) continue;
    candidates.clear();
    for (int32_t g : paired[f]) {
      const auto& senders = on_face[static_cast<size_t>(g)];
      candidates.insert(candidates.end(), senders.begin(), senders.end());
    }
    for (int32_t i : on_face[f]) {
      for (int c = 0; c < 3; ++c) {
        out.face_vertices.index(i, c) = faces(static_cast<Eigen::Index>(f), c);
        out.face_vertices.mask(i, c) = 1;
      }
      fill_row(out.senders, i, out.points.row(i).transpose(), out.points, candidates, scratch);
    }
  }

  // Layer 3: each vertex takes every interaction point on the faces that contain it.
  std::vector<std::vector<int32_t>> per_vertex(static_cast<size_t>(vertices.rows()));
  for (size_t f = 0; f < n_faces; ++f) {
    if (on_face[f].empty()) continue;
    for (int c = 0; c < 3; ++c) {
      auto& list = per_vertex[static_cast<size_t>(faces(static_cast<Eigen::Index>(f), c))];
      list.insert(list.end(), on_face[f].begin(), on_face[f].end());
    }
  }
  size_t widest = 0;
  for (const auto& l : per_vertex) widest = std::max(widest, l.size());
  out.vertex_points = empty_list(vertices.rows(), static_cast<Eigen::Index>(widest));
  for (Eigen::Index v = 0; v < vertices.rows(); ++v) {
    const auto& list = per_vertex[static_cast<size_t>(v)];
    if (!list.empty())
      fill_row(out.vertex_points, v, vertices.row(v).transpose(), out.points, list, scratch);
  }
  return out;
}

}  // namespace dynscope
