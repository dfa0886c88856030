// Trace file writer and reader (layout in trace_file.h).
#include "engine/io/trace_file.h"

#include <cmath>
#include <string>
#include <vector>

#include "engine/core/error.h"
#include "engine/io/h5_util.h"
#include "engine/io/scene_file.h"
#include "engine/io/temp_file.h"

namespace dynscope {

namespace {

void check_list(const TraceList& l, const std::string& where) {
  if (l.index.rows() != l.mask.rows() || l.index.cols() != l.mask.cols()) {
    throw ValueError(where + "/" + l.name, "index and mask shapes differ");
  }
}

void write_list(const h5::Group& parent, const TraceList& l) {
  const h5::Group g = parent.create_group(l.name);
  g.write_attribute("query_level", static_cast<int64_t>(l.query_level));
  g.write_attribute("source_level", static_cast<int64_t>(l.source_level));
  g.write_int_matrix("index", l.index.data(), static_cast<hsize_t>(l.index.rows()),
                     static_cast<hsize_t>(l.index.cols()));
  const hsize_t dims[2] = {static_cast<hsize_t>(l.mask.rows()),
                           static_cast<hsize_t>(l.mask.cols())};
  h5::Handle space(H5Screate_simple(2, dims, nullptr));
  h5::Handle ds(
      H5Dcreate2(g.id(), "mask", H5T_STD_U8LE, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!space.valid() || !ds.valid() ||
      (l.mask.size() > 0 &&
       H5Dwrite(ds.get(), H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, l.mask.data()) < 0)) {
    throw IoError(g.file(), g.child_path("mask") + ": write failed");
  }
}

TraceList read_list(const h5::Group& parent, const std::string& name) {
  const h5::Group g = parent.group(name);
  TraceList l;
  l.name = name;
  l.query_level = static_cast<int>(g.int_attribute("query_level").value_or(0));
  l.source_level = static_cast<int>(g.int_attribute("source_level").value_or(0));
  l.index = g.read_int_matrix("index", -1, -1).cast<int32_t>();
  l.mask = g.read_int_matrix("mask", l.index.rows(), l.index.cols()).cast<uint8_t>();
  return l;
}

void write_lists(const h5::Group& parent, const std::vector<TraceList>& lists,
                 const std::string& where) {
  const h5::Group g = parent.create_group("lists");
  for (const TraceList& l : lists) {
    check_list(l, where);
    write_list(g, l);
  }
}

std::vector<TraceList> read_lists(const h5::Group& parent) {
  std::vector<TraceList> out;
  if (!parent.has_group("lists")) return out;
  const h5::Group g = parent.group("lists");
  for (const std::string& name : g.children()) out.push_back(read_list(g, name));
  return out;
}

std::vector<int32_t> to_int32(const std::vector<int64_t>& v) {
  return std::vector<int32_t>(v.begin(), v.end());
}

std::string required_string(const h5::Group& root, const char* name) {
  const auto v = root.string_attribute(name);
  if (!v) throw FormatError(root.file(), std::string("@") + name, "missing attribute");
  return *v;
}

template <typename Matrix>
void require_finite(const Matrix& m, const std::string& path, const std::string& field) {
  if (!m.allFinite()) throw FormatError(path, field, "non-finite value (NaN or inf)");
}

// Every index of `list` is -1 (masked, mask 0) or a point of its source level, and it has one
// row per point of its query level.
void validate_list(const TraceList& l, const std::string& path, const std::string& field,
                   int64_t query_rows, int64_t source_rows) {
  if (l.index.rows() != query_rows) {
    throw FormatError(path, field + "/index",
                      "has " + std::to_string(l.index.rows()) + " rows, expected " +
                          std::to_string(query_rows) + " (one per query point)");
  }
  for (Eigen::Index r = 0; r < l.index.rows(); ++r) {
    for (Eigen::Index c = 0; c < l.index.cols(); ++c) {
      const int32_t i = l.index(r, c);
      if (i < -1 || i >= source_rows || (i == -1 && l.mask(r, c) != 0)) {
        throw FormatError(path, field + "/index",
                          "entry " + std::to_string(i) + " in row " + std::to_string(r) +
                              " is not -1 (masked) or a point in [0, " +
                              std::to_string(source_rows) + ")");
      }
    }
  }
}

int64_t level_rows(const ModelTrace& t, int level, const std::string& path,
                   const std::string& field) {
  if (level < 0 || level >= static_cast<int>(t.levels.size())) {
    throw FormatError(path, field,
                      "level " + std::to_string(level) + " is not in [0, " +
                          std::to_string(t.levels.size()) + ")");
  }
  return t.levels[static_cast<size_t>(level)].points.rows();
}

// The checks a reader of a trace relies on: finite values, sizes that agree, indices in range.
void validate_trace(const ModelTrace& t, const std::string& path) {
  for (size_t l = 0; l < t.levels.size(); ++l) {
    const TraceLevel& lv = t.levels[l];
    const std::string where = "levels/" + std::to_string(l);
    require_finite(lv.points, path, where + "/points");
    if (!std::isfinite(lv.voxel) || !std::isfinite(lv.radius) || lv.voxel < 0 || lv.radius < 0) {
      throw FormatError(path, where, "voxel and radius must be finite and >= 0");
    }
    if (l > 0) {
      if (lv.kept.size() != static_cast<size_t>(lv.points.rows())) {
        throw FormatError(path, where + "/kept", "missing (one index per point of the level)");
      }
      const int64_t below = t.levels[l - 1].points.rows();
      for (size_t i = 0; i < lv.kept.size(); ++i) {
        if (lv.kept[i] < 0 || lv.kept[i] >= below) {
          throw FormatError(path, where + "/kept",
                            "entry " + std::to_string(lv.kept[i]) + " at " + std::to_string(i) +
                                " is not a point of level " + std::to_string(l - 1));
        }
      }
    }
    for (const TraceList& list : lv.lists) {
      const std::string field = where + "/lists/" + list.name;
      validate_list(list, path, field, level_rows(t, list.query_level, path, field),
                    level_rows(t, list.source_level, path, field));
    }
  }
  if (t.has_mesh) {
    require_finite(t.mesh.points, path, "mesh/points");
    const int64_t points = t.levels.empty() ? 0 : t.levels[0].points.rows();
    if (t.mesh.faces.size() > 0 &&
        (t.mesh.faces.minCoeff() < 0 || t.mesh.faces.maxCoeff() >= points)) {
      throw FormatError(path, "mesh/faces",
                        "index outside the level-0 points [0, " + std::to_string(points) + ")");
    }
    for (int32_t f : t.mesh.face) {
      if (f < 0 || f >= t.mesh.faces.rows()) {
        throw FormatError(path, "mesh/face",
                          "face " + std::to_string(f) + " is not in [0, " +
                              std::to_string(t.mesh.faces.rows()) + ")");
      }
    }
  }
  for (const TraceFeatures& f : t.features) {
    const std::string field = "features/" + f.block;
    const int64_t rows = level_rows(t, f.level, path, field);
    if (static_cast<int64_t>(f.norms.size()) != rows) {
      throw FormatError(path, field,
                        "has " + std::to_string(f.norms.size()) + " values, expected " +
                            std::to_string(rows) + " (one per point of level " +
                            std::to_string(f.level) + ")");
    }
    for (double v : f.norms) {
      if (!std::isfinite(v) || v < 0) {
        throw FormatError(path, field, "norms must be finite and >= 0");
      }
    }
  }
  for (size_t i = 0; i < t.queries.size(); ++i) {
    const TraceQuery& q = t.queries[i];
    const std::string field = "queries/" + std::to_string(i);
    level_rows(t, 0, path, field);
    if (q.point < 0 || q.point >= t.levels[0].points.rows()) {
      throw FormatError(path, field + "/@point", "is not a level-0 point");
    }
    if (q.query_index < 0 || q.query_index >= level_rows(t, q.level, path, field + "/@level")) {
      throw FormatError(path, field + "/@query_index",
                        "is not a point of level " + std::to_string(q.level));
    }
    require_finite(q.weights, path, field + "/weights");
  }
}

}  // namespace

void write_trace(const ModelTrace& trace, const std::string& path) {
  h5::silence_errors();
  if (trace.source != kTraceSourceScene && trace.source != kTraceSourceRollout) {
    throw ValueError("source", "'" + trace.source + "' is neither '" + kTraceSourceScene +
                                   "' nor '" + kTraceSourceRollout + "'");
  }
  for (size_t l = 0; l < trace.levels.size(); ++l) {
    const TraceLevel& lv = trace.levels[l];
    if (lv.object_ids.size() != static_cast<size_t>(lv.points.rows()) ||
        (!lv.kept.empty() && lv.kept.size() != lv.object_ids.size())) {
      throw ValueError("levels/" + std::to_string(l), "object_ids/kept sizes differ from points");
    }
  }
  for (const TraceQuery& q : trace.queries) {
    if (q.neighbors.size() != q.mask.size() ||
        static_cast<size_t>(q.weights.rows()) != q.neighbors.size()) {
      throw ValueError("queries", "neighbors, mask and weights of " + q.conv + " differ in size");
    }
  }
  TempFile temp(path);
  {
    h5::Group root = h5::Group::create_file(temp.path());
    root.write_attribute("format", std::string(kTraceFormatName));
    root.write_attribute("format_version", kTraceFormatVersion);
    root.write_attribute("up_axis", std::string("z"));
    root.write_attribute("scene_path", trace.scene_path);
    root.write_attribute("checkpoint_path", trace.checkpoint_path);
    root.write_attribute("source", trace.source);
    root.write_attribute("rollout_path", trace.rollout_path);
    root.write_attribute("model_config", trace.model_config);
    root.write_attribute("frame", static_cast<int64_t>(trace.frame));
    root.write_attribute("num_levels", static_cast<int64_t>(trace.levels.size()));

    const h5::Group levels = root.create_group("levels");
    for (size_t l = 0; l < trace.levels.size(); ++l) {
      const TraceLevel& lv = trace.levels[l];
      const h5::Group g = levels.create_group(std::to_string(l));
      g.write_attribute("voxel", lv.voxel);
      g.write_attribute("radius", lv.radius);
      g.write_matrix("points", lv.points.data(), static_cast<hsize_t>(lv.points.rows()), 3);
      g.write_int_vector("object_ids", lv.object_ids);
      if (!lv.kept.empty()) g.write_int_vector("kept", lv.kept);
      write_lists(g, lv.lists, "levels/" + std::to_string(l));
    }
    if (trace.has_mesh) {
      const h5::Group g = root.create_group("mesh");
      g.write_int_matrix("faces", trace.mesh.faces.data(),
                         static_cast<hsize_t>(trace.mesh.faces.rows()), 3);
      g.write_matrix("points", trace.mesh.points.data(),
                     static_cast<hsize_t>(trace.mesh.points.rows()), 3);
      g.write_int_vector("face", trace.mesh.face);
      g.write_int_vector("object_ids", trace.mesh.object_ids);
      write_lists(g, trace.mesh.lists, "mesh");
    }
    const h5::Group features = root.create_group("features");
    for (const TraceFeatures& f : trace.features) {
      features.write_vector(f.block, f.norms);
      // Attributes live on the dataset; Group wraps groups only, so store the level in a
      // sibling attribute named after the block.
      features.write_attribute(f.block + ".level", static_cast<int64_t>(f.level));
    }
    const h5::Group queries = root.create_group("queries");
    for (size_t i = 0; i < trace.queries.size(); ++i) {
      const TraceQuery& q = trace.queries[i];
      const h5::Group g = queries.create_group(std::to_string(i));
      g.write_attribute("point", static_cast<int64_t>(q.point));
      g.write_attribute("conv", q.conv);
      g.write_attribute("level", static_cast<int64_t>(q.level));
      g.write_attribute("list", q.list);
      g.write_attribute("query_index", static_cast<int64_t>(q.query_index));
      g.write_int_vector("neighbors", q.neighbors);
      g.write_uint8_vector("mask", q.mask);
      const h5::MatrixXdR w = q.weights;
      g.write_matrix("weights", w.data(), static_cast<hsize_t>(w.rows()),
                     static_cast<hsize_t>(w.cols()));
    }
    root.close();
  }
  temp.commit();
}

ModelTrace read_trace(const std::string& path) {
  h5::silence_errors();
  const h5::Group root = h5::Group::open_file(path);
  const std::string format = required_string(root, "format");
  if (format != kTraceFormatName) {
    throw FormatError(path, "@format", "is '" + format + "', expected '" + kTraceFormatName + "'");
  }
  const auto version = root.int_attribute("format_version");
  if (!version || *version < 1 || *version > kTraceFormatVersion) {
    throw FormatError(path, "@format_version",
                      version ? "unsupported version " + std::to_string(*version) : "missing");
  }
  ModelTrace t;
  t.scene_path = required_string(root, "scene_path");
  t.checkpoint_path = required_string(root, "checkpoint_path");
  // Files written before rollout-state traces existed are traces of the scene.
  t.source = root.string_attribute("source").value_or(kTraceSourceScene);
  if (t.source != kTraceSourceScene && t.source != kTraceSourceRollout) {
    throw FormatError(path, "@source",
                      "'" + t.source + "' is neither '" + kTraceSourceScene + "' nor '" +
                          kTraceSourceRollout + "'");
  }
  t.rollout_path = root.string_attribute("rollout_path").value_or("");
  t.model_config = required_string(root, "model_config");
  t.frame = static_cast<int>(root.int_attribute("frame").value_or(0));
  const auto num_levels = root.int_attribute("num_levels");
  if (!num_levels || *num_levels < 0) throw FormatError(path, "@num_levels", "missing");

  const h5::Group levels = root.group("levels");
  for (int64_t l = 0; l < *num_levels; ++l) {
    const h5::Group g = levels.group(std::to_string(l));
    TraceLevel lv;
    lv.voxel = g.double_attribute("voxel").value_or(0.0);
    lv.radius = g.double_attribute("radius").value_or(0.0);
    lv.points = g.read_matrix("points", -1, 3);
    lv.object_ids = to_int32(g.read_int_vector("object_ids", lv.points.rows()));
    if (g.has_dataset("kept")) lv.kept = to_int32(g.read_int_vector("kept", lv.points.rows()));
    lv.lists = read_lists(g);
    t.levels.push_back(std::move(lv));
  }
  if (root.has_group("mesh")) {
    const h5::Group g = root.group("mesh");
    t.has_mesh = true;
    t.mesh.faces = g.read_int_matrix("faces", -1, 3).cast<int32_t>();
    t.mesh.points = g.read_matrix("points", -1, 3);
    t.mesh.face = to_int32(g.read_int_vector("face", t.mesh.points.rows()));
    t.mesh.object_ids = to_int32(g.read_int_vector("object_ids", t.mesh.points.rows()));
    t.mesh.lists = read_lists(g);
  }
  const h5::Group features = root.group("features");
  for (const std::string& name : features.children()) {
    TraceFeatures f;
    f.block = name;
    f.norms = features.read_vector(name, -1);
    const auto level = features.int_attribute(name + ".level");
    if (!level) throw FormatError(path, "features/@" + name + ".level", "missing attribute");
    f.level = static_cast<int>(*level);
    t.features.push_back(std::move(f));
  }
  const h5::Group queries = root.group("queries");
  for (size_t i = 0; queries.has_group(std::to_string(i)); ++i) {
    const h5::Group g = queries.group(std::to_string(i));
    TraceQuery q;
    q.point = static_cast<int>(g.int_attribute("point").value_or(0));
    q.conv = required_string(g, "conv");
    q.level = static_cast<int>(g.int_attribute("level").value_or(0));
    q.list = required_string(g, "list");
    q.query_index = static_cast<int>(g.int_attribute("query_index").value_or(0));
    q.neighbors = to_int32(g.read_int_vector("neighbors", -1));
    const std::vector<int64_t> mask =
        g.read_int_vector("mask", static_cast<int64_t>(q.neighbors.size()));
    q.mask.assign(mask.begin(), mask.end());
    q.weights = g.read_matrix("weights", static_cast<int64_t>(q.neighbors.size()), -1);
    t.queries.push_back(std::move(q));
  }
  validate_trace(t, path);
  return t;
}

void check_trace_matches_scene(const ModelTrace& trace, const Scene& scene,
                               const std::string& trace_path) {
  if (trace.frame < 0 || trace.frame >= scene.num_frames()) {
    throw FormatError(trace_path, "@frame",
                      "frame " + std::to_string(trace.frame) + " is not in the scene's [0, " +
                          std::to_string(scene.num_frames()) + ")");
  }
  if (trace.levels.empty()) return;
  const TraceLevel& level0 = trace.levels[0];
  std::vector<Aabb> boxes(scene.objects.size());
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    boxes[i] = Aabb::of(scene.world_vertices(static_cast<int>(i), trace.frame));
    // Sampled surface points lie on the object; the margin covers float rounding and
    // vertex-clustered mesh input.
    const Vec3 margin = Vec3::Constant(0.25 * (boxes[i].max - boxes[i].min).norm() + 1e-6);
    boxes[i].min -= margin;
    boxes[i].max += margin;
  }
  for (Eigen::Index p = 0; p < level0.points.rows(); ++p) {
    const int object = scene.object_index(level0.object_ids[static_cast<size_t>(p)]);
    if (object < 0) {
      throw FormatError(trace_path, "levels/0/object_ids",
                        "object " + std::to_string(level0.object_ids[static_cast<size_t>(p)]) +
                            " is not in the scene (the trace belongs to another scene)");
    }
    if (trace.source == kTraceSourceRollout) continue;  // predictions may leave their object
    const Vec3 x = level0.points.row(p).transpose();
    const Aabb& box = boxes[static_cast<size_t>(object)];
    if ((x.array() < box.min.array()).any() || (x.array() > box.max.array()).any()) {
      throw FormatError(trace_path, "levels/0/points",
                        "point " + std::to_string(p) + " is not on its object at frame " +
                            std::to_string(trace.frame) +
                            " of the scene (the trace belongs to another scene)");
    }
  }
}

bool is_trace_file(const std::string& path) {
  if (!is_hdf5_file(path)) return false;
  h5::silence_errors();
  try {
    const h5::Group root = h5::Group::open_file(path);
    return root.string_attribute("format").value_or("") == kTraceFormatName;
  } catch (const Error&) {
    return false;
  }
}

int trace_level0_point(const ModelTrace& trace, int level, int index) {
  if (level < 0 || level >= static_cast<int>(trace.levels.size())) {
    throw ValueError("level", std::to_string(level) + " is not a level of the trace (it has " +
                                  std::to_string(trace.levels.size()) + ")");
  }
  const auto size = [&](int l) { return trace.levels[static_cast<size_t>(l)].points.rows(); };
  if (index < 0 || index >= size(level)) {
    throw ValueError("point", std::to_string(index) + " is outside the " +
                                  std::to_string(size(level)) + " points of level " +
                                  std::to_string(level));
  }
  for (int l = level; l > 0; --l) {
    const std::vector<int32_t>& kept = trace.levels[static_cast<size_t>(l)].kept;
    if (static_cast<Eigen::Index>(kept.size()) != size(l)) {
      throw ValueError("kept", "level " + std::to_string(l) + " has no kept indices");
    }
    index = kept[static_cast<size_t>(index)];
  }
  return index;
}

}  // namespace dynscope
