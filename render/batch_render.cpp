// The work behind `dynscope render`: scene or rollout file -> PNGs, contact sheet, MP4.
#include "render/batch_render.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <sstream>

#include "engine/core/error.h"
#include "engine/core/log.h"
#include "engine/core/progress.h"
#include "engine/io/rollout_file.h"
#include "engine/io/scene_file.h"
#include "engine/io/temp_file.h"
#include "engine/io/trace_file.h"
#include "render/contact_sheet.h"
#include "render/image.h"
#include "render/png_io.h"
#include "render/renderer.h"
#include "render/scene_adapter.h"

namespace dynscope::render {
namespace {

namespace fs = std::filesystem;

int parse_int(const std::string& text, const std::string& what, const std::string& whole) {
  size_t used = 0;
  int value = 0;
  try {
    value = std::stoi(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size()) {
    throw ValueError(what, "'" + whole + "' is not valid (expected integers)");
  }
  return value;
}

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// Frame number and legend in the top-left corner, on a translucent white box.
void draw_labels(Image& image, const std::vector<std::string>& lines) {
  int width = 0;
  for (const std::string& l : lines) width = std::max(width, text_width(l));
  const int h = static_cast<int>(lines.size()) * 10 + 4;
  for (int y = 2; y < std::min(image.height, 2 + h); ++y) {
    for (int x = 2; x < std::min(image.width, 2 + width + 6); ++x) {
      uint8_t* p = image.pixel(x, y);
      for (int c = 0; c < 3; ++c) p[c] = static_cast<uint8_t>((p[c] + 3 * 255) / 4);
    }
  }
  for (size_t i = 0; i < lines.size(); ++i) {
    draw_text(image, 5, 5 + static_cast<int>(i) * 10, lines[i], {20, 20, 20});
  }
}

// What the shared frame loop needs from a scene or a rollout; built once per input file.
struct FrameSource {
  std::string path;  ///< Input file (for messages).
  int num_frames = 0;
  double dt_s = 0.0;
  std::function<Aabb(int, int)> bounds;  ///< Of everything drawn over frames [first, last].
  std::function<RenderScene(int, const ViewSpec&)> frame;
  std::function<std::vector<std::string>(int)> caption;  ///< Label lines of one frame.
};

// The view file (or the defaults with `default_layers`) with the size options applied.
ViewSpec resolve_view(const BatchRenderOptions& options, const ViewLayers& default_layers) {
  ViewSpec view;
  if (options.view_path.empty()) {
    view.layers = default_layers;
  } else {
    view = load_view_spec(options.view_path);
  }
  if (options.width > 0) view.width = options.width;
  if (options.height > 0) view.height = options.height;
  if (options.level >= 0) {
    view.level = options.level;
    view.layers.level_points = true;
  }
  if (options.picked_point >= 0) {
    view.picked_point = options.picked_point;
    view.layers.neighborhoods = true;
  }
  view.validate();
  return view;
}

void require_out_dir(const BatchRenderOptions& options) {
  if (options.out_dir.empty()) throw ValueError("--out", "an output directory is required");
}

// Renders the chosen frames of `source` into options.out_dir: PNGs, contact sheet, resolved
// view and MP4. Scene and rollout rendering differ only in `source`.
BatchRenderResult render_frames(GlContext& context, const BatchRenderOptions& options,
                                ViewSpec view, const FrameSource& source) {
  const int num_frames = source.num_frames;
  if (num_frames == 0) throw FormatError(source.path, "frames", "the file has no frames");
  const auto [first, last] = options.frames.empty() ? std::pair<int, int>(0, num_frames - 1)
                                                    : parse_frame_range(options.frames, num_frames);

  std::error_code ec;
  fs::create_directories(options.out_dir, ec);
  if (ec || !fs::is_directory(options.out_dir)) {
    throw IoError(options.out_dir, "cannot create output directory: " + ec.message());
  }

  context.make_current();
  context.resize(view.width, view.height);
  Renderer renderer(context, options.samples);
  Camera& camera = view.camera.camera;
  if (view.camera.fit) {
    camera.fit(source.bounds(first, last), static_cast<double>(view.width) / view.height);
  }
  const std::vector<int> sheet_frames = contact_sheet_frames(first, last, 36);
  const int thumb_factor = std::max(1, (view.width + 239) / 240);

  BatchRenderResult result;
  std::vector<std::unique_ptr<TempFile>> pending;
  std::vector<Image> thumbnails;
  std::vector<std::string> captions;
  Progress progress("render", last - first + 1,
                    options.progress ? Progress::Style::kAuto : Progress::Style::kSilent);
  for (int f = first; f <= last; ++f) {
    view.frame = f;
    Image image = renderer.render_image(source.frame(f, view), camera);
    const bool on_sheet =
        options.contact_sheet &&
        std::find(sheet_frames.begin(), sheet_frames.end(), f) != sheet_frames.end();
    // Thumbnails are taken before labelling: the sheet captions them itself.
    if (on_sheet) {
      thumbnails.push_back(downscale(image, thumb_factor));
      captions.push_back(std::to_string(f));
    }
    if (view.labels) draw_labels(image, source.caption(f));
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04d.png", f);
    const std::string path = (fs::path(options.out_dir) / name).string();
    // Every output waits in a temporary file until the last one is written: a failure on the
    // way leaves the files of an earlier run untouched.
    pending.push_back(std::make_unique<TempFile>(path));
    write_png(pending.back()->path(), image);
    result.frame_files.push_back(path);
    progress.advance();
  }
  progress.finish();

  if (options.contact_sheet && !thumbnails.empty()) {
    result.contact_sheet = (fs::path(options.out_dir) / "contact_sheet.png").string();
    pending.push_back(std::make_unique<TempFile>(result.contact_sheet));
    write_png(pending.back()->path(), make_contact_sheet(thumbnails, captions));
  }
  // The resolved view (camera fixed) reopens the same picture in the viewer.
  view.frame = first;
  view.camera.fit = false;
  view.camera.preset.clear();
  result.view_file = (fs::path(options.out_dir) / "view.json").string();
  pending.push_back(std::make_unique<TempFile>(result.view_file));
  save_view_spec(view, pending.back()->path());
  for (const auto& temp : pending) temp->commit();

  if (options.video && last > first) {
    const std::string ffmpeg = find_on_path("ffmpeg");
    if (ffmpeg.empty()) {
      result.notes.push_back("MP4 skipped: ffmpeg is not on PATH");
    } else {
      const std::string video = (fs::path(options.out_dir) / "render.mp4").string();
      TempFile tmp(video);
      const double fps = source.dt_s > 0 ? 1.0 / source.dt_s : 12.0;
      std::ostringstream cmd;
      // Even sizes are required by yuv420p; pad by one pixel when needed.
      cmd << shell_quote(ffmpeg) << " -y -loglevel error -framerate " << fps << " -start_number "
          << first << " -i " << shell_quote((fs::path(options.out_dir) / "frame_%04d.png").string())
          << " -frames:v " << (last - first + 1) << " -vf "
          << shell_quote("pad=ceil(iw/2)*2:ceil(ih/2)*2") << " -pix_fmt yuv420p -f mp4 "
          << shell_quote(tmp.path());
      if (std::system(cmd.str().c_str()) == 0) {
        tmp.commit();
        result.video = video;
      } else {
        result.notes.push_back("MP4 skipped: ffmpeg failed (see its message above)");
      }
    }
  }
  return result;
}

// Rollout layers as drawn: the prediction is always coloured by its error, and a shown truth
// becomes the ghost of the prediction so the two sets stay distinguishable.
ViewLayers effective_rollout_layers(ViewLayers l) {
  if (l.prediction) {
    l.error = true;
    if (l.ground_truth) {
      l.ground_truth = false;
      l.ghost = true;
    }
  }
  l.level_points = l.voxels = l.neighborhoods = l.interaction_points = false;
  return l;
}

std::string frame_caption(int f, int num_frames) {
  return "frame " + std::to_string(f) + "/" + std::to_string(num_frames - 1);
}

}  // namespace

std::pair<int, int> parse_frame_range(const std::string& text, int num_frames) {
  const std::string what = "--frames";
  auto resolve = [&](int v) { return v < 0 ? v + num_frames : v; };
  int first = 0, end = num_frames;
  const size_t colon = text.find(':');
  if (colon == std::string::npos) {
    first = resolve(parse_int(text, what, text));
    end = first + 1;
  } else {
    const std::string a = text.substr(0, colon), b = text.substr(colon + 1);
    if (!a.empty()) first = resolve(parse_int(a, what, text));
    if (!b.empty()) end = resolve(parse_int(b, what, text));
  }
  if (first < 0 || end > num_frames || first >= end) {
    throw ValueError(what, "'" + text + "' selects no frames of a scene with " +
                               std::to_string(num_frames) + " frames (0 .. " +
                               std::to_string(num_frames - 1) + ")");
  }
  return {first, end - 1};
}

std::pair<int, int> parse_image_size(const std::string& text) {
  const size_t x = text.find_first_of("xX");
  if (x == std::string::npos) throw ValueError("--size", "'" + text + "' is not WxH");
  const int w = parse_int(text.substr(0, x), "--size", text);
  const int h = parse_int(text.substr(x + 1), "--size", text);
  check_image_size("--size", w, h);
  return {w, h};
}

std::string find_on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  if (!path) return "";
  std::stringstream dirs(path);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const std::string candidate = dir + "/" + name;
    if (::access(candidate.c_str(), X_OK) == 0 && fs::is_regular_file(candidate)) return candidate;
  }
  return "";
}

