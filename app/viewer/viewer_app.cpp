// ViewerApp: panels (ImGui), 3D view (Renderer), picking, timeline and file actions.
#include "app/viewer/viewer_app.h"

#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "engine/core/error.h"
#include "engine/io/rollout_file.h"
#include "engine/io/scene_file.h"
#include "engine/io/trace_file.h"
#include "engine/model/model_config.h"
#include "engine/rollout/metrics.h"
#include "render/batch_render.h"
#include "render/png_io.h"

namespace dynscope::app::viewer {
namespace {

constexpr float kPanelWidth = 370.0f;
constexpr float kTimelineHeight = 58.0f;
constexpr float kErrorStripHeight = 64.0f;  // added under the timeline while a rollout is shown
constexpr int kMaxLevel = 3;                // the U-Net's 4 levels (DESIGN §5)
constexpr float kClickSlop = 3.0f;          // pixels a press may move and still count as a click
constexpr int kFirstTraceFrame = 2;         // the model's state reads p(t-2) (DESIGN §5)
const ImVec4 kMutedText(0.65f, 0.65f, 0.65f, 1.0f);

ImVec4 to_imvec(const render::Color& c) { return ImVec4(c.x(), c.y(), c.z(), 1.0f); }

std::string format_vec(const Vec3& v, const char* format = "%.3f") {
  char x[32], y[32], z[32];
  std::snprintf(x, sizeof(x), format, v.x());
  std::snprintf(y, sizeof(y), format, v.y());
  std::snprintf(z, sizeof(z), format, v.z());
  return std::string("(") + x + ", " + y + ", " + z + ")";
}

std::string file_name(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// The scene a rollout started from (render::find_rollout_scene), or none when it is not found;
// a scene that exists but cannot be read throws, naming it.
std::optional<Scene> rollout_scene(const Rollout& rollout, const std::string& rollout_path) {
  const std::string path = find_rollout_scene(rollout, rollout_path);
  if (path.empty()) return std::nullopt;
  return read_scene(path);
}

}  // namespace

ViewerApp::ViewerApp(render::GlContext& context, Platform& platform, ModelServices* services)
    : context_(context),
      platform_(platform),
      services_(services),
      renderer_(context),
      imgui_(context) {
  view_.layers.level_points = true;
  scissor_ = reinterpret_cast<ScissorFn>(context.get_proc_address("glScissor"));
  if (scissor_ == nullptr) {
    throw Error("viewer: GL entry point glScissor is missing (" + context.backend() + ")");
  }
}

ViewerApp::~ViewerApp() = default;

const SceneDocument& ViewerApp::document() const {
  if (!doc_) throw ValueError("scene", "no scene is loaded");
  return *doc_;
}

void ViewerApp::open_scene(const std::string& path) { set_scene(read_scene(path), path); }

void ViewerApp::set_scene(const Scene& scene, const std::string& path) {
  scene.validate();
  auto doc = std::make_unique<SceneDocument>();
  doc->path = path;
  doc->scene = scene;
  render::ViewSpec build = view_;
  build.layers.level_points = true;
  build.picked_point = -1;
  build.frame = 0;
  doc->data = std::make_unique<render::SceneRenderData>(doc->scene, build);
  doc->contact_distance = contact_distances(doc->scene, doc->data->cloud());
  doc_ = std::move(doc);
  data_level_ = view_.level;
  rollout_.reset();
  compare_.reset();
  trace_.reset();
  trace_data_.reset();
  trace_from_file_ = false;
  edit_object_ = -1;
  view_.layers.level_points = true;
  scene_field_ = path;
  view_.frame = 0;
  view_.picked_point = -1;
  timeline_ = Timeline{};
  view_.camera.fit = true;
  fit_camera();
}

void ViewerApp::set_view(const render::ViewSpec& view) {
  view.validate();
  if (num_frames() > 0 && view.frame >= num_frames()) {
    throw ValueError("frame", std::to_string(view.frame) + " is outside the " +
                                  std::to_string(num_frames()) + " frames shown");
  }
  const render::ViewSpec previous = view_;
  view_ = view;
  // Voxel, radius or point size may differ: rebuild the level data from scratch.
  data_level_ = -1;
  try {
    ensure_render_data();
    if (doc_ && view_.picked_point >= doc_->data->level_size()) {
      throw ValueError("picked_point",
                       std::to_string(view_.picked_point) + " is outside the level's points");
    }
  } catch (...) {
    view_ = previous;
    data_level_ = -1;
    ensure_render_data();
    throw;
  }
  if (view_.camera.fit) fit_camera();
  if (view_.picked_point >= 0) show_panel(Panel::kInspector);
  if (view_.level > 0 || view_.layers.voxels) show_panel(Panel::kLevels);
}

void ViewerApp::open_view(const std::string& path) {
  set_view(render::load_view_spec(path));
  view_field_ = path;
}

render::ViewSpec ViewerApp::current_view() const {
  render::ViewSpec v = view_;
  v.width = context_.width();
  v.height = context_.height();
  v.camera.fit = false;
  v.camera.preset.clear();
  return v;
}

void ViewerApp::save_view(const std::string& path) const {
  render::save_view_spec(current_view(), path);
}

int ViewerApp::num_frames() const {
  if (rollout_) return rollout_->num_frames();
  return doc_ ? doc_->scene.num_frames() : 0;
}

void ViewerApp::set_frame(int frame) {
  if (num_frames() == 0) return;
  const int clamped = std::clamp(frame, 0, num_frames() - 1);
  // Level points of a model trace are the hierarchy of one frame; only level-0 points (the
  // model's points) keep their index from frame to frame.
  if (clamped != view_.frame && !checkpoint_.empty() && view_.level > 0) view_.picked_point = -1;
  view_.frame = clamped;
}

void ViewerApp::select_point(int point) {
  if (point >= 0) {
    ensure_render_data();
    const render::SceneRenderData* data = active_data();
    const int n = data ? data->level_size() : 0;
    if (point >= n) {
      throw ValueError("picked_point", std::to_string(point) + " is outside the " +
                                           std::to_string(n) + " points of level " +
                                           std::to_string(view_.level));
    }
    view_.layers.neighborhoods = true;
    show_panel(Panel::kInspector);
  }
  view_.picked_point = std::max(point, -1);
}

void ViewerApp::set_level(int level) {
  if (level < 0 || level > kMaxLevel) {
    throw ValueError("level",
                     std::to_string(level) + " is outside 0.." + std::to_string(kMaxLevel));
  }
  if (level == view_.level) return;
  view_.level = level;
  view_.picked_point = -1;  // indices of another level's points mean nothing here
  ensure_render_data();
}

void ViewerApp::show_panel(Panel panel) { open_requests_[panel] = true; }

void ViewerApp::open_file(const std::string& path) {
  if (is_rollout_file(path)) {
    open_rollout(path);
  } else if (is_trace_file(path)) {
    open_trace(path);
  } else {
    open_scene(path);
  }
}

void ViewerApp::open_rollout(const std::string& path) {
  const Rollout rollout = read_rollout(path);
  try {
    rollout.validate();
  } catch (const Error& e) {
    throw ValueError("rollout", path + ": " + e.what());
  }
  if (rollout.num_frames() == 0) throw FormatError(path, "positions", "the rollout has no frames");
  const std::optional<Scene> scene = rollout_scene(rollout, path);
  if (scene) set_scene(*scene, rollout.scene_path);
  set_rollout(rollout, path, scene ? &*scene : nullptr);
  scene_field_ = path;
}

void ViewerApp::set_rollout(const Rollout& rollout, const std::string& label, const Scene* scene) {
  std::unique_ptr<RolloutDocument> doc = make_rollout_document(rollout, label, scene);
  if (!scene) {
    // No scene to go with it: scene panels and level layers have nothing to read.
    doc_.reset();
    trace_.reset();
    trace_data_.reset();
  }
  rollout_ = std::move(doc);
  compare_.reset();
  // One voxel of mean error: the points have drifted by their own spacing.
  error_threshold_ =
      rollout.sampling_voxel > 0 ? rollout.sampling_voxel : 0.5 * rollout_->max_error();
  const render::ViewLayers defaults = render::default_rollout_layers();
  view_.layers.error = defaults.error;
  view_.layers.level_points = false;
  view_.layers.voxels = false;
  view_.layers.neighborhoods = false;
  view_.layers.ground_truth = false;
  view_.picked_point = -1;
  view_.frame = std::min(view_.frame, rollout_->num_frames() - 1);
  if (rollout_mode_ == RolloutMode::kSideBySide) rollout_mode_ = RolloutMode::kGhost;
  timeline_ = Timeline{};
  fit_camera();
  show_panel(Panel::kRollout);
}

void ViewerApp::set_compared_rollout(const Rollout& other, const std::string& label) {
  if (!rollout_) throw ValueError("compared rollout", "no rollout is shown to compare with");
  if (other.num_frames() < rollout_->num_frames()) {
    throw ValueError("compared rollout", label + " has " + std::to_string(other.num_frames()) +
                                             " frames, the shown rollout " +
                                             std::to_string(rollout_->num_frames()));
  }
  compare_ = make_rollout_document(other, label, rollout_->scene ? &*rollout_->scene : nullptr);
  fit_camera();
}

const RolloutDocument& ViewerApp::rollout() const {
  if (!rollout_) throw ValueError("rollout", "no rollout is shown");
  return *rollout_;
}

void ViewerApp::set_rollout_mode(RolloutMode mode) {
  const bool refit =
      (mode == RolloutMode::kSideBySide) != (rollout_mode_ == RolloutMode::kSideBySide);
  rollout_mode_ = mode;
  if (refit) fit_camera();
}

int ViewerApp::jump_to_error_threshold() {
  if (!rollout_) return -1;
  const int f = first_frame_over(rollout_->rollout.point_error, error_threshold_);
  if (f >= 0) set_frame(f);
  return f;
}

void ViewerApp::set_checkpoint(const std::string& checkpoint) {
  if (!checkpoint.empty() && services_ == nullptr) {
    throw ValueError("checkpoint", "this viewer has no model services to run " + checkpoint);
  }
  checkpoint_ = checkpoint;
  checkpoint_field_ = checkpoint;
  trace_.reset();
  trace_data_.reset();
  trace_from_file_ = false;
  trace_failed_ = TraceRequest{};
  view_.picked_point = -1;
  if (!checkpoint.empty()) view_.layers.level_points = true;
}

void ViewerApp::open_trace(const std::string& path) {
  auto trace = std::make_shared<const ModelTrace>(read_trace(path));
  if (!doc_ || rollout_) {
    if (trace->scene_path.empty() || !std::filesystem::is_regular_file(trace->scene_path)) {
      throw IoError(path, "the trace's scene file '" + trace->scene_path +
                              "' cannot be found; open the scene first");
    }
    open_scene(trace->scene_path);
  }
  if (trace->frame < 0 || trace->frame >= doc_->scene.num_frames()) {
    throw FormatError(path, "frame",
                      std::to_string(trace->frame) + " is not a frame of " + doc_->path);
  }
  checkpoint_.clear();
  const int level = std::min(view_.level, static_cast<int>(trace->levels.size()) - 1);
  view_.level = std::max(level, 0);
  ensure_render_data();
  install_trace(trace, view_.level, -1);
  trace_from_file_ = true;
  view_.frame = trace->frame;
  view_.picked_point = -1;
  view_.layers.level_points = true;
  show_panel(Panel::kLevels);
}

void ViewerApp::install_trace(std::shared_ptr<const ModelTrace> trace, int level, int picked) {
  render::ViewSpec build = view_;
  build.level = level;
  build.layers.level_points = true;
  build.layers.ground_truth = true;  // the "all points" layer stays available
  build.picked_point = -1;
  build.frame = trace->frame;
  trace_data_ = std::make_unique<render::SceneRenderData>(doc_->scene, build, trace);
  trace_ = std::move(trace);
  trace_level_ = level;
  trace_picked_ = picked;
}

const ModelTrace* ViewerApp::shown_trace() const {
  if (!trace_ || !trace_data_ || trace_->frame != view_.frame || trace_level_ != view_.level) {
    return nullptr;
  }
  return trace_.get();
}

const render::SceneRenderData* ViewerApp::active_data() const {
  if (shown_trace()) return trace_data_.get();
  return doc_ ? doc_->data.get() : nullptr;
}

void ViewerApp::start_rollouts(const std::string& compare) {
  if (!services_ || checkpoint_.empty()) {
    throw ValueError("rollout", "a checkpoint is needed (--checkpoint, or Model > Use)");
  }
  if (!doc_) throw ValueError("rollout", "no scene is loaded");
  const int observed = rollout_ ? rollout_->rollout.observed_frames : 3;
  std::vector<RolloutRequest> requests = {{checkpoint_, doc_->scene, doc_->path, observed}};
  if (!compare.empty()) requests.push_back({compare, doc_->scene, doc_->path, observed});
  compare_field_ = compare;
  start_rollout_job(compare.empty() ? "rollout" : "rollouts", std::move(requests), false);
}

void ViewerApp::start_what_if(const ObjectEdit& edit) {
  if (!services_ || checkpoint_.empty()) {
    throw ValueError("what-if", "a checkpoint is needed (--checkpoint, or Model > Use)");
  }
  if (!doc_) throw ValueError("what-if", "no scene is loaded");
  // The original is the shown rollout when it is this checkpoint's on this scene.
  const bool have_original =
      rollout_ && rollout_->rollout.checkpoint_path == checkpoint_ && rollout_->scene && !compare_;
  const int observed = rollout_ ? rollout_->rollout.observed_frames : 3;
  Scene edited = apply_initial_state_edit(doc_->scene, edit, observed - 1);
  std::vector<RolloutRequest> requests;
  if (!have_original) requests.push_back({checkpoint_, doc_->scene, doc_->path, observed});
  requests.push_back({checkpoint_, edited, doc_->path, observed});
  what_if_scene_ = std::move(edited);
  start_rollout_job("what-if", std::move(requests), true);
}

void ViewerApp::start_rollout_job(const std::string& label, std::vector<RolloutRequest> requests,
                                  bool what_if) {
  if (rollout_job_) throw ValueError("rollout", "a " + rollout_job_->label() + " is running");
  int64_t total = 0;
  for (const RolloutRequest& r : requests) {
    total += std::max(0, r.scene.num_frames() - r.observed_frames);
  }
  ModelServices* services = services_;
  rollout_job_what_if_ = what_if;
  rollout_job_ = std::make_unique<BackgroundJob<std::vector<Rollout>>>(
      label, total, [services, requests = std::move(requests)](Progress* progress) {
        std::vector<Rollout> out;
        for (const RolloutRequest& r : requests) out.push_back(services->rollout(r, progress));
        return out;
      });
}

void ViewerApp::update_jobs() {
  if (rollout_job_ && rollout_job_->done()) {
    const std::unique_ptr<BackgroundJob<std::vector<Rollout>>> job = std::move(rollout_job_);
    std::vector<Rollout> results = job->take();
    if (rollout_job_what_if_) {
      const Rollout original = results.size() == 2 ? results[0] : rollout_->rollout;
      const Scene edited = std::move(*what_if_scene_);
      what_if_scene_.reset();
      set_rollout(results.back(), "what-if of " + file_name(checkpoint_), &edited);
      set_compared_rollout(original, "original");
    } else {
      set_rollout(results[0], "rollout of " + file_name(results[0].checkpoint_path), &doc_->scene);
      if (results.size() > 1) {
        set_compared_rollout(results[1], "rollout of " + file_name(results[1].checkpoint_path));
      }
    }
    if (compare_) set_rollout_mode(RolloutMode::kSideBySide);
  }
  if (trace_job_ && trace_job_->done()) {
    const std::unique_ptr<BackgroundJob<ModelTrace>> job = std::move(trace_job_);
    try {
      auto trace = std::make_shared<const ModelTrace>(job->take());
      if (doc_) install_trace(std::move(trace), trace_request_.level, trace_request_.picked);
    } catch (...) {
      trace_failed_ = trace_request_;
      throw;
    }
  }
  if (trace_from_file_ && trace_ && trace_level_ != view_.level &&
      view_.level < static_cast<int>(trace_->levels.size())) {
    install_trace(trace_, view_.level, -1);
  }
  if (checkpoint_.empty() || !services_ || !doc_ || trace_job_ ||
      view_.frame >= doc_->scene.num_frames() || view_.frame < kFirstTraceFrame) {
    return;
  }
  const TraceRequest want{view_.frame, view_.level, view_.picked_point};
  const bool have = trace_ && trace_->frame == want.frame && trace_level_ == want.level &&
                    trace_picked_ == want.picked;
  const bool failed = trace_failed_.frame == want.frame && trace_failed_.level == want.level &&
                      trace_failed_.picked == want.picked;
  if (have || failed) return;
  trace_request_ = want;
  ModelServices* services = services_;
  auto scene = std::make_shared<const Scene>(doc_->scene);
  trace_job_ = std::make_unique<BackgroundJob<ModelTrace>>(
      "trace", 1, [services, scene, path = doc_->path, checkpoint = checkpoint_, want](Progress*) {
        return services->trace(checkpoint, *scene, path, want.frame, want.level, want.picked);
      });
}

render::ViewSpec ViewerApp::rollout_view(bool prediction, bool truth, bool ghost) const {
  render::ViewSpec v = view_;
  v.layers.prediction = prediction;
  v.layers.ground_truth = truth;
  v.layers.ghost = ghost;
  if (v.auto_range) {
    // One range for both rollouts of a comparison, so equal colours mean equal errors.
    float hi = rollout_->max_error();
    if (compare_) hi = std::max(hi, compare_->max_error());
    v.auto_range = false;
    v.range_min = 0.0f;
    v.range_max = std::max(hi, 1e-6f);
  }
  return v;
}

void ViewerApp::add_scene_layers(render::RenderScene& out) const {
  const render::ViewLayers& l = view_.layers;
  if (!doc_ || view_.frame >= doc_->scene.num_frames() ||
      !(l.level_points || l.voxels || l.neighborhoods || l.interaction_points)) {
    return;
  }
  render::ViewSpec v = view_;
  v.layers.grid = v.layers.meshes = v.layers.ground_truth = v.layers.prediction = false;
  render::RenderScene levels = active_data()->frame(view_.frame, v);
  out.points.insert(out.points.end(), levels.points.begin(), levels.points.end());
  out.lines.insert(out.lines.end(), levels.lines.begin(), levels.lines.end());
  out.boxes.insert(out.boxes.end(), levels.boxes.begin(), levels.boxes.end());
}

std::vector<Viewport> ViewerApp::viewports() const {
  std::vector<Viewport> out;
  const int w = context_.width();
  const render::Camera& camera = view_.camera.camera;
  if (!rollout_) {
    if (!doc_) return out;
    render::ViewSpec v = view_;
    // The selection indexes the model trace's level; without it there is nothing to show.
    if (!checkpoint_.empty() && !shown_trace()) v.picked_point = -1;
    out.push_back({active_data()->frame(view_.frame, v), camera, 0, w, ""});
    return out;
  }
  const int f = view_.frame;
  const RolloutDocument& a = *rollout_;
  switch (rollout_mode_) {
    case RolloutMode::kPrediction:
      out.push_back({render::rollout_frame(a, f, rollout_view(true, false, false)), camera, 0, w, ""});
      break;
    case RolloutMode::kTruth:
      out.push_back({render::rollout_frame(a, f, rollout_view(false, true, false)), camera, 0, w, ""});
      break;
    case RolloutMode::kGhost:
      if (compare_) {
        out.push_back({render::rollout_frame(a, f, rollout_view(true, false, false)), camera, 0, w, ""});
        add_prediction_ghost(out.back().scene, *compare_, f);
      } else {
        out.push_back({render::rollout_frame(a, f, rollout_view(true, false, true)), camera, 0, w, ""});
      }
      break;
    case RolloutMode::kSideBySide: {
      const float left = ui_visible_ ? kPanelWidth : 0.0f;
      const double quarter = 0.25 * std::max(1.0f, w - left);
      const int split = static_cast<int>(left + 2.0 * quarter);
      const double h = std::max(1, context_.height());
      // One camera: each viewport sees it shifted to its own centre.
      render::Camera lc = camera, rc = camera;
      lc.pan(quarter / h, 0.0);
      rc.pan(-quarter / h, 0.0);
      if (compare_) {
        out.push_back({render::rollout_frame(*compare_, f, rollout_view(true, false, false)), lc, 0, split,
                       compare_->path});
        out.push_back(
            {render::rollout_frame(a, f, rollout_view(true, false, false)), rc, split, w, a.path});
      } else {
        out.push_back(
            {render::rollout_frame(a, f, rollout_view(false, true, false)), lc, 0, split, "truth"});
        out.push_back(
            {render::rollout_frame(a, f, rollout_view(true, false, false)), rc, split, w, "prediction"});
      }
      break;
    }
  }
  add_scene_layers(out.back().scene);
  return out;
}

int ViewerApp::viewport_at(int x) const {
  if (!rollout_ || rollout_mode_ != RolloutMode::kSideBySide) return 0;
  const float left = ui_visible_ ? kPanelWidth : 0.0f;
  return x < left + 0.5f * (context_.width() - left) ? 0 : 1;
}

void ViewerApp::ensure_render_data() {
  if (!doc_ || (doc_->data && data_level_ == view_.level)) return;
  render::ViewSpec build = view_;
  build.layers.level_points = true;  // points are always prepared so they can be picked
  build.picked_point = -1;
  build.frame = 0;
  doc_->data = std::make_unique<render::SceneRenderData>(doc_->scene, build);
  data_level_ = view_.level;
}

void ViewerApp::fit_camera() {
  if (!doc_ && !rollout_) return;
  render::Camera& camera = view_.camera.camera;
  if (!view_.camera.preset.empty()) camera.set_preset(render::parse_preset(view_.camera.preset));
  const double w = context_.width(), h = context_.height();
  // Fit into the part of the window the panels leave free, then shift the view so the scene is
  // centred there (the 3D view itself spans the whole window, behind the panels).
  const double left = ui_visible_ ? kPanelWidth : 0.0;
  const double bottom = ui_visible_ ? kTimelineHeight + (rollout_ ? kErrorStripHeight : 0.0) : 0.0;
  const bool split = rollout_ && rollout_mode_ == RolloutMode::kSideBySide;
  const double vw = std::max(1.0, (w - left) / (split ? 2.0 : 1.0)), vh = std::max(1.0, h - bottom);
  Aabb bounds;
  if (rollout_) {
    bounds = rollout_->bounds;
    if (compare_) bounds.extend(compare_->bounds);
  } else {
    bounds = doc_->data->bounds(0, doc_->scene.num_frames() - 1);
  }
  camera.fit(bounds, vw / vh);
  if (!bounds.empty()) {
    const double radius = std::max(0.5 * (bounds.max - bounds.min).norm(), 1e-3);
    const double tan_half = std::tan(camera.fov_deg * M_PI / 360.0);
    const double half = std::min(std::atan(tan_half * vh / h), std::atan(tan_half * vw / h));
    camera.distance = 1.1 * radius / std::sin(half);
    camera.pan(-0.5 * left / h, -0.5 * bottom / h);
  }
  view_.camera.fit = false;
  view_.camera.preset.clear();
}

render::RenderScene ViewerApp::pick_scene() const {
  // Only the level's points, so a hit's index is a level point index.
  render::ViewSpec v = view_;
  v.layers = render::ViewLayers{};
  v.layers.grid = false;
  v.layers.meshes = false;
  v.layers.prediction = false;
  v.layers.level_points = true;
  v.picked_point = -1;
  return active_data()->frame(view_.frame, v);
}

bool ViewerApp::pick(int x, int y) {
  if (!doc_ || view_.frame >= doc_->scene.num_frames()) return false;
  ensure_render_data();
  // With a checkpoint, points are picked from the model's own levels once its trace is there.
  if (!checkpoint_.empty() && !shown_trace()) return false;
  const std::vector<Viewport> ports = viewports();
  const render::Camera& camera = ports[static_cast<size_t>(viewport_at(x))].camera;
  const render::PickResult hit = renderer_.pick(pick_scene(), camera, x, y);
  if (!hit.hit()) return false;
  select_point(hit.point);
  return true;
}

void ViewerApp::report(const std::exception& e) {
  error_ = e.what();
  error_pending_ = true;
}

void ViewerApp::handle_input() {
  const ImGuiIO& io = ImGui::GetIO();
  if (!io.WantCaptureMouse) {
    render::Camera& camera = view_.camera.camera;
    const float h = std::max(1.0f, io.DisplaySize.y);
    if (ImGui::IsMouseClicked(ImGuiMouseButton_Left)) {
      dragging_ = true;
      drag_distance_ = 0.0f;
    }
    if (dragging_) drag_distance_ += std::fabs(io.MouseDelta.x) + std::fabs(io.MouseDelta.y);
    if (ImGui::IsMouseDown(ImGuiMouseButton_Left) && drag_distance_ > kClickSlop) {
      camera.orbit(-0.3 * io.MouseDelta.x, 0.3 * io.MouseDelta.y);
    }
    if (ImGui::IsMouseDown(ImGuiMouseButton_Right) || ImGui::IsMouseDown(ImGuiMouseButton_Middle)) {
      camera.pan(-io.MouseDelta.x / h, io.MouseDelta.y / h);
    }
    if (io.MouseWheel != 0.0f) camera.zoom(std::pow(0.9, io.MouseWheel));
    if (ImGui::IsMouseReleased(ImGuiMouseButton_Left) && dragging_) {
      dragging_ = false;
      if (drag_distance_ <= kClickSlop) {
        pick(static_cast<int>(io.MousePos.x), static_cast<int>(io.MousePos.y));
      }
    }
  } else if (!ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
    dragging_ = false;
  }
  if (num_frames() == 0 || io.WantTextInput) return;
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Space), false)) {
    timeline_.playing = !timeline_.playing;
  }
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_RightArrow))) set_frame(view_.frame + 1);
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_LeftArrow))) set_frame(view_.frame - 1);
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Home), false)) set_frame(0);
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_End), false)) set_frame(num_frames() - 1);
}

