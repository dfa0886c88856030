// render_scene_file: the work behind `dynscope render` (scene -> PNGs, contact sheet, MP4).
#include "render/batch_render.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "engine/core/error.h"
#include "engine/core/log.h"
#include "engine/core/progress.h"
#include "engine/io/scene_file.h"
#include "render/contact_sheet.h"
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
  if (w < 1 || h < 1 || w > 16384 || h > 16384) {
    throw ValueError("--size", "'" + text + "' is outside 1x1 .. 16384x16384");
  }
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

BatchRenderResult render_scene_file(GlContext& context, const BatchRenderOptions& options) {
  if (options.out_dir.empty()) throw ValueError("--out", "an output directory is required");
  const Scene scene = read_scene(options.scene_path);
  ViewSpec view = options.view_path.empty() ? ViewSpec{} : load_view_spec(options.view_path);
  if (options.width > 0) view.width = options.width;
  if (options.height > 0) view.height = options.height;
  view.validate();
  const int num_frames = scene.num_frames();
  if (num_frames == 0) throw FormatError(options.scene_path, "frames", "the scene has no frames");
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
  SceneRenderData data(scene, view);
  Camera& camera = view.camera.camera;
  if (view.camera.fit) {
    camera.fit(data.bounds(first, last), static_cast<double>(view.width) / view.height);
  }
  const std::vector<int> sheet_frames = contact_sheet_frames(first, last, 36);
  const int thumb_factor = std::max(1, (view.width + 239) / 240);

  BatchRenderResult result;
  std::vector<Image> thumbnails;
  std::vector<std::string> captions;
  Progress progress("render", last - first + 1,
                    options.progress ? Progress::Style::kAuto : Progress::Style::kSilent);
  const std::vector<std::string> legend = data.legend(view);
  for (int f = first; f <= last; ++f) {
    view.frame = f;
    Image image = renderer.render_image(data.frame(f, view), camera);
    const bool on_sheet =
        options.contact_sheet &&
        std::find(sheet_frames.begin(), sheet_frames.end(), f) != sheet_frames.end();
    // Thumbnails are taken before labelling: the sheet captions them itself.
    if (on_sheet) {
      thumbnails.push_back(downscale(image, thumb_factor));
      captions.push_back(std::to_string(f));
    }
    if (view.labels) {
      std::vector<std::string> lines = {"frame " + std::to_string(f) + "/" +
                                        std::to_string(num_frames - 1)};
      lines.insert(lines.end(), legend.begin(), legend.end());
      draw_labels(image, lines);
    }
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04d.png", f);
    const std::string path = (fs::path(options.out_dir) / name).string();
    write_png(path, image);
    result.frame_files.push_back(path);
    progress.advance();
  }
  progress.finish();

  if (options.contact_sheet && !thumbnails.empty()) {
    result.contact_sheet = (fs::path(options.out_dir) / "contact_sheet.png").string();
    write_png(result.contact_sheet, make_contact_sheet(thumbnails, captions));
  }
  // The resolved view (camera fixed) reopens the same picture in the viewer.
  view.frame = first;
  view.camera.fit = false;
  view.camera.preset.clear();
  result.view_file = (fs::path(options.out_dir) / "view.json").string();
  save_view_spec(view, result.view_file);

  if (options.video && last > first) {
    const std::string ffmpeg = find_on_path("ffmpeg");
    if (ffmpeg.empty()) {
      result.notes.push_back("MP4 skipped: ffmpeg is not on PATH");
    } else {
      const std::string video = (fs::path(options.out_dir) / "render.mp4").string();
      const std::string tmp = (fs::path(options.out_dir) / ".render.tmp.mp4").string();
      const double fps = scene.dt_s > 0 ? 1.0 / scene.dt_s : 12.0;
      std::ostringstream cmd;
      // Even sizes are required by yuv420p; pad by one pixel when needed.
      cmd << shell_quote(ffmpeg) << " -y -loglevel error -framerate " << fps << " -start_number "
          << first << " -i " << shell_quote((fs::path(options.out_dir) / "frame_%04d.png").string())
          << " -frames:v " << (last - first + 1)
          << " -vf pad=ceil(iw/2)*2:ceil(ih/2)*2 -pix_fmt yuv420p -f mp4 " << shell_quote(tmp);
      if (std::system(cmd.str().c_str()) == 0) {
        fs::rename(tmp, video, ec);
        if (ec) throw IoError(video, "cannot move the encoded video into place: " + ec.message());
        result.video = video;
      } else {
        fs::remove(tmp, ec);
        result.notes.push_back("MP4 skipped: ffmpeg failed (see its message above)");
      }
    }
  }
  return result;
}

}  // namespace dynscope::render
