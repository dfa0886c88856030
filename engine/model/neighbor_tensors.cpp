// Conversion of neighbour lists and hierarchies to tensors; neighbour gathers.
#include "engine/model/neighbor_tensors.h"

#include <string>

#include "engine/core/error.h"

namespace dynscope {

torch::Tensor NeighborTensors::nearest() const {
  if (index.size(1) == 0) return torch::zeros({index.size(0)}, index.options());
  return index.select(1, 0).clamp_min(0);
}

torch::Tensor NeighborTensors::valid_count() const { return mask.sum(1).to(torch::kFloat); }

NeighborTensors NeighborTensors::to(const torch::Device& device) const {
  return {index.to(device), mask.to(device)};
}

NeighborTensors to_tensors(const NeighborList& list, const torch::Device& device) {
  if (list.index.rows() != list.mask.rows() || list.index.cols() != list.mask.cols()) {
    throw ValueError("neighbor_list", "index is " + std::to_string(list.index.rows()) + "x" +
                                          std::to_string(list.index.cols()) + " but mask is " +
                                          std::to_string(list.mask.rows()) + "x" +
                                          std::to_string(list.mask.cols()));
  }
  const int64_t m = list.index.rows(), k = list.index.cols();
  NeighborTensors t;
  if (m * k == 0) {
    t.index = torch::empty({m, k}, torch::TensorOptions(torch::kInt64).device(device));
    t.mask = torch::empty({m, k}, torch::TensorOptions(torch::kBool).device(device));
    return t;
  }
  // from_blob does not own the memory, so clone before the Eigen storage can go away.
  t.index = torch::from_blob(const_cast<int32_t*>(list.index.data()), {m, k}, torch::kInt32)
                .to(torch::kInt64)
                .to(device);
  t.mask = torch::from_blob(const_cast<uint8_t*>(list.mask.data()), {m, k}, torch::kUInt8)
               .to(torch::kBool)
               .to(device);
  return t;
}

torch::Tensor points_to_tensor(const Points& points, const torch::Device& device) {
  if (points.rows() == 0) {
    return torch::empty({0, 3}, torch::TensorOptions(torch::kFloat64).device(device));
  }
  return torch::from_blob(const_cast<double*>(points.data()), {points.rows(), 3}, torch::kFloat64)
      .clone()
      .to(device);
}

torch::Tensor gather_neighbors(const torch::Tensor& values, const torch::Tensor& index) {
  const int64_t m = index.size(0), k = index.size(1);
  const torch::Tensor flat = index.clamp_min(0).reshape({m * k});
  return values.index_select(0, flat).reshape({m, k, values.size(1)});
}

torch::Tensor relative_positions(const torch::Tensor& query, const torch::Tensor& source,
                                 const torch::Tensor& index, double scale) {
  const torch::Tensor rel = gather_neighbors(source, index) - query.unsqueeze(1);
  return (rel / scale).to(torch::kFloat);
}

HierarchyTensors to_tensors(const Hierarchy& hierarchy, const torch::Device& device) {
  HierarchyTensors out;
  out.levels.reserve(hierarchy.levels.size());
  for (const HierarchyLevel& level : hierarchy.levels) {
    LevelTensors t;
    t.points = points_to_tensor(level.points, device);
    t.same = to_tensors(level.same, device);
    t.relational = to_tensors(level.relational, device);
    t.down = to_tensors(level.down, device);
    t.up = to_tensors(level.up, device);
    t.radius = level.radius;
    out.levels.push_back(std::move(t));
  }
  if (hierarchy.has_mesh && !out.levels.empty()) {
    LevelTensors& l0 = out.levels.front();
    l0.has_mesh = true;
    l0.mesh.points = points_to_tensor(hierarchy.mesh.points, device);
    l0.mesh.face_vertices = to_tensors(hierarchy.mesh.face_vertices, device);
    l0.mesh.senders = to_tensors(hierarchy.mesh.senders, device);
    l0.mesh.vertex_points = to_tensors(hierarchy.mesh.vertex_points, device);
  }
  return out;
}

}  // namespace dynscope