void ViewerApp::advance_playback(float dt_s) {
  if (num_frames() == 0 || !timeline_.playing) return;
  const int last = num_frames() - 1;
  const double frame_s = rollout_ ? rollout_->rollout.dt_s : doc_->scene.dt_s;
  timeline_.accumulated_s += dt_s * timeline_.speed;
  while (timeline_.accumulated_s >= frame_s) {
    timeline_.accumulated_s -= frame_s;
    if (view_.frame < last) {
      ++view_.frame;
    } else if (timeline_.loop) {
      view_.frame = 0;
    } else {
      timeline_.playing = false;
      timeline_.accumulated_s = 0.0;
      break;
    }
  }
}

void ViewerApp::frame() {
  context_.make_current();
  platform_.new_frame();
  ImGui::NewFrame();
  if (!open_request_.empty()) {
    const std::string path = std::move(open_request_);
    open_request_.clear();
    try {
      open_file(path);
    } catch (const std::exception& e) {
      report(e);
    }
  }
  try {
    update_jobs();
    handle_input();
    advance_playback(ImGui::GetIO().DeltaTime);
    ensure_render_data();
  } catch (const std::exception& e) {
    report(e);
  }
  if (ui_visible_) draw_panels();
  std::vector<Viewport> ports;
  try {
    ports = viewports();
  } catch (const std::exception& e) {
    // A view that cannot be drawn (e.g. a stale picked point) falls back to no selection.
    view_.picked_point = -1;
    report(e);
  }
  if (ui_visible_) draw_viewport_captions(ports);
  ImGui::Render();

  try {
    if (ports.size() == 1) {
      renderer_.render(ports[0].scene, ports[0].camera);
    } else if (!ports.empty()) {
      // Side by side: each viewport clears and draws only its columns (the scissor also limits
      // the renderer's multisample resolve), with the window's projection and a shifted camera.
      const render::GlFunctions& gl = renderer_.gl();
      gl.Enable(GL_SCISSOR_TEST);
      for (const Viewport& p : ports) {
        scissor_(p.x0, 0, p.x1 - p.x0, context_.height());
        renderer_.render(p.scene, p.camera);
      }
      gl.Disable(GL_SCISSOR_TEST);
    } else {
      const render::GlFunctions& gl = renderer_.gl();
      gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
      gl.Viewport(0, 0, context_.width(), context_.height());
      gl.ClearColor(view_.background.x(), view_.background.y(), view_.background.z(), 1.0f);
      gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    }
  } catch (const std::exception& e) {
    // A view that cannot be drawn (e.g. a stale picked point) falls back to no selection.
    view_.picked_point = -1;
    report(e);
  }
  if (ui_visible_) imgui_.render(ImGui::GetDrawData());
  if (!screenshot_path_.empty()) {
    try {
      render::write_png(screenshot_path_, context_.read_pixels());
    } catch (const std::exception& e) {
      report(e);
    }
    screenshot_path_.clear();
  }
  context_.swap_buffers();
}

