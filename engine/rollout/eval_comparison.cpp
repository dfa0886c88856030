// Comparing evaluations over seeds and scenes.
#include "engine/rollout/eval_comparison.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <utility>

#include "engine/core/error.h"

namespace dynscope {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Mean and sample standard deviation (0 for fewer than two values).
void mean_sd(const std::vector<double>& v, double* mean, double* sd) {
  double m = 0.0;
  for (double x : v) m += x;
  m /= static_cast<double>(v.size());
  double ss = 0.0;
  for (double x : v) ss += (x - m) * (x - m);
  *mean = m;
  *sd = v.size() > 1 ? std::sqrt(ss / static_cast<double>(v.size() - 1)) : 0.0;
}

std::string fmt(const char* format, double a, double b = 0.0) {
  char text[64];
  std::snprintf(text, sizeof text, format, a, b);
  return text;
}

// `text` right-aligned in `width` characters (UTF-8: "±" is one character, two bytes).
std::string right_aligned(const std::string& text, size_t width) {
  size_t chars = 0;
  for (const char ch : text) chars += (static_cast<unsigned char>(ch) & 0xC0) != 0x80;
  return std::string(width > chars ? width - chars : 0, ' ') + text;
}

}  // namespace

EvalComparison compare_evaluations(const std::vector<RunEvaluations>& runs) {
  if (runs.empty()) throw ValueError("runs", "nothing to compare");
  const EvalSummary* first = nullptr;
  std::string first_path;
  std::map<std::string, size_t> scene_index;  // file -> position in the first evaluation
  for (const RunEvaluations& run : runs) {
    if (run.seeds.empty()) throw ValueError(run.label, "no evaluation given");
    for (size_t k = 0; k < run.seeds.size(); ++k) {
      const EvalSummary& s = run.seeds[k];
      const std::string path = k < run.paths.size() ? run.paths[k] : run.label;
      if (!first) {
        first = &s;
        first_path = path;
        for (size_t i = 0; i < s.scenes.size(); ++i) {
          if (!scene_index.emplace(s.scenes[i].file, i).second) {
            throw ValueError(path, "scene " + s.scenes[i].file + " appears twice");
          }
        }
        continue;
      }
      if (s.split != first->split) {
        throw ValueError(path, "evaluates the " + s.split + " split, " + first_path + " the " +
                                   first->split + " split");
      }
      std::set<std::string> files;
      for (const SceneEvaluation& e : s.scenes) {
        if (!scene_index.count(e.file) || !files.insert(e.file).second) {
          throw ValueError(path, "scene " + e.file + " is not one of the " +
                                     std::to_string(first->scenes.size()) + " scenes of " +
                                     first_path + " (or appears twice)");
        }
        const SceneEvaluation& f = first->scenes[scene_index.at(e.file)];
        if (e.scenario != f.scenario || e.label != f.label || e.has_contact != f.has_contact) {
          throw ValueError(
              path,
              "scene " + e.file + " has another scenario or contact label than in " + first_path);
        }
      }
      if (files.size() != scene_index.size()) {
        throw ValueError(path, "evaluates " + std::to_string(files.size()) + " scenes, " +
                                   first_path + " " + std::to_string(scene_index.size()));
      }
    }
  }

  EvalComparison c;
  c.split = first->split;
  c.scenes = static_cast<int>(scene_index.size());
  c.floor_end_error = c.floor_accuracy = c.truth_accuracy = kNaN;
  // The same scenes, so the same labelled scenarios in every evaluation.
  if (first->contact.scenarios >= 2) {
    for (const auto& [name, a] : first->scenarios) {
      if (name != "all" && a.labelled > 0) c.contact_scenarios.push_back(name);
    }
  }
  const size_t n_scenarios = c.contact_scenarios.size();
  c.floor_scenario_accuracy.assign(n_scenarios, kNaN);
  c.truth_scenario_accuracy.assign(n_scenarios, kNaN);
  // The floor and the ceiling do not depend on the model: taken from an evaluation that has them.
  for (const RunEvaluations& run : runs) {
    for (const EvalSummary& s : run.seeds) {
      const ScenarioSummary& all = s.scenarios.at("all");
      const bool labelled = s.contact.scenarios > 0;
      if (std::isnan(c.floor_end_error) && !all.baseline_curve.empty()) {
        c.floor_end_error = all.baseline_end_error;
        if (labelled) c.floor_accuracy = s.contact.baseline;
        for (size_t i = 0; i < n_scenarios; ++i)
          c.floor_scenario_accuracy[i] = s.scenarios.at(c.contact_scenarios[i]).baseline_accuracy;
      }
      if (std::isnan(c.truth_accuracy) && labelled) {
        c.truth_accuracy = s.contact.truth;
        for (size_t i = 0; i < n_scenarios; ++i)
          c.truth_scenario_accuracy[i] = s.scenarios.at(c.contact_scenarios[i]).truth_accuracy;
      }
    }
  }

  // Per run: every scene's end error averaged over its seeds, in the first evaluation's order.
  std::vector<std::vector<double>> per_scene;
  for (const RunEvaluations& run : runs) {
    RunStats st;
    st.label = run.label;
    st.seeds = static_cast<int>(run.seeds.size());
    std::vector<double> ends, accuracies;
    std::vector<std::vector<double>> scenario_accuracies(n_scenarios);
    std::vector<double> scene_mean(scene_index.size(), 0.0);
    st.floor_end_error = kNaN;
    for (const EvalSummary& s : run.seeds) {
      const ScenarioSummary& all = s.scenarios.at("all");
      ends.push_back(all.model_end_error);
      if (std::isnan(st.floor_end_error) && !all.baseline_curve.empty())
        st.floor_end_error = all.baseline_end_error;
      st.labelled = all.labelled;
      if (s.contact.scenarios > 0) accuracies.push_back(s.contact.model);
      for (size_t i = 0; i < n_scenarios; ++i)
        scenario_accuracies[i].push_back(s.scenarios.at(c.contact_scenarios[i]).model_accuracy);
      for (const SceneEvaluation& e : s.scenes) {
        scene_mean[scene_index.at(e.file)] += e.model_curve.back() / st.seeds;
      }
    }
    mean_sd(ends, &st.end_error_mean, &st.end_error_sd);
    if (!accuracies.empty()) mean_sd(accuracies, &st.accuracy_mean, &st.accuracy_sd);
    st.scenario_accuracy_mean.assign(n_scenarios, 0.0);
    st.scenario_accuracy_sd.assign(n_scenarios, 0.0);
    for (size_t i = 0; i < n_scenarios; ++i) {
      mean_sd(scenario_accuracies[i], &st.scenario_accuracy_mean[i], &st.scenario_accuracy_sd[i]);
    }
    c.runs.push_back(st);
    per_scene.push_back(std::move(scene_mean));
  }

  for (size_t a = 0; a < runs.size(); ++a) {
    for (size_t b = a + 1; b < runs.size(); ++b) {
      PairedDifference p;
      p.a = runs[a].label;
      p.b = runs[b].label;
      p.scenes = c.scenes;
      std::vector<double> d(per_scene[a].size());
      for (size_t i = 0; i < d.size(); ++i) {
        d[i] = per_scene[a][i] - per_scene[b][i];
        if (d[i] < 0) ++p.a_better;
      }
      double sd = 0.0;
      mean_sd(d, &p.mean, &sd);
      p.std_error = sd / std::sqrt(static_cast<double>(d.size()));
      const RunStats& ra = c.runs[a];
      const RunStats& rb = c.runs[b];
      if (ra.seeds < 2 || rb.seeds < 2) {
        c.pairs.push_back(p);
        continue;
      }
      p.seed_intervals_overlap =
          ra.end_error_mean - ra.end_error_sd <= rb.end_error_mean + rb.end_error_sd &&
          rb.end_error_mean - rb.end_error_sd <= ra.end_error_mean + ra.end_error_sd;
      c.pairs.push_back(p);
    }
  }
  return c;
}

