// ViewSpec: what to show and from where (JSON), shared by `dynscope render` and the viewer.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "render/camera.h"
#include "render/colormap.h"

namespace dynscope::render {

/// Which layers a view shows. Point layers come from the scene's point cloud (scene files) or
/// from a rollout's true and predicted point sets.
struct ViewLayers {
  bool grid = true;
  bool meshes = true;
  bool ground_truth = false;        ///< True (ground-truth) points.
  bool prediction = true;           ///< Predicted points (rollouts only).
  bool ghost = false;               ///< The other point set drawn translucent over the shown one.
  bool error = false;               ///< Colour predicted points by their distance to the truth.
  bool level_points = false;        ///< Points of U-Net level `level`.
  bool voxels = false;              ///< Voxel boxes of level `level`.
  bool neighborhoods = false;       ///< Object kNN and relational edges of the picked point.
  bool interaction_points = false;  ///< Mesh interaction-point pairs between objects.
};

/// Camera part of a view: either fitted to the scene at render time or given explicitly.
struct CameraSpec {
  bool fit = true;     ///< Centre on the scene bounds and set the distance (keeps the angles).
  std::string preset;  ///< "front", "side", "top", "iso" sets yaw/pitch; empty keeps them.
  Camera camera;
};

/// Everything `dynscope render` and the viewer need to reproduce an image.
struct ViewSpec {
  int frame = 0;
  CameraSpec camera;
  int width = 640;  ///< Image size in pixels.
  int height = 480;
  Color background = Color(1.0f, 1.0f, 1.0f);
  ViewLayers layers;
  std::string colormap = "viridis";
  bool auto_range = true;  ///< Error range from the data (0 .. max over the rendered frames).
  float range_min = 0.0f;
  float range_max = 0.1f;
  int picked_point = -1;         ///< Index into the level's points; -1 for none.
  int level = 0;                 ///< U-Net level for level points, voxels and neighbourhoods.
  bool labels = true;            ///< Frame number and layer names drawn on images.
  float point_radius = 0.0f;     ///< Sphere radius; 0 picks one from the voxel size.
  /// Point drawing: "auto" (flat discs above kDiscPointThreshold points), "spheres" or "discs".
  std::string point_style = "auto";
  /// Sampling voxel of the points (level 0); 0 picks the paper's default per scale. Levels,
  /// neighbour counts and radii are the model's (its trace, or the level view of its config).
  double voxel = 0.0;

  /// Throws ValueError naming the first bad field (sizes, frame, level, colormap, range, ...).
  void validate() const;
};

/// The view as JSON (every field written, so a saved view reproduces exactly).
nlohmann::json view_spec_to_json(const ViewSpec& view);
/// Reads a view from JSON. Missing keys keep their defaults; unknown keys are ignored with a
/// warning. Throws FormatError(source, "key.path", ...) for a wrong type or invalid value.
ViewSpec view_spec_from_json(const nlohmann::json& json, const std::string& source);
/// Writes the view as pretty JSON, atomically; throws IoError naming `path`.
void save_view_spec(const ViewSpec& view, const std::string& path);
/// Reads a view file; throws IoError if unreadable, FormatError for bad JSON or bad values.
ViewSpec load_view_spec(const std::string& path);

}  // namespace dynscope::render
