// Mesh interaction lists: deduplicated interaction points and their three neighbourhoods.
#include "engine/model/mesh_interaction.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "engine/core/error.h"
#include "engine/geometry/interaction_points.h"
#include "engine/geometry/kdtree_index.h"

namespace dynscope {

namespace {

// Fills row `row` of `list` with the list.k() nearest of `candidates` to `query`, nearest first
// (ties: lower index; the candidates are distinct). When there are more candidates than that, one
// pass keeps the best so far in order and inserts a candidate only when it is nearer than the
// last of them, which most candidates of a long list are not; else they are sorted.
void fill_row(NeighborList& list, Eigen::Index row, const Vec3& query, const Points& source,
              const std::vector<int32_t>& candidates,
              std::vector<std::pair<double, int32_t>>& best) {
  const auto k = static_cast<size_t>(list.k());
  best.clear();
  if (candidates.size() <= k) {
    for (int32_t c : candidates)
      best.emplace_back(squared_distance(source.row(c).transpose(), query), c);
    std::sort(best.begin(), best.end());
  } else {
    for (int32_t c : candidates) {
      const std::pair<double, int32_t> e(squared_distance(source.row(c).transpose(), query), c);
      if (best.size() == k) {
        if (!(e < best.back())) continue;
        best.pop_back();
      }
      best.insert(std::upper_bound(best.begin(), best.end(), e), e);
    }
  }
  for (size_t j = 0; j < best.size(); ++j) {
    list.index(row, static_cast<Eigen::Index>(j)) = best[j].second;
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
                                       const Faces& faces, double threshold, int lattice, int k,
                                       double spacing) {
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
  const GroupedSamplePairs sp =
      find_grouped_sample_pairs(vertices, faces, face_object, threshold, lattice, spacing);

  MeshInteraction out;
  // The same lattice sample may pair with several others; it is one interaction point, numbered
  // in the order of its first appearance in the pairs taken in (sample a, sample b) order, each
  // pair's a before its b. That order needs no sort of the pairs: sample x first appears at
  // (x, before any partner) if it pairs as a first sample, else at its smallest (a, x); one pass
  // takes the smallest such key of every sample, and only the samples are sorted by it.
  const auto n_samples = static_cast<int64_t>(sp.samples.rows());
  constexpr int64_t kNever = std::numeric_limits<int64_t>::max();
  std::vector<int64_t> first(static_cast<size_t>(n_samples), kNever);
  for (int64_t a = 0; a < n_samples; ++a) {
    const size_t begin = sp.start[static_cast<size_t>(a)];
    const size_t end = sp.start[static_cast<size_t>(a) + 1];
    if (begin == end) continue;
    const int64_t base = a * (n_samples + 1);
    first[static_cast<size_t>(a)] = std::min(first[static_cast<size_t>(a)], base);
    for (size_t p = begin; p < end; ++p) {
      int64_t& key = first[static_cast<size_t>(sp.partner[p])];
      key = std::min(key, base + 1 + sp.partner[p]);
    }
  }
  std::vector<std::pair<int64_t, int32_t>> order;
  for (int64_t x = 0; x < n_samples; ++x) {
    if (first[static_cast<size_t>(x)] != kNever)
      order.emplace_back(first[static_cast<size_t>(x)], static_cast<int32_t>(x));
  }
  std::sort(order.begin(), order.end());
  // Each sample in that order becomes a new point unless it coincides with a point already on its
  // face, which merges the coinciding samples of a degenerate face. Per face: its interaction
  // points (ascending) and the faces paired with it.
  std::vector<std::vector<int32_t>> on_face(n_faces), paired(n_faces);
  std::vector<Vec3> pts;
  for (const auto& [key, sample] : order) {
    const int32_t face = sp.sample_face[static_cast<size_t>(sample)];
    const Vec3 p = sp.samples.row(sample).transpose();
    std::vector<int32_t>& here = on_face[static_cast<size_t>(face)];
    if (std::any_of(here.begin(), here.end(),
                    [&](int32_t i) { return pts[static_cast<size_t>(i)] == p; }))
      continue;
    here.push_back(static_cast<int32_t>(pts.size()));
    pts.push_back(p);
    out.face.push_back(face);
    out.object_ids.push_back(face_object[static_cast<size_t>(face)]);
  }
  const auto n_ip = static_cast<Eigen::Index>(pts.size());
  out.points.resize(n_ip, 3);
  for (Eigen::Index i = 0; i < n_ip; ++i) out.points.row(i) = pts[static_cast<size_t>(i)];

  for (const auto& [fa, fb] : sp.face_pairs) {
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
