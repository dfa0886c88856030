// EngineModelServices: the viewer's model run through the engine's LibTorch code (library
// dynscope_viewer_engine, beside the viewer, which stays free of LibTorch).
#pragma once

#include <memory>
#include <string>

#include "app/viewer/model_services.h"

namespace dynscope::app::viewer {

/// Loads checkpoints with load_model (one per checkpoint, the viewer's ModelCache keeps it) and
/// runs rollouts, traces and explanations with the engine's rollout runner, trace capture and
/// RolloutExplainer, one call at a time per model.
class EngineModelServices : public ModelServices {
 public:
  std::shared_ptr<LoadedCheckpoint> load(const std::string& checkpoint) override;
  Rollout rollout(LoadedCheckpoint& model, const RolloutRequest& request,
                  JobControl& control) override;
  ModelTrace trace(LoadedCheckpoint& model, const TraceRequest& request,
                   JobControl& control) override;
  RolloutExplanation explain(LoadedCheckpoint& model, const ExplainJobRequest& request,
                             JobControl& control) override;
};

}  // namespace dynscope::app::viewer
