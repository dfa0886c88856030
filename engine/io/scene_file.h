// HDF5 scene files: dynscope's Physion-modelled layout and real Physion files (README).
#pragma once

#include <string>

#include "engine/scene/scene.h"

namespace dynscope {

/// True if `path` exists and starts with the HDF5 signature.
bool is_hdf5_file(const std::string& path);

/// Writes `scene` to `path` in the dynscope layout (z up, wxyz), atomically (temp file + rename).
/// Throws ValueError if the scene is inconsistent, IoError if the file cannot be written.
void write_scene(const Scene& scene, const std::string& path);

/// Reads a scene file. Files without dynscope's `up_axis`/`quaternion_order` attributes are read
/// as Physion files (see read_physion). Throws IoError/FormatError naming the file and field.
Scene read_scene(const std::string& path);

/// Reads a Physion (TDW) HDF5 file: converts left-handed y-up to z-up (x,y,z)->(x,z,y),
/// quaternions xyzw -> wxyz, applies `static/scale`, maps `static/target_id`/`zone_id` to roles;
/// dt is 0.01 s (TDW's default physics step) unless the root has a `dt` attribute.
/// Missing optional groups are tolerated; malformed required ones throw FormatError.
Scene read_physion(const std::string& path);

}  // namespace dynscope
