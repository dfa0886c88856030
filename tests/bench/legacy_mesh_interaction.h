// The previous interaction points (every sample pair sorted in one sort) and mesh interaction
// lists (ordered maps, every candidate list sorted in full per row), kept as the reference that
// the library's find_interaction_points and build_mesh_interaction must equal exactly (tests) and
// are timed beside (model_bench).
#pragma once

#include <algorithm>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "engine/geometry/interaction_points.h"
#include "engine/model/mesh_interaction.h"

namespace dynscope::legacy {

// The previous ordering of find_sample_pairs' pairs: one sort of them all, then the face pairs
// sorted and made unique on their own.
inline InteractionPoints find_interaction_points(const Points& vertices, const Faces& faces,
                                                 const std::vector<int32_t>& face_object,
                                                 double threshold, int lattice = 3) {
  SamplePairs found = find_sample_pairs(vertices, faces, face_object, threshold, lattice);
  const Points& samples = found.samples;
  const std::vector<int32_t>& sample_face = found.sample_face;
  std::vector<std::pair<int32_t, int32_t>>& pairs = found.pairs;
  std::sort(pairs.begin(), pairs.end());

  InteractionPoints out;
  out.point_a.resize(static_cast<Eigen::Index>(pairs.size()), 3);
  out.point_b.resize(static_cast<Eigen::Index>(pairs.size()), 3);
  for (size_t p = 0; p < pairs.size(); ++p) {
    const auto row = static_cast<Eigen::Index>(p);
    const int32_t fa = sample_face[static_cast<size_t>(pairs[p].first)];
    const int32_t fb = sample_face[static_cast<size_t>(pairs[p].second)];
    out.point_a.row(row) = samples.row(pairs[p].first);
    out.point_b.row(row) = samples.row(pairs[p].second);
    out.face_a.push_back(fa);
    out.face_b.push_back(fb);
    out.object_a.push_back(face_object[static_cast<size_t>(fa)]);
    out.object_b.push_back(face_object[static_cast<size_t>(fb)]);
    out.face_pairs.emplace_back(fa, fb);
  }
  std::sort(out.face_pairs.begin(), out.face_pairs.end());
  out.face_pairs.erase(std::unique(out.face_pairs.begin(), out.face_pairs.end()),
                       out.face_pairs.end());
  return out;
}

// Fills row `row` of `list` with `candidates` sorted by distance to `query` (ties: lower index),
// keeping at most list.k().
inline void interaction_fill_row(NeighborList& list, Eigen::Index row, const Vec3& query,
                                 const Points& source, std::vector<int32_t> candidates) {
  std::vector<std::pair<double, int32_t>> d;
  d.reserve(candidates.size());
  for (int32_t c : candidates) d.emplace_back((source.row(c).transpose() - query).squaredNorm(), c);
  std::sort(d.begin(), d.end());
  const size_t n = std::min(d.size(), static_cast<size_t>(list.k()));
  for (size_t j = 0; j < n; ++j) {
    list.index(row, static_cast<Eigen::Index>(j)) = d[j].second;
    list.mask(row, static_cast<Eigen::Index>(j)) = 1;
  }
}

inline NeighborList interaction_empty_list(Eigen::Index rows, Eigen::Index k) {
  NeighborList l;
  l.index = IndexMatrix::Constant(rows, k, -1);
  l.mask = MaskMatrix::Zero(rows, k);
  return l;
}

inline MeshInteraction build_mesh_interaction(const Points& vertices,
                                              const std::vector<int32_t>& vertex_object_ids,
                                              const Faces& faces, double threshold, int lattice,
                                              int k) {
  // Inputs are valid in the tests and the benchmark (the library validates them).
  std::vector<int32_t> face_object(static_cast<size_t>(faces.rows()));
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    face_object[static_cast<size_t>(f)] = vertex_object_ids[static_cast<size_t>(faces(f, 0))];
  }
  const InteractionPoints ip =
      find_interaction_points(vertices, faces, face_object, threshold, lattice);

  MeshInteraction out;
  // The same lattice sample may pair with several others; it is one interaction point.
  std::map<std::tuple<int32_t, double, double, double>, int32_t> seen;
  std::vector<Vec3> pts;
  auto add = [&](int32_t face, const Eigen::RowVector3d& p) {
    const auto key = std::make_tuple(face, p.x(), p.y(), p.z());
    if (seen.emplace(key, static_cast<int32_t>(pts.size())).second) {
      pts.push_back(p.transpose());
      out.face.push_back(face);
      out.object_ids.push_back(face_object[static_cast<size_t>(face)]);
    }
  };
  for (size_t p = 0; p < ip.size(); ++p) {
    add(ip.face_a[p], ip.point_a.row(static_cast<Eigen::Index>(p)));
    add(ip.face_b[p], ip.point_b.row(static_cast<Eigen::Index>(p)));
  }
  const auto n_ip = static_cast<Eigen::Index>(pts.size());
  out.points.resize(n_ip, 3);
  for (Eigen::Index i = 0; i < n_ip; ++i) out.points.row(i) = pts[static_cast<size_t>(i)];

  std::map<int32_t, std::vector<int32_t>> on_face, paired;
  for (Eigen::Index i = 0; i < n_ip; ++i) {
    on_face[out.face[static_cast<size_t>(i)]].push_back(static_cast<int32_t>(i));
  }
  for (const auto& [fa, fb] : ip.face_pairs) {
    paired[fa].push_back(fb);
    paired[fb].push_back(fa);
  }

  out.face_vertices = interaction_empty_list(n_ip, 3);
  out.senders = interaction_empty_list(n_ip, k);
  for (Eigen::Index i = 0; i < n_ip; ++i) {
    const int32_t f = out.face[static_cast<size_t>(i)];
    for (int c = 0; c < 3; ++c) {
      out.face_vertices.index(i, c) = faces(f, c);
      out.face_vertices.mask(i, c) = 1;
    }
    std::vector<int32_t> candidates;
    for (int32_t g : paired[f]) {
      const auto it = on_face.find(g);
      if (it != on_face.end())
        candidates.insert(candidates.end(), it->second.begin(), it->second.end());
    }
    interaction_fill_row(out.senders, i, out.points.row(i).transpose(), out.points,
                         std::move(candidates));
  }

  std::vector<std::vector<int32_t>> per_vertex(static_cast<size_t>(vertices.rows()));
  for (const auto& [f, members] : on_face) {
    for (int c = 0; c < 3; ++c) {
      auto& list = per_vertex[static_cast<size_t>(faces(f, c))];
      list.insert(list.end(), members.begin(), members.end());
    }
  }
  size_t widest = 0;
  for (const auto& l : per_vertex) widest = std::max(widest, l.size());
  out.vertex_points = interaction_empty_list(vertices.rows(), static_cast<Eigen::Index>(widest));
  for (Eigen::Index v = 0; v < vertices.rows(); ++v) {
    interaction_fill_row(out.vertex_points, v, vertices.row(v).transpose(), out.points,
                         std::move(per_vertex[static_cast<size_t>(v)]));
  }
  return out;
}

}  // namespace dynscope::legacy
