// ViewSpec JSON: typed reading with file/key errors, warnings for unknown keys, atomic saving.
#include "render/view_spec.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "engine/core/error.h"
#include "engine/core/log.h"
#include "engine/io/temp_file.h"
#include "render/image.h"
#include "render/render_scene.h"

namespace dynscope::render {
namespace {

using nlohmann::json;

// Reads typed fields of one JSON object; errors name the source and the dotted key.
class ObjectReader {
 public:
  ObjectReader(const json& object, std::string source, std::string prefix)
      : object_(object), source_(std::move(source)), prefix_(std::move(prefix)) {
    if (!object_.is_object()) {
      throw FormatError(source_,
                        prefix_.empty() ? "(top level)" : prefix_.substr(0, prefix_.size() - 1),
                        std::string("expected an object, got ") + object_.type_name());
    }
  }

  std::string key(const std::string& name) const { return prefix_ + name; }
  const json* find(const std::string& name) {
    known_.insert(name);
    auto it = object_.find(name);
    return it == object_.end() ? nullptr : &*it;
  }

  void read(const std::string& name, bool& out) {
    if (const json* v = find(name)) {
      if (!v->is_boolean()) fail(name, "a boolean", *v);
      out = v->get<bool>();
    }
  }
  void read(const std::string& name, int& out) {
    if (const json* v = find(name)) {
      if (!v->is_number_integer()) fail(name, "an integer", *v);
      out = v->get<int>();
    }
  }
  void read(const std::string& name, double& out) {
    if (const json* v = find(name)) {
      if (!v->is_number()) fail(name, "a number", *v);
      out = v->get<double>();
    }
  }
  void read(const std::string& name, float& out) {
    double d = out;
    read(name, d);
    out = static_cast<float>(d);
  }
  void read(const std::string& name, std::string& out) {
    if (const json* v = find(name)) {
      if (!v->is_string()) fail(name, "a string", *v);
      out = v->get<std::string>();
    }
  }
  void read_vec3(const std::string& name, Eigen::Vector3d& out) {
    if (const json* v = find(name)) {
      if (!v->is_array() || v->size() != 3) fail(name, "an array of 3 numbers", *v);
      for (int k = 0; k < 3; ++k) {
        if (!(*v)[k].is_number()) fail(name, "an array of 3 numbers", *v);
        out[k] = (*v)[k].get<double>();
      }
    }
  }
  ObjectReader child(const std::string& name, const json& value) {
    return ObjectReader(value, source_, prefix_ + name + ".");
  }
  /// Warns once per key the reader never asked for.
  void warn_unknown() const {
    for (auto it = object_.begin(); it != object_.end(); ++it) {
      if (!known_.count(it.key())) {
        log_warn(source_, ": unknown key '", prefix_, it.key(), "' ignored");
      }
    }
  }
  [[noreturn]] void fail(const std::string& name, const char* expected, const json& v) const {
    throw FormatError(
        source_, key(name),
        std::string("expected ") + expected + ", got " + (v.is_null() ? "null" : v.dump()));
  }

