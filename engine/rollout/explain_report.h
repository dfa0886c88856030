// What `dynscope explain`, `render --explain` and the viewer's Explain panel share: object names,
// the default question (the divergence), the text table and the JSON of an explanation (no torch).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "engine/rollout/divergence.h"
#include "engine/rollout/explain.h"
#include "engine/scene/rollout.h"
#include "engine/scene/scene.h"

namespace dynscope {

/// Display names of a rollout's objects.
struct ObjectNames {
  std::map<int32_t, std::string> names;
  /// The object's name, or "object <id>" when it has none.
  std::string operator()(int32_t id) const;
};

/// Names from `scene` (may be null: ids only).
ObjectNames object_names(const Rollout& rollout, const Scene* scene);

/// Parses an object given by name or by id; throws ValueError(`option`) for one the rollout has
/// no points of, listing the objects it has.
int32_t parse_object(const std::string& text, const Rollout& rollout, const ObjectNames& names,
                     const std::string& option = "--object");

/// The question asked when the user leaves parts open. frame < 0: the divergence frame (ValueError
/// naming `frame_option` when the rollout has none). No object and no point: the divergence
/// object at that frame, or, at another frame, the object whose error grows most there.
ExplainSelection resolve_selection(const Rollout& rollout, const Divergence& divergence, int frame,
                                   int32_t object, int point, ExplainTarget target,
                                   const std::string& frame_option = "--frame");

/// "error" or "acceleration".
const char* explain_target_name(ExplainTarget target);
/// Inverse of explain_target_name; throws ValueError("--target") otherwise.
ExplainTarget parse_explain_target(const std::string& name);

/// One line per contributor, "relational  level 0  zone_1  62.0 %  ...", the `top` largest
/// (0: all), with a header; what the CLI prints and the renderer captions.
std::vector<std::string> contributor_lines(const Explanation& e, const ObjectNames& names,
                                           size_t top);
/// "object zone_1" or "point 17 (zone_1)".
std::string explained_subject(const Explanation& e, const ObjectNames& names);

/// The explanation as JSON: frame (int), object (name), object_id, point (−1 for an object),
/// target, error, error_growth, value, contributors (by share descending, each with list, level,
/// object, object_id, share, effect, edges) and, when given, the divergence (threshold, rule,
/// frame, object, per-object first frames, contacts).
std::string explanation_to_json(const Explanation& e, const ObjectNames& names,
                                const Divergence* divergence = nullptr);

}  // namespace dynscope
