// Neighbour lists and hierarchy levels as tensors, and the gathers shared by every conv layer.
#pragma once

#include <torch/types.h>

#include <vector>

#include "engine/geometry/neighbors.h"
#include "engine/model/hierarchy.h"

namespace dynscope {

/// A NeighborList as tensors: `index` int64 `[M,K]` (−1 where masked), `mask` bool `[M,K]`.
struct NeighborTensors {
  torch::Tensor index;
  torch::Tensor mask;

  int64_t rows() const { return index.defined() ? index.size(0) : 0; }
  /// The nearest valid source of every row (column 0, clamped to 0 for fully masked rows), `[M]`.
  torch::Tensor nearest() const;
  /// Number of valid neighbours per row as float32 `[M]`.
  torch::Tensor valid_count() const;
  NeighborTensors to(const torch::Device& device) const;
};

/// Converts a NeighborList; throws ValueError if index and mask shapes differ.
NeighborTensors to_tensors(const NeighborList& list, const torch::Device& device = torch::kCPU);

/// Positions `[N,3]` as a float64 tensor (float64 so that relative positions stay exact far from
/// the origin).
torch::Tensor points_to_tensor(const Points& points, const torch::Device& device = torch::kCPU);

/// Rows of `values` `[N,C]` at `index` `[M,K]` → `[M,K,C]`; masked (−1) entries read row 0, so
/// callers must zero them with the mask.
torch::Tensor gather_neighbors(const torch::Tensor& values, const torch::Tensor& index);

/// p_k − p_0 for every neighbour: `query` `[M,3]`, `source` `[N,3]` (float64) → float32 `[M,K,3]`
/// divided by `scale`; masked entries hold garbage and must be masked by the caller.
torch::Tensor relative_positions(const torch::Tensor& query, const torch::Tensor& source,
                                 const torch::Tensor& index, double scale = 1.0);

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

/// Converts a Hierarchy (copies every list).
HierarchyTensors to_tensors(const Hierarchy& hierarchy, const torch::Device& device = torch::kCPU);

}  // namespace dynscope
