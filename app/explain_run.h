// One explanation of a rollout by a checkpoint, as `dynscope explain` and `render --explain` ask
// for it: the divergence, the resolved question and the answer, with the objects' names.
#pragma once

#include <string>

#include "engine/rollout/explain_report.h"

namespace dynscope::app {

/// What the user asked; frame −1 and empty object / point −1 leave them to the divergence.
struct ExplainRequest {
  std::string checkpoint;
  std::string rollout_path;
  int frame = -1;
  std::string object;  ///< Name or id ("" : none).
  int point = -1;
  ExplainTarget target = ExplainTarget::kError;
  double threshold = 0.0;  ///< Divergence threshold (<= 0: derived from the rollout).
};

/// The answer and what it was computed from.
struct ExplainRun {
  Rollout rollout;
  ObjectNames names;
  Divergence divergence;
  Explanation explanation;
};

/// Reads the rollout, names its objects from the scene it started from (when found), finds the
/// divergence with the checkpoint's model config, resolves the question (resolve_selection) and
/// explains it. Warns when the rollout was made with another checkpoint. Throws IoError for
/// unreadable files, ValueError for --object/--point/--frame the rollout does not have (naming
/// the option), and what RolloutExplainer throws.
ExplainRun explain_checkpoint_rollout(const ExplainRequest& request);

}  // namespace dynscope::app