BatchRenderResult render_scene_file(GlContext& context, const BatchRenderOptions& given) {
  require_out_dir(given);
  BatchRenderOptions options = given;
  const Scene scene = read_scene(options.scene_path);
  std::shared_ptr<const ModelTrace> trace;
  if (!options.trace_path.empty()) {
    trace = std::make_shared<const ModelTrace>(read_trace(options.trace_path));
    if (options.frames.empty()) options.frames = std::to_string(trace->frame);
  }
  const ViewSpec view = resolve_view(options, ViewLayers{});
  // Without a trace, levels and neighbourhoods are the model's hierarchy at each rendered frame.
  std::shared_ptr<LevelViews> levels;
  if (!trace && view_needs_levels(view)) {
    levels = make_level_views(scene, view);
    const int first =
        options.frames.empty() ? 0 : parse_frame_range(options.frames, scene.num_frames()).first;
    trace = levels->at(first);
  }
  SceneRenderData data(scene, view, trace);
  const std::vector<std::string> legend = data.legend(view);
  FrameSource source;
  source.path = options.scene_path;
  source.num_frames = scene.num_frames();
  source.dt_s = scene.dt_s;
  source.bounds = [&](int first, int last) { return data.bounds(first, last); };
  source.frame = [&](int f, const ViewSpec& v) {
    if (levels) data.set_levels(levels->at(f));
    return data.frame(f, v);
  };
  source.caption = [&](int f) {
    std::vector<std::string> lines = {frame_caption(f, source.num_frames)};
    lines.insert(lines.end(), legend.begin(), legend.end());
    return lines;
  };
  return render_frames(context, options, view, source);
}

