// Names, default selection, text and JSON of explanations.
#include "engine/rollout/explain_report.h"

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <set>

#include "engine/core/error.h"

namespace dynscope {

std::string ObjectNames::operator()(int32_t id) const {
  const auto it = names.find(id);
  return it != names.end() && !it->second.empty() ? it->second : "object " + std::to_string(id);
}

ObjectNames object_names(const Rollout& rollout, const Scene* scene) {
  ObjectNames n;
  for (int32_t id : rollout.object_ids) n.names.emplace(id, "");
  if (scene) {
    for (const Object& o : scene->objects) {
      if (n.names.count(o.id)) n.names[o.id] = o.name;
    }
  }
  return n;
}

int32_t parse_object(const std::string& text, const Rollout& rollout, const ObjectNames& names,
                     const std::string& option) {
  const std::set<int32_t> ids(rollout.object_ids.begin(), rollout.object_ids.end());
  for (int32_t id : ids) {
    if (names(id) == text) return id;
  }
  try {
    size_t used = 0;
    const long v = std::stol(text, &used);
    if (used == text.size() && ids.count(static_cast<int32_t>(v))) return static_cast<int32_t>(v);
  } catch (const std::exception&) {
  }
  std::string known;
  for (int32_t id : ids)
    known += (known.empty() ? "" : ", ") + names(id) + " (" + std::to_string(id) + ")";
  throw ValueError(option, "no object '" + text + "' with points in the rollout; it has " + known);
}

ExplainSelection resolve_selection(const Rollout& rollout, const Divergence& divergence, int frame,
                                   int32_t object, int point, ExplainTarget target,
                                   const std::string& frame_option) {
  ExplainSelection s;
  s.target = target;
  s.object = object;
  s.point = point;
  if (frame < 0) {
    if (!divergence.found()) {
      throw ValueError(frame_option,
                       "the rollout's error never grows, so there is no divergence "
                       "frame to explain: give one");
    }
    s.frame = divergence.frame;
  } else {
    s.frame = frame;
  }
  if (s.object >= 0 || s.point >= 0) return s;
  if (s.frame == divergence.frame) {
    s.object = divergence.object;
    return s;
  }
  const PassRange passes = rollout_passes(rollout);
  if (s.frame < passes.first || s.frame > passes.last) return s;  // explain() names the range
  const ObjectErrorCurves curves = object_error_curves(rollout);
  double best = -1e300;
  for (size_t o = 0; o < curves.objects.size(); ++o) {
    const std::vector<double>& e = curves.errors[o];
    const double g = e[static_cast<size_t>(s.frame + 1)] - e[static_cast<size_t>(s.frame)];
    if (g > best) {
      best = g;
      s.object = curves.objects[o];
    }
  }
  return s;
}

const char* explain_target_name(ExplainTarget target) {
  return target == ExplainTarget::kError ? "error" : "acceleration";
}

ExplainTarget parse_explain_target(const std::string& name) {
  if (name == "error") return ExplainTarget::kError;
  if (name == "acceleration") return ExplainTarget::kAcceleration;
  throw ValueError("--target", "must be error or acceleration, got '" + name + "'");
}

std::vector<std::string> contributor_lines(const Explanation& e, const ObjectNames& names,
                                           size_t top) {
  std::vector<std::string> lines;
  size_t width = 6;
  for (const Contributor& c : e.contributors) width = std::max(width, names(c.object).size());
  char line[256];
  std::snprintf(line, sizeof(line), "%-13s %-8s  %-*s  %7s  %10s  %11s  %5s", "list", "level",
                static_cast<int>(width), "object", "share", "|dE/dg|", "effect", "edges");
  lines.push_back(line);
  const size_t n = top == 0 ? e.contributors.size() : std::min(top, e.contributors.size());
  for (size_t i = 0; i < n; ++i) {
    const Contributor& c = e.contributors[i];
    std::snprintf(line, sizeof(line), "%-13s level %-2d  %-*s  %5.1f %%  %10.3g  %+11.3g  %5d",
                  c.list.c_str(), c.level, static_cast<int>(width), names(c.object).c_str(),
                  100.0 * c.share, c.magnitude, c.effect, c.edges);
    lines.push_back(line);
  }
  if (n < e.contributors.size()) {
    double rest = 0.0;
    for (size_t i = n; i < e.contributors.size(); ++i) rest += e.contributors[i].share;
    std::snprintf(line, sizeof(line), "(%zu more groups: %.1f %%)", e.contributors.size() - n,
                  100.0 * rest);
    lines.push_back(line);
  }
  return lines;
}

std::string explained_subject(const Explanation& e, const ObjectNames& names) {
  if (e.point >= 0) return "point " + std::to_string(e.point) + " (" + names(e.object) + ")";
  return "object " + names(e.object);
}

std::string explanation_to_json(const Explanation& e, const ObjectNames& names,
                                const Divergence* divergence) {
  nlohmann::json j;
  j["frame"] = e.frame;
  j["predicted_frame"] = e.frame + 1;
  j["object"] = names(e.object);
  j["object_id"] = e.object;
  j["point"] = e.point;
  j["target"] = explain_target_name(e.target);
  j["error"] = e.error;
  j["error_growth"] = e.error_growth;
  j["value"] = e.value;
  j["edge_total"] = e.edge_total;
  nlohmann::json list = nlohmann::json::array();
  for (const Contributor& c : e.contributors) {
    list.push_back({{"list", c.list},
                    {"level", c.level},
                    {"object", names(c.object)},
                    {"object_id", c.object},
                    {"share", c.share},
                    {"magnitude", c.magnitude},
                    {"effect", c.effect},
                    {"edges", c.edges}});
  }
  j["contributors"] = list;
  if (divergence) {
    nlohmann::json d;
    d["threshold"] = divergence->threshold;
    d["threshold_rule"] = divergence->threshold_rule;
    d["frame"] = divergence->frame;
    d["object"] =
        divergence->found() ? nlohmann::json(names(divergence->object)) : nlohmann::json();
    d["object_id"] = divergence->object;
    d["error"] = divergence->error;
    d["growth"] = divergence->growth;
    nlohmann::json objects = nlohmann::json::array();
    for (const ObjectDivergence& o : divergence->objects) {
      objects.push_back({{"object", names(o.object)},
                         {"object_id", o.object},
                         {"frame", o.frame},
                         {"error", o.error},
                         {"growth", o.growth}});
    }
    d["objects"] = objects;
    nlohmann::json contacts = nlohmann::json::array();
    for (const ContactPair& c : divergence->contacts) {
      contacts.push_back({{"a", names(c.a)}, {"b", names(c.b)}, {"edges", c.edges}});
    }
    d["contacts"] = contacts;
    j["divergence"] = d;
  }
  return j.dump(2) + "\n";
}

}  // namespace dynscope
