// Interaction points between mesh faces of different objects (paper supplement §1).
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "engine/core/types.h"

namespace dynscope {

/// Close point pairs on faces of different objects. Pair p joins point_a[p] on face_a[p]
/// (object object_a[p]) with point_b[p] on face_b[p]; each unordered pair is reported once with
/// object_a < object_b. sample_a[p] and sample_b[p] number the two lattice samples (face by face,
/// `(n+1)(n+2)/2` per face of n subdivisions, face_lattice). `face_pairs` lists the distinct
/// (face_a, face_b) pairs, ascending.
struct InteractionPoints {
  Points point_a = Points(0, 3);
  Points point_b = Points(0, 3);
  std::vector<int32_t> sample_a, sample_b;
  std::vector<int32_t> face_a, face_b;
  std::vector<int32_t> object_a, object_b;
  std::vector<std::pair<int32_t, int32_t>> face_pairs;

  size_t size() const { return face_a.size(); }
};

/// The lattice samples of every face and their close pairs across objects, unordered: the search
/// behind find_interaction_points (which validates the same inputs and orders the pairs).
struct SamplePairs {
  Points samples = Points(0, 3);                   ///< `[S,3]` samples, numbered face by face.
  std::vector<int32_t> sample_face;                ///< `[S]` face of each sample.
  std::vector<std::pair<int32_t, int32_t>> pairs;  ///< (sample a, sample b), object a < object b.
};
SamplePairs find_sample_pairs(const Points& vertices, const Faces& faces,
                              const std::vector<int32_t>& face_object, double threshold,
                              int lattice = 3, double spacing = 0.0);

/// Subdivisions per edge of the lattice on a face whose longest edge is `longest_edge`: `lattice`,
/// or with `spacing` > 0 as many more as keep the samples at most `spacing` apart along the edges
/// (ceil(longest_edge / spacing), at most 256), so that a large face is sampled as densely as a
/// small one.
int face_lattice(double longest_edge, int lattice, double spacing);

/// find_sample_pairs' pairs grouped by their first sample, kept compact: the partners of sample a
/// are partner[start[a], start[a+1]), in no particular order. `face_pairs` lists the distinct
/// (face of a, face of b) pairs, ascending, as InteractionPoints does. Callers that need the
/// interaction points rather than every pair in order (build_mesh_interaction) read this instead
/// of one record per pair.
struct GroupedSamplePairs {
  Points samples = Points(0, 3);     ///< `[S,3]` as SamplePairs.
  std::vector<int32_t> sample_face;  ///< `[S]` as SamplePairs.
  std::vector<size_t> start;         ///< `[S+1]` offsets into `partner`.
  std::vector<int32_t> partner;      ///< `[pairs]` second samples, grouped by first sample.
  std::vector<std::pair<int32_t, int32_t>> face_pairs;

  size_t pairs() const { return partner.size(); }
};
GroupedSamplePairs find_grouped_sample_pairs(const Points& vertices, const Faces& faces,
                                             const std::vector<int32_t>& face_object,
                                             double threshold, int lattice = 3,
                                             double spacing = 0.0);

/// Samples points on every face (a barycentric lattice with n = face_lattice(longest edge,
/// `lattice`, `spacing`) subdivisions per edge, i.e. (n+1)(n+2)/2 points, corners included), pairs
/// samples of faces of different objects strictly closer than `threshold` and returns them, ordered
/// by the sample on face_a, then the sample on face_b (samples numbered face by face). The lattice
/// spacing must be small against `threshold` for touching faces to be found. `vertices` `[V,3]`
/// are world positions, `faces` `[F,3]` index them, `face_object` `[F]` gives each face's object
/// id. Throws ValueError on inconsistent sizes, a bad face index, a non-finite vertex, threshold
/// <= 0, lattice < 1 or a negative or non-finite spacing.
InteractionPoints find_interaction_points(const Points& vertices, const Faces& faces,
                                          const std::vector<int32_t>& face_object, double threshold,
                                          int lattice = 3, double spacing = 0.0);

}  // namespace dynscope
