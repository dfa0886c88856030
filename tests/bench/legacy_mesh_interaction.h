// The previous interaction points (every sample pair sorted in one sort) and mesh interaction
// lists (ordered maps, every candidate list sorted in full per row), kept as the reference that
// the library's find_interaction_points and build_mesh_interaction must equal exactly (tests) and
// are timed beside (model_bench).
#pragma once

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "engine/core/error.h"
#include "engine/geometry/interaction_points.h"
#include "engine/geometry/kdtree_index.h"
#include "engine/model/mesh_interaction.h"

namespace dynscope::legacy {

// Lattice samples of one object's faces, with the global sample number of each local point.
struct InteractionObjectSamples {
  std::vector<int32_t> sample;
  Points points = Points(0, 3);
};

inline void check_interaction_inputs(const Points& vertices, const Faces& faces,
                                     const std::vector<int32_t>& face_object, double threshold,
                                     int lattice) {
  if (face_object.size() != static_cast<size_t>(faces.rows())) {
    throw ValueError("face_object", "has " + std::to_string(face_object.size()) + " entries for " +
                                        std::to_string(faces.rows()) + " faces");
  }
  if (!std::isfinite(threshold) || threshold <= 0.0) {
    throw ValueError("threshold", "must be finite and positive, got " + std::to_string(threshold));
  }
  if (lattice < 1) {
    throw ValueError("lattice",
                     "must be >= 1 subdivision per edge, got " + std::to_string(lattice));
  }
  if (!vertices.allFinite()) throw ValueError("vertices", "contain a non-finite coordinate");
  const auto n = static_cast<int32_t>(vertices.rows());
  if (faces.size() > 0 && (faces.minCoeff() < 0 || faces.maxCoeff() >= n)) {
    throw ValueError("faces", "index out of range [0, " + std::to_string(n) + ")");
  }
}

inline InteractionPoints find_interaction_points(const Points& vertices, const Faces& faces,
                                                 const std::vector<int32_t>& face_object,
                                                 double threshold, int lattice = 3) {
  check_interaction_inputs(vertices, faces, face_object, threshold, lattice);

  // Barycentric lattice (i, j, lattice - i - j) / lattice, corners and edges included, numbered
  // face by face so that sample order follows face order.
  const int per_face = (lattice + 1) * (lattice + 2) / 2;
  const Eigen::Index total = faces.rows() * per_face;
  Points samples(total, 3);
  std::vector<int32_t> sample_face(static_cast<size_t>(total));
  Eigen::Index s = 0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::RowVector3d a = vertices.row(faces(f, 0));
    const Eigen::RowVector3d b = vertices.row(faces(f, 1));
    const Eigen::RowVector3d c = vertices.row(faces(f, 2));
    for (int i = 0; i <= lattice; ++i) {
      for (int j = 0; j <= lattice - i; ++j) {
        const int k = lattice - i - j;
        samples.row(s) = (i * a + j * b + k * c) / lattice;
        sample_face[static_cast<size_t>(s)] = static_cast<int32_t>(f);
        ++s;
      }
    }
  }

  // One tree per object, so a query only visits objects that can pair with it.
  std::map<int32_t, InteractionObjectSamples> by_object;
  for (Eigen::Index i = 0; i < total; ++i) {
    by_object[face_object[static_cast<size_t>(sample_face[static_cast<size_t>(i)])]]
        .sample.push_back(static_cast<int32_t>(i));
  }
  std::map<int32_t, KdIndex> trees;
  std::map<int32_t, Aabb> boxes;
  for (auto& [object, group] : by_object) {
    group.points.resize(static_cast<Eigen::Index>(group.sample.size()), 3);
    for (size_t j = 0; j < group.sample.size(); ++j) {
      group.points.row(static_cast<Eigen::Index>(j)) = samples.row(group.sample[j]);
    }
    boxes.emplace(object, Aabb::of(group.points));
    trees.emplace(object, KdIndex(group.points, "vertices"));
  }

  // Each unordered pair is found once, from the object with the smaller id.
  const double sq_threshold = threshold * threshold;
  std::vector<std::pair<int32_t, int32_t>> pairs;
  std::vector<Neighbor> found;
  for (auto it_a = by_object.begin(); it_a != by_object.end(); ++it_a) {
    const Aabb& box_a = boxes.at(it_a->first);
    for (auto it_b = std::next(it_a); it_b != by_object.end(); ++it_b) {
      const Aabb& box_b = boxes.at(it_b->first);
      const Vec3 gap = (box_a.min - box_b.max).cwiseMax(box_b.min - box_a.max).cwiseMax(0.0);
      // Same summation order as squared_distance: with monotone rounding no sample pair of these
      // objects can then be computed closer than the boxes.
      if (gap.x() * gap.x() + gap.y() * gap.y() + gap.z() * gap.z() >= sq_threshold) continue;
      const KdIndex& tree_b = trees.at(it_b->first);
      for (size_t j = 0; j < it_a->second.sample.size(); ++j) {
        tree_b.radius(it_a->second.points.row(static_cast<Eigen::Index>(j)).transpose(), threshold,
                      found);
        for (const Neighbor& n : found) {
          // "Closer than" the threshold: strictly less.
          if (n.sq_dist < sq_threshold) {
            pairs.emplace_back(it_a->second.sample[j],
                               it_b->second.sample[static_cast<size_t>(n.index)]);
          }
        }
      }
    }
  }
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
  if (static_cast<Eigen::Index>(vertex_object_ids.size()) != vertices.rows()) {
    throw ValueError("vertex_object_ids", "has " + std::to_string(vertex_object_ids.size()) +
                                              " entries for " + std::to_string(vertices.rows()) +
                                              " vertices");
  }
  if (k < 1) throw ValueError("k", "must be >= 1, got " + std::to_string(k));
  if (faces.size() > 0 && (faces.minCoeff() < 0 || faces.maxCoeff() >= vertices.rows())) {
    throw ValueError("faces", "index out of range [0, " + std::to_string(vertices.rows()) + ")");
  }
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
