// Per-object error curves, the divergence rule and the model's contact pairs.
#include "engine/rollout/divergence.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <utility>

#include "engine/core/error.h"
#include "engine/model/hierarchy.h"
#include "engine/rollout/state_history.h"

namespace dynscope {

int ObjectErrorCurves::row(int32_t object) const {
  const auto it = std::lower_bound(objects.begin(), objects.end(), object);
  return it != objects.end() && *it == object ? static_cast<int>(it - objects.begin()) : -1;
}

ObjectErrorCurves object_error_curves(const Rollout& rollout) {
  rollout.validate();
  ObjectErrorCurves c;
  c.objects = rollout.object_ids;
  std::sort(c.objects.begin(), c.objects.end());
  c.objects.erase(std::unique(c.objects.begin(), c.objects.end()), c.objects.end());
  const int frames = rollout.num_frames();
  c.errors.assign(c.objects.size(), std::vector<double>(static_cast<size_t>(frames), 0.0));
  std::vector<int> count(c.objects.size(), 0);
  std::vector<int> row(rollout.object_ids.size());
  for (size_t i = 0; i < row.size(); ++i) {
    row[i] = c.row(rollout.object_ids[i]);
    ++count[static_cast<size_t>(row[i])];
  }
  for (int f = 0; f < frames; ++f) {
    const Points& p = rollout.predicted[static_cast<size_t>(f)];
    const Points& t = rollout.truth[static_cast<size_t>(f)];
    for (Eigen::Index i = 0; i < p.rows(); ++i) {
      c.errors[static_cast<size_t>(row[static_cast<size_t>(i)])][static_cast<size_t>(f)] +=
          (p.row(i) - t.row(i)).norm();
    }
  }
  for (size_t o = 0; o < c.objects.size(); ++o) {
    for (double& e : c.errors[o]) e /= count[o];
  }
  return c;
}

double mean_error_of(const Rollout& rollout, const std::vector<int>& points, int frame) {
  const Points& p = rollout.predicted[static_cast<size_t>(frame)];
  const Points& t = rollout.truth[static_cast<size_t>(frame)];
  double sum = 0.0;
  for (int i : points) sum += (p.row(i) - t.row(i)).norm();
  return points.empty() ? 0.0 : sum / static_cast<double>(points.size());
}

PassRange rollout_passes(const Rollout& rollout) {
  return {first_rollout_trace_frame(rollout.observed_frames), rollout.num_frames() - 2};
}

std::vector<ContactPair> model_contacts(const Rollout& rollout, int frame,
                                        const ModelConfig& config) {
  if (frame < 0 || frame >= rollout.num_frames()) {
    throw ValueError("frame", std::to_string(frame) + " is outside the rollout's " +
                                  std::to_string(rollout.num_frames()) + " frames");
  }
  const Hierarchy h = build_model_hierarchy(rollout.predicted[static_cast<size_t>(frame)],
                                            rollout.object_ids, rollout.faces, config);
  std::map<std::pair<int32_t, int32_t>, int> edges;
  auto count = [&](const NeighborList& list, const std::vector<int32_t>& query_ids,
                   const std::vector<int32_t>& source_ids) {
    for (Eigen::Index m = 0; m < list.rows(); ++m) {
      for (Eigen::Index k = 0; k < list.k(); ++k) {
        if (!list.mask(m, k)) continue;
        const int32_t a = query_ids[static_cast<size_t>(m)];
        const int32_t b = source_ids[static_cast<size_t>(list.index(m, k))];
        if (a != b) ++edges[{std::min(a, b), std::max(a, b)}];
      }
    }
  };
  if (h.has_mesh) {
    count(h.mesh.senders, h.mesh.object_ids, h.mesh.object_ids);
  } else {
    const HierarchyLevel& l0 = h.levels.front();
    count(l0.relational, l0.object_ids, l0.object_ids);
  }
  std::vector<ContactPair> out;
  for (const auto& [pair, n] : edges) out.push_back({pair.first, pair.second, n});
  std::stable_sort(out.begin(), out.end(),
                   [](const ContactPair& x, const ContactPair& y) { return x.edges > y.edges; });
  return out;
}

Divergence find_divergence(const Rollout& rollout, const ModelConfig& config,
                           const DivergenceOptions& options) {
  Divergence d;
  d.curves = object_error_curves(rollout);
  const ObjectErrorCurves& curves = d.curves;
  const PassRange passes = rollout_passes(rollout);
  double largest = 0.0;
  for (const std::vector<double>& e : curves.errors) {
    for (int t = passes.first; t <= passes.last; ++t) {
      largest = std::max(largest, e[static_cast<size_t>(t + 1)] - e[static_cast<size_t>(t)]);
    }
  }
  char rule[160];
  if (options.threshold > 0) {
    d.threshold = options.threshold;
    std::snprintf(rule, sizeof(rule), "given: %.4g per frame", d.threshold);
  } else {
    d.threshold = kDerivedThresholdFraction * largest;
    d.threshold_derived = true;
    std::snprintf(rule, sizeof(rule),
                  "%.2g x the largest per-object error growth of the rollout (%.4g per frame)",
                  kDerivedThresholdFraction, largest);
  }
  d.threshold_rule = rule;
  for (size_t o = 0; o < curves.objects.size(); ++o) {
    ObjectDivergence od;
    od.object = curves.objects[o];
    const std::vector<double>& e = curves.errors[o];
    // Nothing diverges in a rollout whose errors never grow (a derived threshold is then 0).
    for (int t = passes.first; t <= passes.last && largest > 0; ++t) {
      const double g = e[static_cast<size_t>(t + 1)] - e[static_cast<size_t>(t)];
      if (g > d.threshold) {
        od.frame = t;
        od.error = e[static_cast<size_t>(t + 1)];
        od.growth = g;
        break;
      }
    }
    d.objects.push_back(od);
  }
  std::stable_sort(d.objects.begin(), d.objects.end(),
                   [](const ObjectDivergence& a, const ObjectDivergence& b) {
                     if ((a.frame < 0) != (b.frame < 0)) return b.frame < 0;
                     if (a.frame != b.frame) return a.frame < b.frame;
                     return a.growth > b.growth;
                   });
  if (!d.objects.empty() && d.objects.front().frame >= 0) {
    const ObjectDivergence& first = d.objects.front();
    d.frame = first.frame;
    d.object = first.object;
    d.error = first.error;
    d.growth = first.growth;
    d.contacts = model_contacts(rollout, d.frame, config);
  }
  return d;
}

}  // namespace dynscope
