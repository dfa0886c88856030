// Conversion of neighbour lists and hierarchies to tensors; neighbour gathers.
#include "engine/model/neighbor_tensors.h"

#include <algorithm>
#include <atomic>
#include <string>
#include <vector>

#include "engine/core/error.h"
#include "engine/core/parallel.h"

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
  inv_count = inverse_count();  // from count and has_any, by the one formula
}

void NeighborTensors::compact(int64_t min_idle_rows) {
  active = torch::Tensor();
  active_list.reset();
  if (rows() == 0 || !count.defined() || !rel.defined() || !index.device().is_cpu()) return;
  const int64_t m = rows(), k = index.size(1);
  const torch::Tensor idx = index.contiguous(), cnt = count.contiguous();
  const int64_t* ip = idx.data_ptr<int64_t>();
  const float* cp = cnt.data_ptr<float>();
  // position[r]: place of row r among the rows with neighbours, −1 for the others.
  std::vector<int64_t> position(static_cast<size_t>(m), -1), rows_with;
  for (int64_t r = 0; r < m; ++r) {
    if (cp[r] > 0) {
      position[static_cast<size_t>(r)] = static_cast<int64_t>(rows_with.size());
      rows_with.push_back(r);
    }
  }
  const auto a = static_cast<int64_t>(rows_with.size());
  if (a == m || m - a < min_idle_rows) return;
  torch::Tensor sub_index = torch::empty({a, k}, idx.options());
  int64_t* sp = sub_index.data_ptr<int64_t>();
  for (int64_t i = 0; i < a; ++i) {
    const int64_t* from = ip + rows_with[static_cast<size_t>(i)] * k;
    for (int64_t n = 0; n < k; ++n) {
      const int64_t src = from[n];
      if (src < 0) {
        sp[i * k + n] = -1;
        continue;
      }
      // A source outside the rows with neighbours (or beyond the rows): no compaction.
      if (src >= m || position[static_cast<size_t>(src)] < 0) return;
      sp[i * k + n] = position[static_cast<size_t>(src)];
    }
  }
  const torch::Tensor kept = torch::from_blob(rows_with.data(), {a}, idx.options()).clone();
  auto list = std::make_shared<NeighborTensors>();
  list->index = sub_index;
  list->mask = mask.index_select(0, kept);
  list->rel = rel.index_select(0, kept);
  list->count = count.index_select(0, kept);
  list->has_any = has_any.index_select(0, kept);
  list->inv_count = inv_count.index_select(0, kept);
  active = kept;
  active_list = std::move(list);
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
  if (active_list) {
    t.active = active.to(device);
    t.active_list = std::make_shared<NeighborTensors>(active_list->to(device));
  }
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

NeighborTensors prepared_tensors(const NeighborList& list, const Points& query,
                                 const Points& source, const torch::Device& device) {
  const int64_t m = list.index.rows(), k = list.index.cols();
  if (m * k == 0) return to_tensors(list, device);
  if (list.mask.rows() != m || list.mask.cols() != k || query.rows() != m) {
    throw ValueError("neighbor_list", "has " + std::to_string(m) + "x" + std::to_string(k) +
                                          " entries, a " + std::to_string(list.mask.rows()) + "x" +
                                          std::to_string(list.mask.cols()) + " mask and " +
                                          std::to_string(query.rows()) + " query points");
  }
  const auto on = [](torch::ScalarType t) { return torch::TensorOptions().dtype(t); };
  NeighborTensors t;
  t.index = torch::empty({m, k}, on(torch::kInt64));
  t.mask = torch::empty({m, k}, on(torch::kBool));
  t.rel = torch::empty({m, k, 3}, on(torch::kFloat));
  t.count = torch::empty({m}, on(torch::kFloat));
  t.has_any = torch::empty({m, 1}, on(torch::kFloat));
  t.inv_count = torch::empty({m, 1}, on(torch::kFloat));
  int64_t* index = t.index.data_ptr<int64_t>();
  bool* mask = t.mask.data_ptr<bool>();
  float* rel = t.rel.data_ptr<float>();
  float* count = t.count.data_ptr<float>();
  float* has_any = t.has_any.data_ptr<float>();
  float* inv_count = t.inv_count.data_ptr<float>();
  const int32_t* in_index = list.index.data();
  const uint8_t* in_mask = list.mask.data();
  const int64_t n_src = source.rows();
  const double* src = source.data();  // [N,3] row-major
  static constexpr double kZeros[3] = {0.0, 0.0, 0.0};
  const double* first = n_src > 0 ? src : kZeros;
  std::atomic<bool> out_of_range{false};
  parallel_chunks(m, 256, true, [&](int64_t begin, int64_t end) {
    bool bad = false;
    for (int64_t r = begin; r < end; ++r) {
      int64_t valid = 0;
      const double qx = query(r, 0), qy = query(r, 1), qz = query(r, 2);
      for (int64_t j = 0; j < k; ++j) {
        const int64_t e = r * k + j;
        const int64_t s = in_index[e];
        const bool ok = in_mask[e] != 0 && s >= 0 && s < n_src;
        bad |= in_mask[e] != 0 && !ok;
        // Without branches: a masked entry reads the first source row (or zeros) and writes 0.
        const double* p = ok ? src + 3 * s : first;
        const auto dx = static_cast<float>(p[0] - qx), dy = static_cast<float>(p[1] - qy),
                   dz = static_cast<float>(p[2] - qz);
        mask[e] = ok;
        index[e] = ok ? s : -1;
        rel[3 * e] = ok ? dx : 0.0f;
        rel[3 * e + 1] = ok ? dy : 0.0f;
        rel[3 * e + 2] = ok ? dz : 0.0f;
        valid += ok ? 1 : 0;
      }
      const float c = static_cast<float>(valid), has = valid > 0 ? 1.0f : 0.0f;
      count[r] = c;
      has_any[r] = has;
      inv_count[r] = has / std::max(c, 1.0f);
    }
    if (bad) out_of_range = true;
  });
  if (out_of_range) {
    throw ValueError("neighbor_list", "a valid entry indexes outside the " + std::to_string(n_src) +
                                          " source points");
  }
  return device.is_cpu() ? t : t.to(device);
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
    t.radius = level.radius;
    t.same = prepared_tensors(level.same, level.points, level.points, device);
    t.relational = prepared_tensors(level.relational, level.points, level.points, device);
    t.relational.compact();
    if (l > 0) {
      const Points& finer = hierarchy.levels[l - 1].points;
      t.down = prepared_tensors(level.down, level.points, finer, device);
      t.up = prepared_tensors(level.up, finer, level.points, device);
    } else {
      t.down = to_tensors(level.down, device);
      t.up = to_tensors(level.up, device);
    }
    out.levels.push_back(std::move(t));
  }
  if (hierarchy.has_mesh && !out.levels.empty()) {
    LevelTensors& l0 = out.levels.front();
    l0.has_mesh = true;
    MeshTensors& mesh = l0.mesh;
    mesh.points = points_to_tensor(hierarchy.mesh.points, device);
    const Points& vertices = hierarchy.levels.front().points;
    const Points& interaction = hierarchy.mesh.points;
    mesh.face_vertices =
        prepared_tensors(hierarchy.mesh.face_vertices, interaction, vertices, device);
    mesh.senders = prepared_tensors(hierarchy.mesh.senders, interaction, interaction, device);
    mesh.vertex_points =
        prepared_tensors(hierarchy.mesh.vertex_points, vertices, interaction, device);
  }
  return out;
}

}  // namespace dynscope