 private:
  const json& object_;
  std::string source_;
  std::string prefix_;
  std::set<std::string> known_;
};

// The message of a ValueError without its "name: " prefix (the FormatError names the key).
std::string reason(const ValueError& e) {
  const std::string what = e.what();
  const std::string prefix = e.name() + ": ";
  return what.compare(0, prefix.size(), prefix) == 0 ? what.substr(prefix.size()) : what;
}

}  // namespace

void ViewSpec::validate() const {
  if (frame < 0) throw ValueError("frame", std::to_string(frame) + " < 0");
  check_image_size("image", width, height);
  camera.camera.validate();
  if (!camera.preset.empty()) parse_preset(camera.preset);
  check_colormap(colormap);
  if (!auto_range && !(range_max > range_min)) {
    throw ValueError("colormap.range", "max must be greater than min");
  }
  if (level < 0) throw ValueError("level", std::to_string(level) + " < 0");
  if (picked_point < -1) throw ValueError("picked_point", std::to_string(picked_point) + " < -1");
  if (point_radius < 0) throw ValueError("points.radius", "must be >= 0");
  parse_point_style(point_style);
  if (voxel < 0) throw ValueError("points.voxel", "must be >= 0");
  for (int k = 0; k < 3; ++k) {
    if (!(background[k] >= 0.0f && background[k] <= 1.0f)) {
      throw ValueError("background", "channels must be in [0, 1]");
    }
  }
}

json view_spec_to_json(const ViewSpec& v) {
  const Camera& c = v.camera.camera;
  json j;
  j["frame"] = v.frame;
  j["camera"] = {{"fit", v.camera.fit},
                 {"preset", v.camera.preset},
                 {"target", {c.target.x(), c.target.y(), c.target.z()}},
                 {"distance", c.distance},
                 {"yaw", c.yaw_deg},
                 {"pitch", c.pitch_deg},
                 {"fov", c.fov_deg}};
  j["image"] = {{"width", v.width}, {"height", v.height}};
  j["background"] = {v.background.x(), v.background.y(), v.background.z()};
  const ViewLayers& l = v.layers;
  j["layers"] = {{"grid", l.grid},
                 {"meshes", l.meshes},
                 {"ground_truth", l.ground_truth},
                 {"prediction", l.prediction},
                 {"ghost", l.ghost},
                 {"error", l.error},
                 {"level_points", l.level_points},
                 {"voxels", l.voxels},
                 {"neighborhoods", l.neighborhoods},
                 {"interaction_points", l.interaction_points}};
  j["colormap"] = {{"name", v.colormap},
                   {"range", v.auto_range ? json(nullptr) : json({v.range_min, v.range_max})}};
  j["picked_point"] = v.picked_point;
  j["level"] = v.level;
  j["labels"] = v.labels;
  j["points"] = {{"radius", v.point_radius},
                 {"style", v.point_style},
                 {"voxel", v.voxel}};
  return j;
}

ViewSpec view_spec_from_json(const json& j, const std::string& source) {
  ViewSpec v;
  ObjectReader top(j, source, "");
  top.read("frame", v.frame);
  if (const json* cam = top.find("camera")) {
    ObjectReader r = top.child("camera", *cam);
    Camera& c = v.camera.camera;
    // An explicit position means "use it" unless fit is asked for explicitly.
    if (cam->contains("target") || cam->contains("distance")) v.camera.fit = false;
    r.read("fit", v.camera.fit);
    r.read("preset", v.camera.preset);
    r.read_vec3("target", c.target);
    r.read("distance", c.distance);
    r.read("yaw", c.yaw_deg);
    r.read("pitch", c.pitch_deg);
    r.read("fov", c.fov_deg);
    r.warn_unknown();
    if (!v.camera.preset.empty()) {
      try {
        c.set_preset(parse_preset(v.camera.preset));
      } catch (const ValueError& e) {
        throw FormatError(source, "camera.preset", reason(e));
      }
    }
  }
  if (const json* image = top.find("image")) {
    ObjectReader r = top.child("image", *image);
    r.read("width", v.width);
    r.read("height", v.height);
    r.warn_unknown();
  }
  Eigen::Vector3d background = v.background.cast<double>();
  top.read_vec3("background", background);
  v.background = background.cast<float>();
  if (const json* layers = top.find("layers")) {
    ObjectReader r = top.child("layers", *layers);
    ViewLayers& l = v.layers;
    r.read("grid", l.grid);
    r.read("meshes", l.meshes);
    r.read("ground_truth", l.ground_truth);
    r.read("prediction", l.prediction);
    r.read("ghost", l.ghost);
    r.read("error", l.error);
    r.read("level_points", l.level_points);
    r.read("voxels", l.voxels);
    r.read("neighborhoods", l.neighborhoods);
    r.read("interaction_points", l.interaction_points);
    r.warn_unknown();
  }
  if (const json* cmap = top.find("colormap")) {
    ObjectReader r = top.child("colormap", *cmap);
    r.read("name", v.colormap);
    if (const json* range = r.find("range")) {
      if (range->is_null()) {
        v.auto_range = true;
      } else {
        if (!range->is_array() || range->size() != 2 || !(*range)[0].is_number() ||
            !(*range)[1].is_number()) {
          r.fail("range", "[min, max] or null", *range);
        }
        v.auto_range = false;
        v.range_min = (*range)[0].get<float>();
        v.range_max = (*range)[1].get<float>();
      }
    }
    r.warn_unknown();
  }
  top.read("picked_point", v.picked_point);
  top.read("level", v.level);
  top.read("labels", v.labels);
  if (const json* points = top.find("points")) {
    ObjectReader r = top.child("points", *points);
    r.read("radius", v.point_radius);
    r.read("style", v.point_style);
    r.read("voxel", v.voxel);
    r.warn_unknown();
  }
  top.warn_unknown();
  try {
    v.validate();
  } catch (const ValueError& e) {
    throw FormatError(source, e.name(), reason(e));
  }
  return v;
}

void save_view_spec(const ViewSpec& view, const std::string& path) {
  view.validate();
  TempFile temp(path);
  {
    std::ofstream out(temp.path());
    out << view_spec_to_json(view).dump(2) << "\n";
    if (!out) throw IoError(path, "write failed");
  }
  temp.commit();
}

ViewSpec load_view_spec(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError(path, "cannot open view file");
  std::stringstream text;
  text << in.rdbuf();
  json j;
  try {
    j = json::parse(text.str());
  } catch (const json::parse_error& e) {
    throw FormatError(path, "json", std::string("not valid JSON: ") + e.what());
  }
  return view_spec_from_json(j, path);
}

}  // namespace dynscope::render
