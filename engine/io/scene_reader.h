// Internal: the one scene-file reader shared by dynscope files and Physion files.
#pragma once

#include <optional>
#include <string>

#include "engine/core/types.h"
#include "engine/io/h5_util.h"
#include "engine/scene/scene.h"

namespace dynscope {

/// How a file's numbers map onto dynscope's conventions (z up, right-handed, wxyz).
struct FileConvention {
  /// A: file coordinates -> dynscope coordinates, a signed permutation. Positions, mesh
  /// vertices and particles become A·x, rotations A·R·Aᵀ, scales |A|·s; det A < 0 flips the
  /// triangle winding so that faces stay counter-clockwise seen from outside.
  Mat3 axes = Mat3::Identity();
  /// True if rotation rows are stored x, y, z, w (Physion, scipy); false for w, x, y, z.
  bool quaternion_xyzw = false;
  /// Seconds between frames when the root has no `dt` attribute; nullopt makes `dt` required.
  std::optional<double> default_dt;
  /// Scenario name when the root has no `scenario` attribute.
  std::string default_scenario;
  /// True: label datasets that are not numeric scalars in every frame are skipped (Physion
  /// stores other per-frame data there); false: they are a FormatError.
  bool skip_irregular_labels = false;
};

/// Physion's (TDW's) conventions: A = (x, y, z) -> (x, z, y), quaternions x y z w, dt 0.01 s
/// unless the root has `dt`, scenario "physion", irregular labels skipped (physion_reader.cpp).
FileConvention physion_convention();

/// Reads the Physion-modelled layout documented in scene_file.cpp from the open file `root`
/// under `convention`. Throws IoError naming the file if it cannot be read, FormatError naming
/// the file and the dataset for a missing, mis-shaped, mis-typed or non-finite required field.
Scene read_scene_file(const h5::Group& root, const FileConvention& convention);

}  // namespace dynscope