render::Image ViewerApp::read_pixels() {
  context_.make_current();
  return context_.read_pixels();
}

bool ViewerApp::section(const char* label, Panel panel, bool default_open) {
  auto request = open_requests_.find(panel);
  if (request != open_requests_.end()) {
    ImGui::SetNextItemOpen(request->second, ImGuiCond_Always);
    open_requests_.erase(request);
  } else {
    ImGui::SetNextItemOpen(default_open, ImGuiCond_Once);
  }
  return ImGui::CollapsingHeader(label);
}

void ViewerApp::draw_panels() {
  const ImGuiIO& io = ImGui::GetIO();
  const ImGuiWindowFlags fixed =
      ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse;
  ImGui::SetNextWindowPos(ImVec2(0, 0), ImGuiCond_Always);
  const std::string shown = rollout_ ? rollout_->path : doc_ ? doc_->path : "";
  const std::string title =
      (shown.empty() ? std::string("dynscope") : "dynscope - " + file_name(shown)) + "###panel";
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, io.DisplaySize.y - timeline_height()),
                           ImGuiCond_Always);
  if (ImGui::Begin(title.c_str(), nullptr, fixed)) {
    try {
      if (section("Files", Panel::kFiles, !doc_ && !rollout_)) draw_files_section();
      if (section("Display", Panel::kDisplay, false)) draw_display_section();
      if (rollout_ && section("Rollout", Panel::kRollout, true)) draw_rollout_section();
      if (services_ && section("Model", Panel::kModel, !checkpoint_.empty())) draw_model_section();
      if (doc_) {
        if (section("Objects", Panel::kObjects, true)) draw_objects_section();
        if (section("Contact timeline", Panel::kContacts, false)) draw_contacts_section();
        if (section("U-Net levels", Panel::kLevels, false)) draw_levels_section();
        if (section("Selection & neighbourhood", Panel::kInspector, false)) {
          draw_inspector_section();
        }
      } else if (!rollout_) {
        ImGui::TextWrapped(
            "No scene loaded: enter a scene, rollout or trace file (.h5) under Files and press "
            "Open.");
      }
    } catch (const std::exception& e) {
      report(e);
    }
  }
  ImGui::End();
  draw_timeline();
  draw_error_popup();
}

