// Physion (TDW) HDF5 files: the same reader as dynscope files under Physion's conventions.
//
// Physion stores Unity/TDW data: left-handed, y up, quaternions x y z w, meshes in the object
// frame before `static/scale` is applied, the target and zone as `static/target_id` /
// `static/zone_id`, materials as `static/mass`, `static_friction`, `bounciness`, names as
// `static/model_names`, and labels such as `frames/NNNN/labels/target_contacting_zone` (bool).
// The mapping (x, y, z) -> (x, z, y) turns Unity's (right, up, forward) into dynscope's
// right-handed z-up (right, forward, up); it is a reflection, so triangle winding is flipped.
//
// Physion files carry no frame period. TDW advances physics by its fixed time step, 0.01 s by
// default, once per recorded frame, so dt defaults to 0.01 s; a root attribute `dt` (seconds)
// overrides it. Only the per-frame displacement enters the model, so dt matters for units of
// reported velocities and for playback speed.
#include "engine/io/h5_util.h"
#include "engine/io/scene_file.h"
#include "engine/io/scene_reader.h"

namespace dynscope {
namespace {

constexpr double kPhysionDefaultDt = 0.01;

}  // namespace

FileConvention physion_convention() {
  FileConvention c;
  c.axes << 1, 0, 0,  //
      0, 0, 1,        //
      0, 1, 0;
  c.quaternion_xyzw = true;
  c.default_dt = kPhysionDefaultDt;
  c.default_scenario = "physion";
  c.skip_irregular_labels = true;
  return c;
}

Scene read_physion(const std::string& path) {
  const h5::Group root = h5::Group::open_file(path);
  return read_scene_file(root, physion_convention());
}

}  // namespace dynscope
