// Interaction points: lattice samples on faces, paired across objects by exact radius search.
#include "engine/geometry/interaction_points.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "engine/core/error.h"
#include "engine/geometry/kdtree_index.h"

namespace dynscope {
namespace {

// Lattice samples of one object's faces, with the global sample number of each local point.
struct ObjectSamples {
  std::vector<int32_t> sample;
  Points points = Points(0, 3);
};

void check_inputs(const Points& vertices, const Faces& faces,
                  const std::vector<int32_t>& face_object, double threshold, int lattice,
                  double spacing) {
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
  if (!std::isfinite(spacing) || spacing < 0.0) {
    throw ValueError("spacing",
                     "must be finite and >= 0 (0: the same lattice on every face), got " +
                         std::to_string(spacing));
  }
  if (!vertices.allFinite()) throw ValueError("vertices", "contain a non-finite coordinate");
  const auto n = static_cast<int32_t>(vertices.rows());
  if (faces.size() > 0 && (faces.minCoeff() < 0 || faces.maxCoeff() >= n)) {
    throw ValueError("faces", "index out of range [0, " + std::to_string(n) + ")");
  }
}

// A face's subdivisions are capped: a face this much longer than the spacing is sampled as if it
// were this long (it would otherwise ask for more samples than memory holds).
constexpr int kMaxFaceLattice = 256;

}  // namespace

int face_lattice(double longest_edge, int lattice, double spacing) {
  if (spacing <= 0.0 || !(longest_edge > lattice * spacing)) return lattice;
  return static_cast<int>(std::min<double>(std::ceil(longest_edge / spacing), kMaxFaceLattice));
}

SamplePairs find_sample_pairs(const Points& vertices, const Faces& faces,
                              const std::vector<int32_t>& face_object, double threshold,
                              int lattice, double spacing) {
  check_inputs(vertices, faces, face_object, threshold, lattice, spacing);

  // Barycentric lattice (i, j, n - i - j) / n of each face's n subdivisions, corners and edges
  // included, numbered face by face so that sample order follows face order.
  std::vector<int> subdivisions(static_cast<size_t>(faces.rows()), lattice);
  Eigen::Index total = 0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    int& n = subdivisions[static_cast<size_t>(f)];
    if (spacing > 0.0) {
      const Eigen::RowVector3d a = vertices.row(faces(f, 0));
      const Eigen::RowVector3d b = vertices.row(faces(f, 1));
      const Eigen::RowVector3d c = vertices.row(faces(f, 2));
      n = face_lattice(std::max({(a - b).norm(), (b - c).norm(), (c - a).norm()}), lattice,
                       spacing);
    }
    total += (n + 1) * (n + 2) / 2;
  }
  SamplePairs out;
  Points& samples = out.samples;
  std::vector<int32_t>& sample_face = out.sample_face;
  samples.resize(total, 3);
  sample_face.resize(static_cast<size_t>(total));
  Eigen::Index s = 0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::RowVector3d a = vertices.row(faces(f, 0));
    const Eigen::RowVector3d b = vertices.row(faces(f, 1));
    const Eigen::RowVector3d c = vertices.row(faces(f, 2));
    const int n = subdivisions[static_cast<size_t>(f)];
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n - i; ++j) {
        const int k = n - i - j;
        samples.row(s) = (i * a + j * b + k * c) / n;
        sample_face[static_cast<size_t>(s)] = static_cast<int32_t>(f);
        ++s;
      }
    }
  }

  // One tree per object, so a query only visits objects that can pair with it.
  std::map<int32_t, ObjectSamples> by_object;
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
  std::vector<std::pair<int32_t, int32_t>>& pairs = out.pairs;
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
        // Unsorted: the callers order the pairs by sample number.
        tree_b.radius(it_a->second.points.row(static_cast<Eigen::Index>(j)).transpose(), threshold,
                      found, false);
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
  return out;
}