void ViewerApp::draw_files_section() {
  ImGui::PushItemWidth(-90.0f);
  ImGui::InputText("##scene", &scene_field_);
  ImGui::SameLine();
  if (ImGui::Button("Open", ImVec2(-1, 0))) request_open(scene_field_);
  ImGui::TextColored(kMutedText, "scene, rollout or trace file (.h5)");
  ImGui::InputText("##view", &view_field_);
  ImGui::SameLine();
  if (ImGui::Button("Save view", ImVec2(-1, 0))) {
    try {
      save_view(view_field_);
    } catch (const std::exception& e) {
      report(e);
    }
  }
  ImGui::Dummy(ImVec2(0, 0));
  ImGui::SameLine(ImGui::GetContentRegionAvail().x - 82.0f);
  if (ImGui::Button("Open view", ImVec2(-1, 0))) {
    try {
      open_view(view_field_);
    } catch (const std::exception& e) {
      report(e);
    }
  }
  ImGui::InputText("##png", &screenshot_field_);
  ImGui::SameLine();
  if (ImGui::Button("Screenshot", ImVec2(-1, 0))) request_screenshot(screenshot_field_);
  ImGui::PopItemWidth();
}

void ViewerApp::draw_display_section() {
  render::ViewLayers& l = view_.layers;
  ImGui::Checkbox("meshes", &l.meshes);
  ImGui::SameLine(120);
  ImGui::Checkbox("grid", &l.grid);
  ImGui::SameLine(220);
  ImGui::Checkbox("all points", &l.ground_truth);
  ImGui::Checkbox("level points", &l.level_points);
  ImGui::SameLine(120);
  ImGui::Checkbox("voxels", &l.voxels);
  ImGui::SameLine(220);
  ImGui::Checkbox("neighbours", &l.neighborhoods);
  ImGui::Checkbox("interaction points", &l.interaction_points);
  ImGui::TextUnformatted("camera");
  for (render::ViewPreset p : {render::ViewPreset::kFront, render::ViewPreset::kSide,
                               render::ViewPreset::kTop, render::ViewPreset::kIso}) {
    ImGui::SameLine();
    if (ImGui::SmallButton(render::preset_name(p))) {
      view_.camera.preset = render::preset_name(p);
      fit_camera();
    }
  }
  ImGui::SameLine();
  if (ImGui::SmallButton("fit")) fit_camera();
  ImGui::TextColored(kMutedText, "drag: orbit, right drag: pan, wheel: zoom, click: pick");
}

