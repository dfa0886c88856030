// EngineModelServices: checkpoints loaded once and run through the engine's LibTorch code.
#include "app/viewer/engine_model_services.h"

#include <memory>
#include <mutex>

#include "app/cli_util.h"
#include "engine/core/error.h"
#include "engine/rollout/explain_report.h"
#include "engine/rollout/model_points.h"
#include "engine/rollout/model_predictor.h"
#include "engine/rollout/rollout_runner.h"
#include "engine/train/train_options.h"

namespace dynscope::app::viewer {
namespace {

class EngineCheckpoint : public LoadedCheckpoint {
 public:
  explicit EngineCheckpoint(const std::string& path)
      : path(path), model(load_model(path)), sampling(checkpoint_sampling(path, model.config)) {}
  std::string path;
  LoadedModel model;
  SamplingOptions sampling;
  std::unique_ptr<RolloutExplainer> explainer;  ///< Loaded on the first explanation.
  std::mutex mutex;
};

}  // namespace

std::shared_ptr<LoadedCheckpoint> EngineModelServices::load(const std::string& checkpoint) {
  require_readable_file(checkpoint);
  return std::make_shared<EngineCheckpoint>(checkpoint);
}

Rollout EngineModelServices::rollout(LoadedCheckpoint& loaded, const RolloutRequest& request,
                                     JobControl& control) {
  auto& c = static_cast<EngineCheckpoint&>(loaded);
  std::lock_guard<std::mutex> lock(c.mutex);
  RolloutOptions options;
  options.observed_frames = request.observed_frames;
  const ModelPoints points = build_model_points(request.scene, c.sampling);
  // Cancellation is polled before every model step.
  const StepPredictor predict = [&c, &control](const PointState& state) {
    control.check();
    return c.model.predict(state);
  };
  Rollout r = run_rollout(request.scene, points, predict, options, control.progress());
  r.scene_path = request.scene_path;
  r.checkpoint_path = c.path;
  r.model_config = c.model.config_json;
  return r;
}

ModelTrace EngineModelServices::trace(LoadedCheckpoint& loaded, const TraceRequest& request,
                                      JobControl& control) {
  auto& c = static_cast<EngineCheckpoint&>(loaded);
  std::lock_guard<std::mutex> lock(c.mutex);
  control.check();
  if (request.rollout) {
    return app::capture_checkpoint_rollout_trace(c.path, *request.rollout, request.rollout_path,
                                                 request.frame, request.level, request.picked);
  }
  return app::capture_checkpoint_trace(c.path, *request.scene, request.scene_path, request.frame,
                                       request.level, request.picked);
}

RolloutExplanation EngineModelServices::explain(LoadedCheckpoint& loaded,
                                                const ExplainJobRequest& request,
                                                JobControl& control) {
  auto& c = static_cast<EngineCheckpoint&>(loaded);
  std::lock_guard<std::mutex> lock(c.mutex);
  control.check();
  if (!request.rollout) throw ValueError("explain", "no rollout to explain");
  if (!c.explainer) c.explainer = std::make_unique<RolloutExplainer>(c.path);
  RolloutExplanation out;
  out.divergence = find_divergence(*request.rollout, c.explainer->config());
  control.check();
  const ExplainSelection selection =
      resolve_selection(*request.rollout, out.divergence, request.frame, request.object,
                        request.point, request.target, "frame");
  out.explanation = c.explainer->explain(*request.rollout, selection);
  return out;
}

}  // namespace dynscope::app::viewer