std::string comparison_table(const EvalComparison& c) {
  size_t width = 5;
  for (const RunStats& r : c.runs) width = std::max(width, r.label.size());
  const int w = static_cast<int>(width);
  std::string out;
  char line[512];
  std::snprintf(line, sizeof line,
                "%d scenes of the %s split; end error: mean point distance at the last frame, "
                "mean ± sd over seeds\n",
                c.scenes, c.split.c_str());
  out += line;
  const bool contact = !std::isnan(c.truth_accuracy);
  std::snprintf(line, sizeof line, "%-*s %5s %18s %9s%s\n", w, "run", "seeds", "end error",
                "vs floor", contact ? "   contact accuracy" : "");
  out += line;
  for (const RunStats& r : c.runs) {
    std::string ratio =
        std::isnan(r.floor_end_error) ? "-" : fmt("%.2fx", r.end_error_mean / r.floor_end_error);
    std::snprintf(line, sizeof line, "%-*s %5d %s %9s", w, r.label.c_str(), r.seeds,
                  right_aligned(fmt("%.4f ± %.4f", r.end_error_mean, r.end_error_sd), 18).c_str(),
                  ratio.c_str());
    out += line;
    if (contact) {
      out += r.labelled > 0
                 ? "   " + fmt("%.1f %% ± %.1f", 100 * r.accuracy_mean, 100 * r.accuracy_sd)
                 : "   -";
    }
    out += "\n";
  }
  // One floor row per distinct floor: runs on other points (mesh vertices) have their own, and
  // the row then names its runs.
  std::vector<std::pair<double, std::string>> floors;
  for (const RunStats& r : c.runs) {
    if (std::isnan(r.floor_end_error)) continue;
    auto same = std::find_if(floors.begin(), floors.end(),
                             [&](const auto& f) { return f.first == r.floor_end_error; });
    if (same == floors.end()) {
      floors.emplace_back(r.floor_end_error, r.label);
    } else {
      same->second += ", " + r.label;
    }
  }
  for (const auto& [floor, labels] : floors) {
    std::snprintf(line, sizeof line, "%-*s %5s %18s %9s", w, "floor", "-",
                  fmt("%.4f", floor).c_str(), "1.00x");
    out += line;
    if (contact && !std::isnan(c.floor_accuracy) && floor == c.floor_end_error) {
      out += "   " + fmt("%.1f %%", 100 * c.floor_accuracy);
    }
    out += "   (constant velocity + gravity";
    out += floors.size() > 1 ? "; the floor of " + labels + ")\n" : ")\n";
  }
  if (contact) {
    out += "ceiling: the contact rule on the ground truth, " +
           fmt("%.1f %%", 100 * c.truth_accuracy) + "\n";
  }
  if (!c.contact_scenarios.empty()) {
    out += "contact accuracy above: the mean over " + std::to_string(c.contact_scenarios.size()) +
           " scenarios; per scenario (%, mean ± sd over seeds):\n";
    size_t cell = 12;  // "61.1 ± 13.4" and a space
    for (const std::string& name : c.contact_scenarios) cell = std::max(cell, name.size());
    std::snprintf(line, sizeof line, "%-*s", w, "run");
    out += line;
    for (const std::string& name : c.contact_scenarios) out += " " + right_aligned(name, cell);
    out += "\n";
    auto row = [&](const std::string& label, const std::vector<double>& mean,
                   const std::vector<double>* sd) {
      std::snprintf(line, sizeof line, "%-*s", w, label.c_str());
      out += line;
      for (size_t i = 0; i < mean.size(); ++i) {
        const std::string v = std::isnan(mean[i]) ? "-"
                              : sd ? fmt("%.1f ± %.1f", 100 * mean[i], 100 * (*sd)[i])
                                   : fmt("%.1f", 100 * mean[i]);
        out += " " + right_aligned(v, cell);
      }
      out += "\n";
    };
    for (const RunStats& r : c.runs)
      row(r.label, r.scenario_accuracy_mean, &r.scenario_accuracy_sd);
    if (!std::isnan(c.floor_accuracy)) row("floor", c.floor_scenario_accuracy, nullptr);
    row("ceiling", c.truth_scenario_accuracy, nullptr);
  }
  if (c.pairs.empty()) return out;
  out +=
      "\npaired per scene (A - B, each scene's end error averaged over seeds first; ± standard "
      "error over scenes)\n";
  std::snprintf(line, sizeof line, "%-*s %-*s %20s %14s  %s\n", w, "A", w, "B", "A - B",
                "A better on", "seed intervals");
  out += line;
  for (const PairedDifference& p : c.pairs) {
    std::snprintf(line, sizeof line, "%-*s %-*s %s %14s  %s\n", w, p.a.c_str(), w, p.b.c_str(),
                  right_aligned(fmt("%+.4f ± %.4f", p.mean, p.std_error), 20).c_str(),
                  (std::to_string(p.a_better) + "/" + std::to_string(p.scenes)).c_str(),
                  !p.seed_intervals_overlap   ? "- (needs 2+ seeds each)"
                  : *p.seed_intervals_overlap ? "overlap"
                                              : "apart");
    out += line;
  }
  return out;
}