void ViewerApp::draw_objects_section() {
  const Scene& scene = doc_->scene;
  const ScenePointCloud& cloud = doc_->data->cloud();
  const ImGuiTableFlags flags =
      ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit;
  ImGui::Text("%s, %zu objects, %d frames, dt %.4g s", scene.scenario.c_str(), scene.objects.size(),
              scene.num_frames(), scene.dt_s);
  if (!ImGui::BeginTable("objects", 7, flags)) return;
  for (const char* h : {"id", "name", "role", "mass", "fric", "rest", "pts"}) {
    ImGui::TableSetupColumn(h);
  }
  ImGui::TableHeadersRow();
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Object& o = scene.objects[i];
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    ImGui::ColorButton("##c", to_imvec(render::categorical_color(o.id)),
                       ImGuiColorEditFlags_NoTooltip, ImVec2(10, 10));
    ImGui::SameLine();
    ImGui::Text("%d", o.id);
    ImGui::TableNextColumn();
    ImGui::TextUnformatted(o.name.c_str());
    ImGui::TableNextColumn();
    ImGui::TextUnformatted(role_name(o.role));
    ImGui::TableNextColumn();
    ImGui::Text(o.mass == 0.0 ? "static" : "%.3g", o.mass);
    ImGui::TableNextColumn();
    ImGui::Text("%.2f", o.friction);
    ImGui::TableNextColumn();
    ImGui::Text("%.2f", o.restitution);
    ImGui::TableNextColumn();
    ImGui::Text("%lld", static_cast<long long>(cloud.count_of(static_cast<int>(i))));
  }
  ImGui::EndTable();
  if (services_ && !checkpoint_.empty()) draw_what_if();
}

void ViewerApp::draw_what_if() {
  const Scene& scene = doc_->scene;
  const int observed = rollout_ ? rollout_->rollout.observed_frames : 3;
  ImGui::Separator();
  ImGui::TextUnformatted("What-if");
  ImGui::TextColored(kMutedText, "initial state at frame %d (last observed)", observed - 1);
  const std::string current =
      edit_object_ >= 0 ? scene.objects[static_cast<size_t>(edit_object_)].name : "(object)";
  ImGui::SetNextItemWidth(160);
  if (ImGui::BeginCombo("object", current.c_str())) {
    for (size_t i = 0; i < scene.objects.size(); ++i) {
      if (ImGui::Selectable(scene.objects[i].name.c_str(), edit_object_ == static_cast<int>(i))) {
        edit_object_ = static_cast<int>(i);
        edit_ = object_initial_state(scene, edit_object_, observed - 1);
      }
    }
    ImGui::EndCombo();
  }
  if (edit_object_ < 0) return;
  ImGui::SameLine();
  if (ImGui::SmallButton("reset")) edit_ = object_initial_state(scene, edit_object_, observed - 1);
  ImGui::InputScalarN("position", ImGuiDataType_Double, edit_.position.data(), 3, nullptr, nullptr,
                      "%.3f");
  ImGui::InputScalarN("euler deg", ImGuiDataType_Double, edit_.euler_deg.data(), 3, nullptr,
                      nullptr, "%.1f");
  ImGui::InputScalarN("velocity", ImGuiDataType_Double, edit_.velocity.data(), 3, nullptr, nullptr,
                      "%.3f");
  ImGui::BeginDisabled(rollout_job_ != nullptr);
  if (ImGui::Button("Re-run rollout")) start_what_if(edit_);
  ImGui::EndDisabled();
  if (rollout_job_) {
    ImGui::SameLine();
    ImGui::ProgressBar(rollout_job_->fraction(), ImVec2(-1, 0));
  }
  ImGui::TextColored(kMutedText, "earlier frames move rigidly with the edit");
}

void ViewerApp::draw_contacts_section() {
  const Scene& scene = doc_->scene;
  const std::vector<double>& d = doc_->contact_distance;
  if (rollout_ && rollout_->rollout.has_contact()) {
    draw_rollout_contacts();
  } else if (d.empty()) {
    ImGui::TextWrapped("This scene has no target and zone object (no contact timeline).");
  } else {
    std::vector<float> values(d.begin(), d.end());
    const float top = std::max(1e-3f, *std::max_element(values.begin(), values.end()));
    char overlay[64];
    const int f = std::min(view_.frame, static_cast<int>(d.size()) - 1);
    std::snprintf(overlay, sizeof(overlay), "frame %d: %.3f", f, d[f]);
    ImGui::PlotLines("##dist", values.data(), static_cast<int>(values.size()), 0, overlay, 0.0f,
                     top, ImVec2(-1, 60));
    ImGui::TextColored(kMutedText, "target-zone minimum point distance over time");
  }
  for (const auto& [name, values] : scene.labels) {
    const auto first = std::find_if(values.begin(), values.end(), [](double v) { return v > 0.5; });
    ImGui::Text(
        "%s: %s", name.c_str(),
        view_.frame < static_cast<int>(values.size()) && values[view_.frame] > 0.5 ? "yes" : "no");
    ImGui::SameLine();
    if (first == values.end()) {
      ImGui::TextColored(kMutedText, "(never)");
    } else {
      ImGui::TextColored(kMutedText, "(first at frame %d)",
                         static_cast<int>(first - values.begin()));
    }
  }
}

