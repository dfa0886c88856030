// Trace file writer and reader (layout in trace_file.h).
#include "engine/io/trace_file.h"

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

}  // namespace

void write_trace(const ModelTrace& trace, const std::string& path) {
  h5::silence_errors();
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
  return t;
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
