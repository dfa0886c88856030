// Where a rollout goes wrong: per-object error curves, the first frame whose error growth stands
// out, and the object pairs the model saw in contact there (plain data, no torch).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/model/model_config.h"
#include "engine/scene/rollout.h"

namespace dynscope {

/// Mean |predicted − truth| of each object's points per frame.
struct ObjectErrorCurves {
  std::vector<int32_t> objects;             ///< `[O]` ids of the objects with points, ascending.
  std::vector<std::vector<double>> errors;  ///< `[O][T]` scene units.

  /// Row of `object` in `objects`, or −1.
  int row(int32_t object) const;
};

/// Per-object error curves of a validated rollout. Throws ValueError as Rollout::validate.
ObjectErrorCurves object_error_curves(const Rollout& rollout);

/// Mean |predicted − truth| of the rollout points `points` at `frame` (no checks beyond asserts;
/// `points` must be valid indices, `frame` a frame of the rollout).
double mean_error_of(const Rollout& rollout, const std::vector<int>& points, int frame);

/// Frames of the model passes a rollout holds: pass t read predicted frames t−2..t and produced
/// t+1, for t in [first_rollout_trace_frame(observed), T−2] (state_history.h). first > last when
/// the rollout predicted nothing.
struct PassRange {
  int first = 0;
  int last = -1;
  bool empty() const { return first > last; }
};
PassRange rollout_passes(const Rollout& rollout);

/// Two objects the model sees in contact at a pass.
struct ContactPair {
  int32_t a = 0, b = 0;  ///< Object ids, a < b.
  int edges = 0;         ///< Neighbour-list edges between them (both directions).
};

/// The object pairs in relational contact at pass `frame`, as the model sees them: edges of the
/// level-0 relational lists (point input) or of the interaction-point sender lists (mesh input)
/// between points of different objects, in the hierarchy `config` builds on the rollout's own
/// predicted frame `frame`. Most edges first (ties: by ids). Throws ValueError for a frame outside
/// the rollout, and as build_model_hierarchy (mesh input needs the rollout's faces).
std::vector<ContactPair> model_contacts(const Rollout& rollout, int frame,
                                        const ModelConfig& config);

/// How find_divergence decides.
struct DivergenceOptions {
  /// Error growth per frame (scene units) above which an object diverges; <= 0: derived from the
  /// rollout as kDerivedThresholdFraction × the largest growth of any object at any pass.
  double threshold = 0.0;
};

/// Fraction of the rollout's largest per-object error growth that is the default threshold: an
/// object diverges at the first pass where its error grows at least half as fast as the fastest
/// growth anywhere in the rollout.
inline constexpr double kDerivedThresholdFraction = 0.5;

/// One object's first pass over the threshold.
struct ObjectDivergence {
  int32_t object = 0;
  int frame = -1;       ///< Pass t (−1: never over the threshold).
  double error = 0.0;   ///< Error at t+1.
  double growth = 0.0;  ///< error(t+1) − error(t).
};

/// Result of find_divergence.
struct Divergence {
  double threshold = 0.0;
  bool threshold_derived = false;
  std::string threshold_rule;  ///< How the threshold was chosen, for output ("0.5 × ...").
  int frame = -1;              ///< First pass where an object's growth exceeds the threshold.
  int32_t object = -1;         ///< That object (ties at the frame: the larger growth).
  double error = 0.0;          ///< Its error at frame+1.
  double growth = 0.0;         ///< Its growth at frame.
  std::vector<ObjectDivergence> objects;  ///< Every object, by first divergence (never: last).
  std::vector<ContactPair> contacts;      ///< model_contacts at `frame` (empty without one).
  ObjectErrorCurves curves;               ///< The per-object error curves it read.

  bool found() const { return frame >= 0; }
};

/// Per-object error growth g_o(t) = e_o(t+1) − e_o(t) over the rollout's passes (rollout_passes),
/// the threshold (options, else derived), every object's first pass with g_o(t) > threshold, and
/// the earliest of them with the model's contacts there. Nothing is found when the rollout has no
/// pass or no growth is positive. Throws ValueError as object_error_curves and model_contacts.
Divergence find_divergence(const Rollout& rollout, const ModelConfig& config,
                           const DivergenceOptions& options = {});

}  // namespace dynscope