void ViewerApp::draw_levels_section() {
  const render::SceneRenderData& data = *active_data();
  int level = view_.level;
  ImGui::SetNextItemWidth(150);
  if (ImGui::SliderInt("level", &level, 0, kMaxLevel)) set_level(level);
  ImGui::SameLine();
  ImGui::Checkbox("points", &view_.layers.level_points);
  ImGui::SameLine();
  ImGui::Checkbox("voxels", &view_.layers.voxels);
  ImGui::Text("shown: %d points, voxel %.3g, radius %.3g", data.level_size(), data.level_voxel(),
              data.level_radius());
  if (view_.frame >= doc_->scene.num_frames()) return;
  std::vector<LevelCount> counts;
  if (const ModelTrace* trace = shown_trace()) {
    counts = trace_level_counts(*trace);
    ImGui::TextColored(kMutedText, "the model's own hierarchy (trace) at frame %d", trace->frame);
  } else {
    auto cached = doc_->level_counts.find(view_.frame);
    if (cached == doc_->level_counts.end()) {
      cached =
          doc_->level_counts
              .emplace(view_.frame, level_counts(doc_->scene, doc_->data->cloud(), view_.frame))
              .first;
    }
    counts = cached->second;
    ImGui::TextColored(kMutedText, "model hierarchy (%s preset) at frame %d",
                       hierarchy_preset(doc_->scene).c_str(), view_.frame);
    if (!checkpoint_.empty() && view_.frame >= kFirstTraceFrame) {
      ImGui::TextColored(kMutedText, "capturing the model's trace...");
    }
  }
  const Scene& scene = doc_->scene;
  const int columns = 3 + static_cast<int>(scene.objects.size());
  const ImGuiTableFlags flags =
      ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit;
  if (!ImGui::BeginTable("levels", columns, flags)) return;
  ImGui::TableSetupColumn("lvl");
  ImGui::TableSetupColumn("voxel");
  ImGui::TableSetupColumn("points");
  for (const Object& o : scene.objects)
    ImGui::TableSetupColumn(("obj " + std::to_string(o.id)).c_str());
  ImGui::TableHeadersRow();
  for (const LevelCount& c : counts) {
    ImGui::TableNextRow();
    if (c.level == view_.level) {
      ImGui::TableSetBgColor(ImGuiTableBgTarget_RowBg1, IM_COL32(60, 90, 140, 160));
    }
    ImGui::TableNextColumn();
    ImGui::Text("%d", c.level);
    ImGui::TableNextColumn();
    if (c.level == 0) {
      ImGui::TextUnformatted("-");
    } else {
      ImGui::Text("%.3g", c.voxel);
    }
    ImGui::TableNextColumn();
    ImGui::Text("%d", c.points);
    for (const Object& o : scene.objects) {
      ImGui::TableNextColumn();
      const auto it = c.per_object.find(o.id);
      ImGui::Text("%d", it == c.per_object.end() ? 0 : it->second);
    }
  }
  ImGui::EndTable();
}

void ViewerApp::draw_inspector_section() {
  const ModelTrace* trace = shown_trace();
  if (!checkpoint_.empty() && !trace) {
    if (view_.frame < kFirstTraceFrame) {
      ImGui::TextWrapped("The model reads frames t-2..t: its trace starts at frame %d.",
                         kFirstTraceFrame);
    } else {
      ImGui::TextWrapped("Capturing the model's trace at frame %d...", view_.frame);
    }
    return;
  }
  if (view_.picked_point < 0) {
    ImGui::TextWrapped("Click a point in the 3D view to inspect it and its neighbourhood.");
    return;
  }
  if (view_.frame >= doc_->scene.num_frames()) return;
  const render::SceneRenderData& data = *active_data();
  const PointInfo info =
      trace ? inspect_trace_point(*trace, doc_->scene, view_.level, view_.picked_point)
            : inspect_point(data, view_.picked_point, view_.frame);
  ImGui::Text("point %d of level %d (%s point %d)", info.level_point, view_.level,
              trace ? "model" : "cloud", info.cloud_point);
  ImGui::SameLine();
  if (ImGui::SmallButton("clear")) {
    view_.picked_point = -1;
    return;
  }
  ImGui::Text("object   %d %s", info.object_id, info.object_name.c_str());
  ImGui::Text("position %s", format_vec(info.position).c_str());
  if (!trace) {
    ImGui::Text("velocity %s  |v| %.3f", format_vec(info.velocity).c_str(), info.velocity.norm());
  }
  if (trace) draw_trace_features(*trace);
  ImGui::Checkbox("show edges", &view_.layers.neighborhoods);
  if (!trace) {
    ImGui::SameLine();
    ImGui::SetNextItemWidth(110);
    ImGui::SliderInt("k", &view_.neighbors, 1, 32);
  }
  const Neighborhood n = point_neighborhood(data, view_.picked_point, view_.frame, view_.neighbors);
  const bool weighted = trace_picked_ == view_.picked_point;
  auto table = [&](const char* id, const std::vector<NeighborEntry>& list, const ImVec4& color) {
    const ImGuiTableFlags flags = ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg |
                                  ImGuiTableFlags_ScrollY | ImGuiTableFlags_SizingStretchSame;
    const float rows = static_cast<float>(std::min<size_t>(list.size(), 5) + 1);
    const int columns = trace ? 4 : 3;
    if (list.empty() || !ImGui::BeginTable(id, columns, flags, ImVec2(0, rows * 19.0f + 4.0f))) {
      return;
    }
    ImGui::TableSetupScrollFreeze(0, 1);
    ImGui::TableSetupColumn("point");
    ImGui::TableSetupColumn("object");
    ImGui::TableSetupColumn("distance");
    if (trace) ImGui::TableSetupColumn("|h|");
    ImGui::TableHeadersRow();
    for (const NeighborEntry& e : list) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextColored(color, "%d", e.point);
      ImGui::TableNextColumn();
      ImGui::Text("%d", e.object_id);
      ImGui::TableNextColumn();
      ImGui::Text("%.4f", e.distance);
      if (trace) {
        ImGui::TableNextColumn();
        if (e.weight >= 0.0) {
          ImGui::Text("%.4f", e.weight);
        } else {
          ImGui::TextColored(kMutedText, "-");
        }
      }
    }
    ImGui::EndTable();
    // The learned filter h(p_k - p_0) as bars, one per neighbour in list order.
    std::vector<float> bars;
    for (const NeighborEntry& e : list) {
      if (e.weight >= 0.0) bars.push_back(static_cast<float>(e.weight));
    }
    if (!bars.empty()) {
      ImGui::PushStyleColor(ImGuiCol_PlotHistogram, color);
      ImGui::PlotHistogram((std::string("##h") + id).c_str(), bars.data(),
                           static_cast<int>(bars.size()), 0, "|h(p_k - p_0)|", 0.0f, FLT_MAX,
                           ImVec2(-1, 40));
      ImGui::PopStyleColor();
    }
  };
  const ImVec4 blue(0.35f, 0.6f, 1.0f, 1.0f), orange(1.0f, 0.6f, 0.15f, 1.0f);
  ImGui::TextColored(blue, "object kNN: %zu of k=%d (same object)", n.object.size(), n.k);
  if (!n.object_conv.empty()) ImGui::TextColored(kMutedText, "h of %s", n.object_conv.c_str());
  table("knn", n.object, blue);
  ImGui::TextColored(orange, "relational: %zu within r=%.3g (other objects)", n.relational.size(),
                     n.radius);
  if (!n.relational_conv.empty()) {
    ImGui::TextColored(kMutedText, "h of %s", n.relational_conv.c_str());
  }
  table("rel", n.relational, orange);
  if (trace && !weighted) ImGui::TextColored(kMutedText, "capturing filter weights...");
  if (trace && trace->has_mesh) draw_trace_mesh(*trace);
}

void ViewerApp::draw_trace_features(const ModelTrace& trace) {
  std::vector<float> norms;
  std::string names;
  for (const TraceFeatures& f : trace.features) {
    if (f.level != view_.level || view_.picked_point >= static_cast<int>(f.norms.size())) continue;
    norms.push_back(static_cast<float>(f.norms[static_cast<size_t>(view_.picked_point)]));
    names += (names.empty() ? "" : ", ") + f.block;
  }
  if (norms.empty()) return;
  ImGui::TextColored(kMutedText, "feature norms after: %s", names.c_str());
  ImGui::PlotHistogram("##features", norms.data(), static_cast<int>(norms.size()), 0,
                       "|feature| per block", 0.0f, FLT_MAX, ImVec2(-1, 40));
}

void ViewerApp::draw_trace_mesh(const ModelTrace& trace) {
  int pairs = 0;
  for (const TraceList& l : trace.mesh.lists) {
    if (l.name == "senders") pairs = static_cast<int>(l.mask.count());
  }
  double threshold = 0.0;
  try {
    threshold = ModelConfig::from_json(trace.model_config, "trace").interaction_threshold;
  } catch (const Error&) {
    threshold = 0.0;  // an unreadable config only hides the number
  }
  ImGui::Text("mesh input: %lld interaction points, %d sender pairs",
              static_cast<long long>(trace.mesh.points.rows()), pairs);
  ImGui::Text("interaction threshold %.4g", threshold);
  ImGui::SameLine();
  ImGui::Checkbox("show", &view_.layers.interaction_points);
}

