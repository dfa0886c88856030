// Headless batch rendering of a scene or rollout file: PNG per frame, contact sheet, optional MP4.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "render/gl_context.h"
#include "render/scene_adapter.h"
#include "render/view_spec.h"

namespace dynscope::render {

/// Parses "a:b" (frames a .. b-1), "a:" (a to the end), ":b", or "a" (one frame) against a
/// scene of `num_frames`; negative numbers count from the end. Returns [first, last] inclusive.
/// Throws ValueError("--frames", ...) if malformed or empty/out of range.
std::pair<int, int> parse_frame_range(const std::string& text, int num_frames);
/// Parses "WxH" (e.g. "1280x720"); throws ValueError("--size", ...) if malformed or out of
/// render::kMaxImagePixels (check_image_size).
std::pair<int, int> parse_image_size(const std::string& text);
/// Full path of executable `name` found on $PATH, or "" if none.
std::string find_on_path(const std::string& name);

/// What `dynscope render` does.
struct BatchRenderOptions {
  std::string scene_path;  ///< Scene file, or a rollout file for render_rollout_file/render_file.
  std::string view_path;   ///< Optional view spec JSON; defaults otherwise.
  std::string trace_path;  ///< Scenes: model trace (`dynscope trace`) whose levels, neighbour
                           ///< lists and filter weights are drawn; frames default to its frame.
  int level = -1;          ///< >= 0: show this U-Net level's points (overrides the view).
  int picked_point = -1;   ///< >= 0: show this level point's neighbourhoods (overrides the view).
  std::string frames;      ///< parse_frame_range syntax; empty = every frame.
  int width = 0;           ///< Overrides the view's image size when > 0.
  int height = 0;
  std::string out_dir;
  bool contact_sheet = true;
  bool video = true;     ///< MP4 through ffmpeg when it is on PATH.
  int samples = 4;       ///< Multisampling (anti-aliasing).
  bool progress = true;  ///< Progress bar on stderr.
  /// Rollouts: an explanation's shares drawn in place of the error colours (add_attribution_layers)
  /// with `attribution_legend` as the caption's legend.
  std::shared_ptr<const PointAttribution> attribution;
  std::vector<std::string> attribution_legend;
};

/// What was written.
struct BatchRenderResult {
  std::vector<std::string> frame_files;  ///< out_dir/frame_NNNN.png
  std::string contact_sheet;             ///< out_dir/contact_sheet.png or ""
  std::string video;                     ///< out_dir/render.mp4 or ""
  std::string view_file;                 ///< out_dir/view.json: the resolved view (camera fixed)
  std::vector<std::string> notes;        ///< e.g. why the MP4 was skipped
};

/// Reads the scene (dynscope::read_scene) and, when options.trace_path is set, the model trace
/// (levels, neighbour lists and filter weights then come from it: SceneRenderData), renders the
/// chosen frames with `context` (resized to
/// the image size) and writes every output atomically into `out_dir` (created if needed). The
/// camera, when fitted, covers all rendered frames so it stays still. Throws IoError/FormatError
/// for an unreadable or corrupt scene or view (naming the file), ValueError for bad options.
BatchRenderResult render_scene_file(GlContext& context, const BatchRenderOptions& options);

/// Layers a rollout is drawn with when no view file is given: error-coloured prediction, the
/// truth as a translucent ghost, and the ground grid.
ViewLayers default_rollout_layers();

/// Reads the rollout at `options.scene_path` (dynscope::read_rollout) and renders it like
/// render_scene_file: per frame the predicted points coloured by their distance to the truth
/// (the view's colormap; range from the view, or 0 .. max error over the whole rollout when
/// auto_range), the truth as a translucent ghost when the view's ghost or ground_truth layer is
/// on, and a caption with the frame, "observed"/"predicted" and the frame's mean point error (m).
/// Without a view file the layers are default_rollout_layers(). The fitted camera covers truth
/// and prediction over all rendered frames. Throws IoError/FormatError naming the file for an
/// unreadable or corrupt rollout or view, ValueError for bad options.
BatchRenderResult render_rollout_file(GlContext& context, const BatchRenderOptions& options);

/// render_rollout_file when `options.scene_path` is a rollout file (is_rollout_file), else
/// render_scene_file; throws what they throw.
BatchRenderResult render_file(GlContext& context, const BatchRenderOptions& options);

}  // namespace dynscope::render