ViewLayers default_rollout_layers() {
  ViewLayers l;
  l.grid = true;
  l.meshes = true;
  l.ground_truth = false;
  l.prediction = true;
  l.ghost = true;
  l.error = true;
  return l;
}

BatchRenderResult render_rollout_file(GlContext& context, const BatchRenderOptions& options) {
  require_out_dir(options);
  Rollout rollout = read_rollout(options.scene_path);
  ViewSpec view = resolve_view(options, default_rollout_layers());
  view.layers = effective_rollout_layers(view.layers);
  const ViewLayers& l = view.layers;
  // Meshes come from the scene the rollout started from, when it can be found.
  std::optional<Scene> scene;
  std::string mesh_note;
  if (l.meshes) {
    const std::string scene_path = find_rollout_scene(rollout, options.scene_path);
    if (scene_path.empty()) {
      mesh_note = rollout.scene_path.empty() ? "the rollout names no scene file"
                                             : "scene file " + rollout.scene_path + " not found";
    } else {
      try {
        scene = read_scene(scene_path);
      } catch (const Error& e) {
        mesh_note = e.what();
      }
    }
  }
  const RolloutRenderData data =
      make_rollout_render_data(std::move(rollout), scene ? &*scene : nullptr, view.point_radius);
  const int num_frames = data.num_frames();
  auto bounds = [&](int first, int last) {
    Aabb box;
    for (int f = std::max(0, first); f <= std::min(last, num_frames - 1); ++f) {
      box.extend(data.series.truth->bounds(f));
      box.extend(data.series.prediction->bounds(f));
    }
    return box;
  };
  std::shared_ptr<PointSeries> attribution;
  if (options.attribution) attribution = make_attribution_series(data, *options.attribution);
  std::vector<std::string> legend;
  if (attribution) {
    legend = options.attribution_legend;
  } else if (l.prediction) {
    char text[96];
    const float lo = view.auto_range ? 0.0f : view.range_min;
    const float hi = view.auto_range ? std::max(data.max_error(), 1e-6f) : view.range_max;
    std::snprintf(text, sizeof(text), "prediction: error %.3g .. %.3g (%s)", lo, hi,
                  view.colormap.c_str());
    legend.push_back(text);
  }
  if (l.ghost && l.prediction) legend.push_back("truth: translucent");
  if (l.ground_truth && !l.prediction) legend.push_back("truth");
  if (l.ghost && l.ground_truth && !l.prediction) legend.push_back("prediction: translucent");
  if (l.meshes && data.scene) {
    legend.push_back(l.prediction ? "meshes: predicted poses" : "meshes: true poses");
  }

  FrameSource source;
  source.path = options.scene_path;
  source.num_frames = num_frames;
  source.dt_s = data.rollout.dt_s;
  source.bounds = bounds;
  source.frame = [&](int f, const ViewSpec& v) {
    RenderScene drawn = rollout_frame(data, f, v);
    if (attribution) {
      add_attribution_layers(drawn, attribution, *options.attribution, f, data.point_radius);
    }
    return drawn;
  };
  source.caption = [&](int f) {
    char text[128];
    std::snprintf(text, sizeof(text), "%s %s  mean error %.4g",
                  frame_caption(f, num_frames).c_str(),
                  f < data.rollout.observed_frames ? "observed" : "predicted",
                  data.rollout.point_error[static_cast<size_t>(f)]);
    std::vector<std::string> lines = {text};
    lines.insert(lines.end(), legend.begin(), legend.end());
    return lines;
  };
  BatchRenderResult result = render_frames(context, options, view, source);
  if (l.meshes && !data.scene) {
    result.notes.push_back("meshes skipped: " + (mesh_note.empty()
                                                     ? "the scene has fewer frames than the rollout"
                                                     : mesh_note));
  }
  return result;
}

BatchRenderResult render_file(GlContext& context, const BatchRenderOptions& options) {
  return is_rollout_file(options.scene_path) ? render_rollout_file(context, options)
                                             : render_scene_file(context, options);
}

}  // namespace dynscope::render