void ViewerApp::draw_timeline() {
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(0, io.DisplaySize.y - timeline_height()), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(io.DisplaySize.x, timeline_height()), ImGuiCond_Always);
  const ImGuiWindowFlags flags = ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize |
                                 ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoTitleBar |
                                 ImGuiWindowFlags_NoScrollbar;
  if (ImGui::Begin("Timeline", nullptr, flags)) {
    if (num_frames() == 0) {
      ImGui::TextColored(kMutedText, "timeline: no scene");
    } else {
      const int last = num_frames() - 1;
      const double dt_s = rollout_ ? rollout_->rollout.dt_s : doc_->scene.dt_s;
      if (ImGui::Button("|<")) set_frame(0);
      ImGui::SameLine();
      if (ImGui::Button("<")) set_frame(view_.frame - 1);
      ImGui::SameLine();
      if (ImGui::Button(timeline_.playing ? "pause" : "play", ImVec2(48, 0))) {
        timeline_.playing = !timeline_.playing;
      }
      ImGui::SameLine();
      if (ImGui::Button(">")) set_frame(view_.frame + 1);
      ImGui::SameLine();
      if (ImGui::Button(">|")) set_frame(last);
      ImGui::SameLine();
      int frame = view_.frame;
      ImGui::SetNextItemWidth(std::max(100.0f, ImGui::GetContentRegionAvail().x - 330.0f));
      if (ImGui::SliderInt("##frame", &frame, 0, last, "frame %d")) set_frame(frame);
      ImGui::SameLine();
      ImGui::Text("t %.3f s", view_.frame * dt_s);
      ImGui::SameLine();
      ImGui::SetNextItemWidth(90);
      ImGui::SliderFloat("speed", &timeline_.speed, 0.1f, 4.0f, "%.1fx");
      ImGui::SameLine();
      ImGui::Checkbox("loop", &timeline_.loop);
      if (rollout_) draw_error_strip();
    }
    ImGui::TextColored(kMutedText, "space: play/pause   left/right: step   home/end: first/last");
  }
  ImGui::End();
}

void ViewerApp::draw_error_popup() {
  if (error_pending_) {
    ImGui::OpenPopup("Error");
    error_pending_ = false;
  }
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x * 0.5f, io.DisplaySize.y * 0.5f),
                          ImGuiCond_Always, ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowSize(ImVec2(std::min(520.0f, io.DisplaySize.x - 20.0f), 0));
  if (ImGui::BeginPopupModal("Error", nullptr, ImGuiWindowFlags_NoMove)) {
    ImGui::TextWrapped("%s", error_.c_str());
    if (ImGui::Button("OK", ImVec2(80, 0))) ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
  }
}

float ViewerApp::timeline_height() const {
  return kTimelineHeight + (rollout_ ? kErrorStripHeight : 0.0f);
}

void ViewerApp::draw_rollout_section() {
  const Rollout& r = rollout_->rollout;
  ImGui::TextWrapped("%s", rollout_->path.c_str());
  ImGui::TextColored(kMutedText, "%d frames (%d observed), %lld points, voxel %.3g", r.num_frames(),
                     r.observed_frames, static_cast<long long>(r.num_points()), r.sampling_voxel);
  if (!r.checkpoint_path.empty()) {
    ImGui::TextColored(kMutedText, "checkpoint %s", file_name(r.checkpoint_path).c_str());
  }
  if (!rollout_->scene) ImGui::TextColored(kMutedText, "scene file not found: no meshes");
  const char* other = compare_ ? "compared" : "truth";
  int mode = static_cast<int>(rollout_mode_);
  ImGui::RadioButton("prediction", &mode, static_cast<int>(RolloutMode::kPrediction));
  ImGui::SameLine();
  ImGui::RadioButton("truth", &mode, static_cast<int>(RolloutMode::kTruth));
  ImGui::SameLine();
  ImGui::RadioButton(compare_ ? "ghost (compared)" : "ghost", &mode,
                     static_cast<int>(RolloutMode::kGhost));
  ImGui::RadioButton(
      compare_ ? "side by side (compared | shown)" : "side by side (truth | prediction)", &mode,
      static_cast<int>(RolloutMode::kSideBySide));
  if (mode != static_cast<int>(rollout_mode_)) set_rollout_mode(static_cast<RolloutMode>(mode));
  if (compare_) {
    ImGui::TextColored(kMutedText, "compared: %s (%s set)", compare_->path.c_str(), other);
  }
  ImGui::Checkbox("error colours", &view_.layers.error);
  ImGui::SameLine();
  ImGui::Checkbox("auto range", &view_.auto_range);
  const render::ViewSpec v = rollout_view(true, false, false);
  if (!view_.auto_range) {
    ImGui::SetNextItemWidth(200);
    ImGui::DragFloatRange2("range", &view_.range_min, &view_.range_max, 0.001f, 0.0f, 1e3f, "%.4f",
                           "%.4f");
    view_.range_max = std::max(view_.range_max, view_.range_min + 1e-6f);
  }
  if (view_.layers.error) draw_colorbar(v.range_min, v.range_max);
  const int f = view_.frame;
  ImGui::Text("frame %d (%s): mean error %.4g", f, f < r.observed_frames ? "observed" : "predicted",
              r.point_error[static_cast<size_t>(f)]);
  if (compare_) {
    ImGui::Text("compared: mean error %.4g", compare_->rollout.point_error[static_cast<size_t>(f)]);
  }
}

void ViewerApp::draw_colorbar(float lo, float hi) {
  const ImVec2 size(ImGui::GetContentRegionAvail().x, 12.0f);
  const ImVec2 p = ImGui::GetCursorScreenPos();
  ImDrawList* draw = ImGui::GetWindowDrawList();
  constexpr int kSteps = 32;
  for (int i = 0; i < kSteps; ++i) {
    const render::Color a = render::colormap(view_.colormap, static_cast<float>(i) / kSteps);
    const render::Color b = render::colormap(view_.colormap, static_cast<float>(i + 1) / kSteps);
    const float x0 = p.x + size.x * i / kSteps, x1 = p.x + size.x * (i + 1) / kSteps;
    draw->AddRectFilledMultiColor(ImVec2(x0, p.y), ImVec2(x1, p.y + size.y),
                                  ImGui::GetColorU32(to_imvec(a)), ImGui::GetColorU32(to_imvec(b)),
                                  ImGui::GetColorU32(to_imvec(b)), ImGui::GetColorU32(to_imvec(a)));
  }
  ImGui::Dummy(size);
  ImGui::Text("%.4g", lo);
  char text[32];
  std::snprintf(text, sizeof(text), "%.4g", hi);
  ImGui::SameLine(ImGui::GetContentRegionAvail().x - ImGui::CalcTextSize(text).x);
  ImGui::TextUnformatted(text);
  ImGui::SameLine(0.35f * ImGui::GetContentRegionAvail().x);
  ImGui::TextColored(kMutedText, "|pred - truth| (%s)", view_.colormap.c_str());
}

