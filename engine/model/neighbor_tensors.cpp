// Conversion of neighbour lists and hierarchies to tensors; neighbour gathers.
#include "engine/model/neighbor_tensors.h"

#include <string>

#include "engine/core/error.h"

namespace dynscope {

torch::Tensor NeighborTensors::nearest() const {
  if (index.size(1) == 0) return torch::zeros({index.size(0)}, index.options());
  return index.select(1, 0).clamp_min(0);
}

torch::Tensor NeighborTensors::valid_count() const {
  return count.defined() ? count : mask.sum(1).to(torch::kFloat);
}

torch::Tensor NeighborTensors::has_neighbors() const {
  return has_any.defined() ? has_any : (valid_count() > 0).to(torch::kFloat).unsqueeze(1);
}

torch::Tensor NeighborTensors::inverse_count() const {
  if (inv_count.defined()) return inv_count;
  return has_neighbors() / valid_count().clamp_min(1.0).unsqueeze(1);
}

torch::Tensor NeighborTensors::relative(const torch::Tensor& query, const torch::Tensor& source,
                                        double scale) const {
  if (rel.defined()) return scale == 1.0 ? rel : rel * static_cast<float>(1.0 / scale);
  if (query.size(0) != index.size(0)) {
    throw ValueError("neighbor_list", "has " + std::to_string(index.size(0)) + " rows for " +
                                          std::to_string(query.size(0)) + " query points");
  }
  // Differences in float64 keep them exact far from the origin; then one conversion.
  const torch::Tensor d = gather_neighbors(source, index) - query.unsqueeze(1);
  return ((d / scale).to(torch::kFloat) * mask.unsqueeze(-1)).contiguous();
}

void NeighborTensors::prepare(const torch::Tensor& query, const torch::Tensor& source) {
  // A level without this list (level 0's down/up, the flat baseline's relational) stays empty.
  if (rows() == 0) return;
  // The fused ops read −1 as masked; lists from to_tensors are already in that form.
  index = torch::where(mask, index, torch::full_like(index, -1));
  rel = relative(query, source, 1.0);
  count = mask.sum(1).to(torch::kFloat);
  has_any = (count > 0).to(torch::kFloat).unsqueeze(1);
  inv_count = has_any / count.clamp_min(1.0).unsqueeze(1);
}

NeighborTensors NeighborTensors::to(const torch::Device& device) const {
  NeighborTensors t;
  t.index = index.to(device);
  t.mask = mask.to(device);
  if (rel.defined()) {
    t.rel = rel.to(device);
    t.count = count.to(device);
    t.has_any = has_any.to(device);
    t.inv_count = inv_count.to(device);
  }
  if (gate.defined()) t.gate = gate.to(device);
  return t;
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

HierarchyTensors to_tensors(const Hierarchy& hierarchy, const torch::Device& device) {
  HierarchyTensors out;
  out.levels.reserve(hierarchy.levels.size());
  for (size_t l = 0; l < hierarchy.levels.size(); ++l) {
    const HierarchyLevel& level = hierarchy.levels[l];
    LevelTensors t;
    t.points = points_to_tensor(level.points, device);
    t.same = to_tensors(level.same, device);
    t.relational = to_tensors(level.relational, device);
    t.down = to_tensors(level.down, device);
    t.up = to_tensors(level.up, device);
    t.radius = level.radius;
    t.same.prepare(t.points, t.points);
    t.relational.prepare(t.points, t.points);
    if (l > 0) {
      const LevelTensors& finer = out.levels.back();
      t.down.prepare(t.points, finer.points);
      t.up.prepare(finer.points, t.points);
    }
    out.levels.push_back(std::move(t));
  }
  if (hierarchy.has_mesh && !out.levels.empty()) {
    LevelTensors& l0 = out.levels.front();
    l0.has_mesh = true;
    MeshTensors& mesh = l0.mesh;
    mesh.points = points_to_tensor(hierarchy.mesh.points, device);
    mesh.face_vertices = to_tensors(hierarchy.mesh.face_vertices, device);
    mesh.senders = to_tensors(hierarchy.mesh.senders, device);
    mesh.vertex_points = to_tensors(hierarchy.mesh.vertex_points, device);
    mesh.face_vertices.prepare(mesh.points, l0.points);
    mesh.senders.prepare(mesh.points, mesh.points);
    mesh.vertex_points.prepare(l0.points, mesh.points);
  }
  return out;
}

}  // namespace dynscope