std::string comparison_to_json(const EvalComparison& c) {
  using nlohmann::json;
  auto num = [](double v) { return std::isnan(v) ? json(nullptr) : json(v); };
  json j = {{"split", c.split},
            {"scenes", c.scenes},
            {"floor_end_error", num(c.floor_end_error)},
            {"floor_contact_accuracy", num(c.floor_accuracy)},
            {"truth_contact_accuracy", num(c.truth_accuracy)},
            {"runs", json::array()},
            {"pairs", json::array()}};
  for (const RunStats& r : c.runs) {
    json run = {{"label", r.label},
                {"seeds", r.seeds},
                {"end_error_mean", r.end_error_mean},
                {"end_error_sd", r.end_error_sd},
                {"floor_end_error", num(r.floor_end_error)},
                {"labelled", r.labelled}};
    if (r.labelled > 0) {
      run["contact_accuracy_mean"] = r.accuracy_mean;
      run["contact_accuracy_sd"] = r.accuracy_sd;
    }
    for (size_t i = 0; i < c.contact_scenarios.size(); ++i) {
      run["scenario_contact_accuracy"][c.contact_scenarios[i]] = {
          {"mean", r.scenario_accuracy_mean[i]}, {"sd", r.scenario_accuracy_sd[i]}};
    }
    j["runs"].push_back(run);
  }
  for (size_t i = 0; i < c.contact_scenarios.size(); ++i) {
    j["scenario_floor_contact_accuracy"][c.contact_scenarios[i]] =
        num(c.floor_scenario_accuracy[i]);
    j["scenario_truth_contact_accuracy"][c.contact_scenarios[i]] =
        num(c.truth_scenario_accuracy[i]);
  }
  for (const PairedDifference& p : c.pairs) {
    j["pairs"].push_back(
        {{"a", p.a},
         {"b", p.b},
         {"scenes", p.scenes},
         {"mean_difference", p.mean},
         {"std_error", p.std_error},
         {"a_better", p.a_better},
         {"seed_intervals_overlap",
          p.seed_intervals_overlap ? json(*p.seed_intervals_overlap) : json(nullptr)}});
  }
  return j.dump(2) + "\n";
}

}  // namespace dynscope
