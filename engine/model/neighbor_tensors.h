// Neighbour lists and hierarchy levels as tensors, and the gathers shared by every conv layer.
#pragma once

#include <torch/types.h>

#include <memory>
#include <vector>

#include "engine/geometry/neighbors.h"
#include "engine/model/hierarchy.h"

namespace dynscope {

/// A NeighborList as tensors: `index` int64 `[M,K]` (−1 where masked), `mask` bool `[M,K]`.
/// prepare() fills what every convolution reading the list shares, once per forward pass: the
/// relative positions p_k − p_0 and the valid counts. Unprepared lists compute them on demand.
struct NeighborTensors {
  torch::Tensor index;
  torch::Tensor mask;
  torch::Tensor rel;        ///< Prepared: p_k − p_0 float32 `[M,K,3]`, zero where masked.
  torch::Tensor count;      ///< Prepared: valid neighbours per row, float32 `[M]`.
  torch::Tensor has_any;    ///< Prepared: 1 where a row has a valid neighbour, float32 `[M,1]`.
  torch::Tensor inv_count;  ///< Prepared: has_any / valid count (0 without neighbours) `[M,1]`.
  /// Optional per-edge factor float32 `[M,K]` every convolution reading the list multiplies into
  /// that edge's term (undefined: 1). Explanations set it to ones with gradients: ∂E/∂gate of an
  /// edge is the first-order effect of its message on E (gradient × input, the input being the
  /// edge's presence).
  torch::Tensor gate;
  /// Set by compact(): the rows that have a valid neighbour, int64 `[A]`, and the list restricted
  /// to them, its rows and its sources both numbered by position in `active`. Undefined / null
  /// when the list is not compacted.
  torch::Tensor active;
  std::shared_ptr<const NeighborTensors> active_list;

  int64_t rows() const { return index.defined() ? index.size(0) : 0; }
  /// The nearest valid source of every row (column 0, clamped to 0 for fully masked rows), `[M]`.
  torch::Tensor nearest() const;
  /// Number of valid neighbours per row as float32 `[M]`.
  torch::Tensor valid_count() const;
  /// 1 where a row has a valid neighbour, else 0, float32 `[M,1]`.
  torch::Tensor has_neighbors() const;
  /// 1 / valid count per row, 0 for rows without neighbours, float32 `[M,1]` (the mean's scale).
  torch::Tensor inverse_count() const;
  /// (p_k − p_0) / scale as float32 `[M,K,3]`, zero where masked; `query` `[M,3]` and `source`
  /// `[N,3]` float64 must be the points the list was built on (prepared lists ignore them).
  torch::Tensor relative(const torch::Tensor& query, const torch::Tensor& source,
                         double scale) const;
  /// Computes rel, count and has_any from the list's `query` `[M,3]` and `source` `[N,3]` points.
  void prepare(const torch::Tensor& query, const torch::Tensor& source);
  /// Fewer rows without neighbours than this, and compact() leaves a list dense: no unit of any
  /// width would use it (ConvUnit::kMinIdleWork).
  static constexpr int64_t kMinIdleRows = 16;
  /// For a prepared list whose queries are its sources: fills `active` and `active_list` when at
  /// least `min_idle_rows` (≥ 1) rows have no valid neighbour and every source a row reads is
  /// itself a row with neighbours, as in a relational list (being within the radius of another
  /// object's point is symmetric). A convolution whose rows without neighbours all give the same
  /// output can then work on the active rows alone (ConvUnit). Otherwise leaves them unset.
  void compact(int64_t min_idle_rows = kMinIdleRows);
  NeighborTensors to(const torch::Device& device) const;
};

/// Converts a NeighborList; throws ValueError if index and mask shapes differ.
NeighborTensors to_tensors(const NeighborList& list, const torch::Device& device = torch::kCPU);

/// to_tensors(list) followed by prepare() on `query` `[M,3]` and `source` `[N,3]` (the points the
/// list was built on), computed in one pass over the list's entries, parallel over rows, with the
/// same values (relative positions differenced in double, then rounded to float). Lists without
/// entries are returned unprepared, as prepare() leaves them. Throws ValueError when the sizes
/// disagree or a valid entry indexes outside `source`.
NeighborTensors prepared_tensors(const NeighborList& list, const Points& query,
                                 const Points& source, const torch::Device& device = torch::kCPU);

/// Positions `[N,3]` as a float64 tensor (float64 so that relative positions stay exact far from
/// the origin).
torch::Tensor points_to_tensor(const Points& points, const torch::Device& device = torch::kCPU);

/// Rows of `values` `[N,C]` at `index` `[M,K]` → `[M,K,C]`; masked (−1) entries read row 0, so
/// callers must zero them with the mask.
torch::Tensor gather_neighbors(const torch::Tensor& values, const torch::Tensor& index);

/// MeshInteraction as tensors: interaction points float64 `[I,3]` and its three lists.
struct MeshTensors {
  torch::Tensor points;
  NeighborTensors face_vertices, senders, vertex_points;
};

/// One hierarchy level as tensors (see HierarchyLevel for what each list indexes).
struct LevelTensors {
  torch::Tensor points;  ///< float64 `[N_l,3]`.
  NeighborTensors same, relational, down, up;
  double radius = 0.0;
  bool has_mesh = false;  ///< Level 0 of a mesh hierarchy: `mesh` is filled.
  MeshTensors mesh;
};

/// All levels of a Hierarchy as tensors, finest first.
struct HierarchyTensors {
  std::vector<LevelTensors> levels;
  int num_levels() const { return static_cast<int>(levels.size()); }
};

/// Converts a Hierarchy (copies every list) and prepares every list on its level's points.
HierarchyTensors to_tensors(const Hierarchy& hierarchy, const torch::Device& device = torch::kCPU);

}  // namespace dynscope