void ViewerApp::draw_error_strip() {
  const std::vector<double>& e = rollout_->rollout.point_error;
  std::vector<float> values(e.begin(), e.end());
  float top = 1e-6f;
  for (float x : values) top = std::max(top, x);
  top = std::max(top, static_cast<float>(error_threshold_) * 1.1f);
  char overlay[96];
  std::snprintf(overlay, sizeof(overlay), "mean point error, frame %d: %.4g", view_.frame,
                e[static_cast<size_t>(view_.frame)]);
  const float width = std::max(100.0f, ImGui::GetContentRegionAvail().x - 330.0f);
  ImGui::PlotHistogram("##error", values.data(), static_cast<int>(values.size()), 0, overlay, 0.0f,
                       top, ImVec2(width, 40.0f));
  const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  if (ImGui::IsItemHovered() && ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
    const float t = (ImGui::GetIO().MousePos.x - a.x) / std::max(1.0f, b.x - a.x);
    set_frame(static_cast<int>(t * static_cast<float>(values.size())));
  }
  ImDrawList* draw = ImGui::GetWindowDrawList();
  const float y = b.y - (b.y - a.y) * static_cast<float>(error_threshold_) / top;
  draw->AddLine(ImVec2(a.x, y), ImVec2(b.x, y), IM_COL32(230, 60, 60, 255), 1.5f);
  const float x = a.x + (b.x - a.x) * (view_.frame + 0.5f) / static_cast<float>(values.size());
  draw->AddLine(ImVec2(x, a.y), ImVec2(x, b.y), IM_COL32(255, 255, 255, 200), 1.0f);
  ImGui::SameLine();
  ImGui::BeginGroup();
  double threshold = error_threshold_;
  ImGui::SetNextItemWidth(110);
  if (ImGui::InputDouble("threshold", &threshold, 0.0, 0.0, "%.4g")) {
    error_threshold_ = std::max(0.0, threshold);
  }
  if (ImGui::Button("jump to first frame over threshold")) {
    if (jump_to_error_threshold() < 0) {
      report(ValueError("threshold",
                        "no frame's mean error exceeds " + std::to_string(error_threshold_)));
    }
  }
  ImGui::EndGroup();
}

void ViewerApp::draw_viewport_captions(const std::vector<Viewport>& viewports) {
  ImDrawList* draw = ImGui::GetBackgroundDrawList();
  const float left = kPanelWidth;
  for (size_t i = 0; i < viewports.size(); ++i) {
    const Viewport& p = viewports[i];
    const float x0 = std::max(static_cast<float>(p.x0), left);
    if (i > 0) {
      draw->AddLine(ImVec2(static_cast<float>(p.x0), 0.0f),
                    ImVec2(static_cast<float>(p.x0),
                           static_cast<float>(context_.height()) - timeline_height()),
                    IM_COL32(90, 90, 90, 255), 2.0f);
    }
    if (p.caption.empty()) continue;
    const std::string text = file_name(p.caption);
    const ImVec2 size = ImGui::CalcTextSize(text.c_str());
    const float x = 0.5f * (x0 + static_cast<float>(p.x1) - size.x);
    draw->AddRectFilled(ImVec2(x - 4, 6), ImVec2(x + size.x + 4, 10 + size.y),
                        IM_COL32(255, 255, 255, 200));
    draw->AddText(ImVec2(x, 8), IM_COL32(20, 20, 20, 255), text.c_str());
  }
}

void ViewerApp::draw_model_section() {
  ImGui::PushItemWidth(-90.0f);
  ImGui::InputText("##checkpoint", &checkpoint_field_);
  ImGui::SameLine();
  if (ImGui::Button(checkpoint_.empty() ? "Use" : "Change", ImVec2(-1, 0))) {
    set_checkpoint(checkpoint_field_);
  }
  ImGui::PopItemWidth();
  ImGui::TextColored(kMutedText, "checkpoint (.pt): traces drive levels and inspector");
  if (!checkpoint_.empty()) {
    if (trace_job_) {
      ImGui::Text("capturing model trace at frame %d...", trace_request_.frame);
    } else if (shown_trace()) {
      ImGui::Text("model trace: frame %d, level %d", trace_->frame, trace_level_);
    }
    ImGui::PushItemWidth(-90.0f);
    ImGui::InputText("##compare", &compare_field_);
    ImGui::PopItemWidth();
    ImGui::SameLine();
    if (ImGui::Button("Roll out", ImVec2(-1, 0))) start_rollouts(compare_field_);
    ImGui::TextColored(kMutedText, "roll the checkpoint out (optional: a second one to compare)");
  } else if (trace_from_file_ && trace_) {
    ImGui::Text("trace file: frame %d (%s)", trace_->frame,
                file_name(trace_->checkpoint_path).c_str());
  }
  if (rollout_job_) {
    char label[64];
    std::snprintf(label, sizeof(label), "%s %.0f%%", rollout_job_->label().c_str(),
                  100.0f * rollout_job_->fraction());
    ImGui::ProgressBar(rollout_job_->fraction(), ImVec2(-1, 0), label);
  }
}

void ViewerApp::draw_rollout_contacts() {
  const Rollout& r = rollout_->rollout;
  const double threshold = kContactThresholdFraction * r.sampling_voxel;
  const std::vector<double>& truth = r.contact_distance_truth;
  const std::vector<double>& pred = r.contact_distance_predicted;
  float top = static_cast<float>(threshold) * 1.2f;
  for (double v : truth) top = std::max(top, static_cast<float>(v));
  for (double v : pred) top = std::max(top, static_cast<float>(v));
  const std::vector<float> t(truth.begin(), truth.end()), p(pred.begin(), pred.end());
  const ImVec2 size(ImGui::GetContentRegionAvail().x, 70.0f);
  const ImVec2 origin = ImGui::GetCursorPos();
  const ImVec4 truth_color(0.3f, 0.8f, 0.4f, 1.0f), pred_color(1.0f, 0.6f, 0.15f, 1.0f);
  ImGui::PushStyleColor(ImGuiCol_PlotLines, truth_color);
  ImGui::PlotLines("##truth", t.data(), static_cast<int>(t.size()), 0, nullptr, 0.0f, top, size);
  ImGui::PopStyleColor();
  const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  // The prediction on the same axes, over the truth (transparent background).
  ImGui::SetCursorPos(origin);
  ImGui::PushStyleColor(ImGuiCol_FrameBg, ImVec4(0, 0, 0, 0));
  ImGui::PushStyleColor(ImGuiCol_PlotLines, pred_color);
  ImGui::PlotLines("##pred", p.data(), static_cast<int>(p.size()), 0, nullptr, 0.0f, top, size);
  ImGui::PopStyleColor(2);
  ImDrawList* draw = ImGui::GetWindowDrawList();
  const float y = b.y - (b.y - a.y) * static_cast<float>(threshold) / top;
  draw->AddLine(ImVec2(a.x, y), ImVec2(b.x, y), IM_COL32(230, 60, 60, 255), 1.0f);
  const float x = a.x + (b.x - a.x) * static_cast<float>(view_.frame) /
                            static_cast<float>(std::max<size_t>(1, t.size() - 1));
  draw->AddLine(ImVec2(x, a.y), ImVec2(x, b.y), IM_COL32(255, 255, 255, 160), 1.0f);
  const size_t f = static_cast<size_t>(view_.frame);
  ImGui::TextColored(truth_color, "truth %.4f", truth[f]);
  ImGui::SameLine();
  ImGui::TextColored(pred_color, "predicted %.4f", pred[f]);
  ImGui::SameLine();
  ImGui::TextColored(ImVec4(0.9f, 0.25f, 0.25f, 1.0f), "threshold %.4g", threshold);
  auto outcome = [&](const std::vector<double>& d) {
    for (size_t i = 0; i < d.size(); ++i) {
      if (d[i] < threshold) return "contact from frame " + std::to_string(i);
    }
    return std::string("no contact");
  };
  ImGui::Text("predicted outcome: %s", outcome(pred).c_str());
  ImGui::Text("true outcome:      %s", outcome(truth).c_str());
  // Scenes written by the simulator carry the outcome label (engine/sim kContactLabel).
  if (rollout_->scene) {
    const auto label = rollout_->scene->labels.find("target_contacting_zone");
    if (label != rollout_->scene->labels.end()) {
      const bool labelled = first_frame_over(label->second, 0.5) >= 0;
      const bool predicted = contact_predicted(pred, threshold);
      ImGui::Text("labelled outcome:  %s", labelled ? "contact" : "no contact");
      ImGui::SameLine();
      ImGui::TextColored(
          predicted == labelled ? ImVec4(0.3f, 0.8f, 0.4f, 1.0f) : ImVec4(0.9f, 0.25f, 0.25f, 1.0f),
          predicted == labelled ? "(prediction agrees)" : "(prediction disagrees)");
    }
  }
  ImGui::TextColored(kMutedText, "target-zone minimum point distance: truth and prediction");
}

}  // namespace dynscope::app::viewer