GroupedSamplePairs find_grouped_sample_pairs(const Points& vertices, const Faces& faces,
                                             const std::vector<int32_t>& face_object,
                                             double threshold, int lattice, double spacing) {
  SamplePairs found = find_sample_pairs(vertices, faces, face_object, threshold, lattice, spacing);
  GroupedSamplePairs out;
  out.samples = std::move(found.samples);
  out.sample_face = std::move(found.sample_face);
  const auto total = static_cast<size_t>(out.samples.rows());
  // Bucketed by the first sample (a counting sort).
  out.start.assign(total + 1, 0);
  for (const auto& [a, b] : found.pairs) ++out.start[static_cast<size_t>(a) + 1];
  for (size_t i = 1; i <= total; ++i) out.start[i] += out.start[i - 1];
  out.partner.resize(found.pairs.size());
  {
    std::vector<size_t> next(out.start.begin(), out.start.end() - 1);
    for (const auto& [a, b] : found.pairs) out.partner[next[static_cast<size_t>(a)]++] = b;
  }
  // Samples are numbered face by face, so the first samples' faces never decrease: each face's
  // distinct partner faces are collected (marked per face, not sorted with their repeats),
  // sorted and appended when the next face begins.
  std::vector<int32_t> marked(static_cast<size_t>(faces.rows()), -1);
  std::vector<int32_t> partners;
  int32_t current = -1;
  auto flush = [&]() {
    std::sort(partners.begin(), partners.end());
    for (int32_t fb : partners) out.face_pairs.emplace_back(current, fb);
    partners.clear();
  };
  for (size_t a = 0; a < total; ++a) {
    if (out.start[a] == out.start[a + 1]) continue;
    const int32_t fa = out.sample_face[a];
    if (fa != current) {
      flush();
      current = fa;
    }
    for (size_t p = out.start[a]; p < out.start[a + 1]; ++p) {
      const int32_t fb = out.sample_face[static_cast<size_t>(out.partner[p])];
      if (marked[static_cast<size_t>(fb)] == fa) continue;
      marked[static_cast<size_t>(fb)] = fa;
      partners.push_back(fb);
    }
  }
  flush();
  return out;
}

InteractionPoints find_interaction_points(const Points& vertices, const Faces& faces,
                                          const std::vector<int32_t>& face_object, double threshold,
                                          int lattice, double spacing) {
  GroupedSamplePairs found =
      find_grouped_sample_pairs(vertices, faces, face_object, threshold, lattice, spacing);
  const Points& samples = found.samples;
  const std::vector<int32_t>& sample_face = found.sample_face;
  const auto n_pairs = static_cast<Eigen::Index>(found.pairs());
  InteractionPoints out;
  out.point_a.resize(n_pairs, 3);
  out.point_b.resize(n_pairs, 3);
  for (auto* v :
       {&out.sample_a, &out.sample_b, &out.face_a, &out.face_b, &out.object_a, &out.object_b}) {
    v->reserve(found.pairs());
  }
  // In (sample a, sample b) order: each group's partners sorted.
  Eigen::Index row = 0;
  for (Eigen::Index a = 0; a < samples.rows(); ++a) {
    const int32_t fa = sample_face[static_cast<size_t>(a)];
    const size_t begin = found.start[static_cast<size_t>(a)];
    const size_t end = found.start[static_cast<size_t>(a) + 1];
    std::sort(found.partner.begin() + static_cast<std::ptrdiff_t>(begin),
              found.partner.begin() + static_cast<std::ptrdiff_t>(end));
    for (size_t p = begin; p < end; ++p, ++row) {
      const int32_t b = found.partner[p];
      const int32_t fb = sample_face[static_cast<size_t>(b)];
      out.point_a.row(row) = samples.row(a);
      out.point_b.row(row) = samples.row(b);
      out.sample_a.push_back(static_cast<int32_t>(a));
      out.sample_b.push_back(b);
      out.face_a.push_back(fa);
      out.face_b.push_back(fb);
      out.object_a.push_back(face_object[static_cast<size_t>(fa)]);
      out.object_b.push_back(face_object[static_cast<size_t>(fb)]);
    }
  }
  out.face_pairs = std::move(found.face_pairs);
  return out;
}

}  // namespace dynscope
