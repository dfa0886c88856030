// ViewerState's explanations: the explain job, its installation and the attribution colours.
#include <limits>

#include "app/viewer/viewer_state.h"
#include "engine/core/error.h"

namespace dynscope::app::viewer {

void ViewerState::start_explain(int frame, int32_t object, int point, ExplainTarget target) {
  if (!rollout_) throw ValueError("explain", "open a rollout to explain");
  if (checkpoint_.empty() || !services_) {
    throw ValueError("explain", "choose the checkpoint that made the rollout (Model panel)");
  }
  if (explain_job_) throw ValueError("explain", "an explanation is running");
  ExplainJobRequest request;
  request.checkpoint = checkpoint_;
  request.rollout = std::make_shared<const Rollout>(rollout_->rollout);
  request.frame = frame;
  request.object = object;
  request.point = point;
  request.target = target;
  ModelServices* services = services_;
  std::shared_ptr<ModelCache> cache = cache_;
  explain_job_ = std::make_unique<BackgroundJob<RolloutExplanation>>(
      "explanation", ticket(), 1,
      [services, cache, request = std::move(request)](JobControl& control) {
        const std::shared_ptr<LoadedCheckpoint> model = cache->get(request.checkpoint);
        control.check();
        RolloutExplanation out = services->explain(*model, request, control);
        control.progress()->advance();
        return out;
      });
}

void ViewerState::update_explain_job() {
  if (!explain_job_ || !explain_job_->done()) return;
  const std::unique_ptr<BackgroundJob<RolloutExplanation>> job = std::move(explain_job_);
  if (job->ticket() != ticket() || job->cancelled() || !rollout_) {
    ++dropped_;  // cannot happen while replaced() retires jobs; kept as the rule's last guard
    return;
  }
  auto result = std::make_unique<const RolloutExplanation>(job->take());
  render::PointAttribution a;
  a.shares.assign(result->explanation.point_shares.begin(), result->explanation.point_shares.end());
  a.explained = result->explanation.points;
  // Validates the shares against the shown rollout before anything is replaced.
  std::shared_ptr<render::PointSeries> series = render::make_attribution_series(*rollout_, a);
  attribution_ = std::move(a);
  attribution_series_ = std::move(series);
  explanation_ = std::move(result);
  set_attribution_colors(true);
  set_frame(explanation_->explanation.frame);
  show_panel(Panel::kExplain);
}

void ViewerState::set_attribution_colors(bool on) {
  attribution_colors_ = on;
  if (on) view_.layers.level_points = false;
}

std::shared_ptr<render::PointSeries> ViewerState::attribution_series() const {
  return attribution_colors_ && explanation_ ? attribution_series_ : nullptr;
}

void ViewerState::inspect_pair(int frame, int32_t a, int32_t b) {
  if (!rollout_) throw ValueError("explain", "no rollout is shown");
  const Rollout& r = rollout_->rollout;
  if (frame < 0 || frame >= r.num_frames()) {
    throw ValueError("frame", std::to_string(frame) + " is outside the rollout");
  }
  const Points& p = r.predicted[static_cast<size_t>(frame)];
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  bool any_b = false;
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    if (r.object_ids[static_cast<size_t>(i)] != a) continue;
    for (Eigen::Index j = 0; j < p.rows(); ++j) {
      if (r.object_ids[static_cast<size_t>(j)] != b) continue;
      any_b = true;
      const double d = (p.row(i) - p.row(j)).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = static_cast<int>(i);
      }
    }
  }
  if (best < 0 || !any_b) {
    throw ValueError("object", "objects " + std::to_string(a) + " and " + std::to_string(b) +
                                   " need points in the rollout");
  }
  set_frame(frame);
  select(PickSet::kPrediction, best);
  show_panel(Panel::kInspector);
}

}  // namespace dynscope::app::viewer
