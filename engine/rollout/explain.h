// Explaining one pass of a rollout from the model's own state: which neighbourhoods made a point
// go wrong, as gradient × input attribution over the edges of every neighbour list (LibTorch stays
// in the source).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "engine/model/model_config.h"
#include "engine/scene/rollout.h"

namespace dynscope {

/// The scalar an explanation attributes, over the chosen points' raw network prediction of t+1
/// (before rigid projection): their mean error |p̂ − p_true| (scene units) or the mean magnitude
/// of their predicted acceleration p̂(t+1) − p(t) − v(t) (scene units per frame²).
/// Names: explain_target_name (explain_report.h).
enum class ExplainTarget { kError, kAcceleration };

/// What to explain: one pass and either an object (all its points) or one point.
struct ExplainSelection {
  int frame = 0;        ///< Pass t: it read predicted frames t−2..t and produced t+1.
  int32_t object = -1;  ///< Object id (its points' mean), or −1 when a point is chosen.
  int point = -1;       ///< Rollout point index, or −1 when an object is chosen.
  ExplainTarget target = ExplainTarget::kError;
};

/// One group of edges: those of one list at one level whose sources belong to one object.
struct Contributor {
  std::string list;    ///< level_list_name or mesh_list_name (hierarchy.h).
  int level = 0;       ///< The list's level (mesh lists: 0), as in its trace name "<level>/<list>".
  int32_t object = 0;  ///< Object id of the edges' source points.
  double share = 0.0;  ///< magnitude over that of all edges; shares sum to 1.
  double magnitude = 0.0;  ///< Σ_e |∂E/∂g_e| over the group's edges (E's units).
  /// Σ_e ∂E/∂g_e (E's units): removing the group's messages would change E by about −effect, so
  /// a positive effect means these neighbours pushed E up.
  double effect = 0.0;
  int edges = 0;  ///< Edges of the group that reach E (nonzero gradient).
  /// The rollout points (level 0) the group's sources are, with their share of the total: a coarse
  /// source through its level-0 representative, an interaction point split over its face's
  /// vertices.
  std::vector<int> points;
  std::vector<double> point_shares;
};

/// The answer to "which neighbours made this go wrong?" for one pass.
struct Explanation {
  int frame = 0;        ///< Pass t.
  int32_t object = -1;  ///< The chosen object (for a point: its object).
  int point = -1;       ///< The chosen point, −1 for an object.
  ExplainTarget target = ExplainTarget::kError;
  std::vector<int> points;    ///< The points E averages over.
  double error = 0.0;         ///< Their mean error in the rollout at t+1.
  double error_growth = 0.0;  ///< error(t+1) − error(t) in the rollout.
  double value = 0.0;         ///< E of the raw prediction (before rigid projection).
  /// Σ_e |∂E/∂g_e| over every edge (E's units): to first order, no set of neighbour messages
  /// changes E by more, which says how much the prediction listens to its neighbours at all.
  double edge_total = 0.0;
  /// Every group with a nonzero share, by share descending (ties: list, level, object).
  std::vector<Contributor> contributors;
  /// `[N]` share of each rollout point over all groups (sums to 1 when any edge reaches E).
  std::vector<double> point_shares;
};

/// A checkpoint loaded once for explanations of rollouts. Each explanation builds the model's
/// hierarchy on the rollout's own predicted frames t−2..t, gives every valid edge e of every
/// neighbour list a gate g_e = 1 that scales its message (NeighborTensors::gate), runs the model
/// forward and E backward, and groups ∂E/∂g_e — gradient × input with the edge's presence as the
/// input — by (list, level, source object). The point's own residual path is not an edge and is
/// not attributed. Thread-safe (one explanation at a time).
class RolloutExplainer {
 public:
  /// Loads `checkpoint_path`; throws as load_checkpoint (IoError, FormatError, Error naming it).
  explicit RolloutExplainer(const std::string& checkpoint_path);
  ~RolloutExplainer();
  RolloutExplainer(const RolloutExplainer&) = delete;
  RolloutExplainer& operator=(const RolloutExplainer&) = delete;

  const std::string& checkpoint_path() const;
  const ModelConfig& config() const;

  /// Throws ValueError for a frame outside rollout_passes (divergence.h), an object without
  /// points, a point outside the rollout, both or neither of object and point, and as
  /// build_model_hierarchy (mesh input needs the rollout's faces); LibTorch errors become Error
  /// naming the checkpoint.
  Explanation explain(const Rollout& rollout, const ExplainSelection& selection) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dynscope
