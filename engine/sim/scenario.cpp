// Scenario registry: names, summaries, parameters and dispatch to the generators.
#include "engine/sim/scenario.h"

#include <nlohmann/json.hpp>

#include "engine/core/error.h"
#include "engine/sim/generators.h"

namespace dynscope {
namespace {

struct Entry {
  const char* name;
  const char* summary;
  SimSetup (*make)(uint64_t seed);
};

// "movi-a" and "movi-c" share one generator and are dispatched separately below.
const Entry kEntries[] = {
    {"movi-a",
     "Kubric MOVi-A: 3-10 cubes, cylinders, spheres thrown onto a floor (24 frames, 12 fps)",
     nullptr},
    {"movi-c", "MOVi-C-like: as movi-a with objects drawn from --meshes (convex-hull collision)",
     nullptr},
    {"drop", "a red target falls onto a yellow zone pad, sometimes deflected by an obstacle",
     sim::make_drop},
    {"collide", "a blue probe knocks the red target towards the yellow zone", sim::make_collide},
    {"roll", "the red target rolls or slides down a ramp towards the yellow zone", sim::make_roll},
    {"dominoes", "a row of dominoes is tipped; the red last one may fall onto the yellow zone",
     sim::make_dominoes},
    {"support", "a leaning stack may topple and drop its red top block onto the yellow zone",
     sim::make_support},
    {"contain", "the red target is dropped or thrown at an open box whose floor is the zone",
     sim::make_contain},
    {"link", "a jointed chain hangs off a table; its red end link may be pulled onto the zone",
     sim::make_link},
};

const Entry& find_entry(const std::string& scenario) {
  for (const Entry& e : kEntries) {
    if (scenario == e.name) return e;
  }
  std::string known;
  for (const Entry& e : kEntries) known += (known.empty() ? "" : ", ") + std::string(e.name);
  throw ValueError("scenario", "unknown scenario '" + scenario + "' (known: " + known + ")");
}

}  // namespace

std::vector<std::string> scenario_names() {
  std::vector<std::string> names;
  for (const Entry& e : kEntries) names.emplace_back(e.name);
  return names;
}

bool is_scenario(const std::string& scenario) {
  for (const Entry& e : kEntries) {
    if (scenario == e.name) return true;
  }
  return false;
}

std::string scenario_summary(const std::string& scenario) { return find_entry(scenario).summary; }

bool scenario_has_contact_label(const std::string& scenario) {
  return find_entry(scenario).make != nullptr;
}

bool scenario_needs_meshes(const std::string& scenario) {
  find_entry(scenario);
  return scenario == "movi-c";
}

std::string scenario_parameters_json(const std::string& scenario) {
  const Entry& e = find_entry(scenario);
  const nlohmann::json p =
      e.make ? sim::physion_parameters(scenario) : sim::movi_parameters(scenario == "movi-c");
  return p.dump();
}

namespace {

SimSetup scenario_own_setup(const std::string& scenario, uint64_t seed,
                            const ScenarioOptions& options) {
  const Entry& e = find_entry(scenario);
  if (e.make) return e.make(seed);
  if (scenario == "movi-c") {
    if (options.meshes.empty()) {
      throw ValueError("movi-c", "needs object meshes (dynscope generate --meshes DIR)");
    }
    for (size_t i = 0; i < options.meshes.size(); ++i) {
      const Mesh& m = options.meshes[i];
      const std::string what = "movi-c mesh " + std::to_string(i);
      m.validate(what);
      if (m.num_vertices() < 4 || m.num_faces() < 4) {
        throw ValueError(what, "needs at least 4 vertices and 4 faces");
      }
      const Aabb box = Aabb::of(m.vertices);
      if (!((box.max - box.min).minCoeff() > 0)) throw ValueError(what, "is flat (zero volume)");
    }
    return sim::make_movi(seed, options.meshes);
  }
  return sim::make_movi(seed, {});
}

}  // namespace

void check_mesh_density(const std::string& scenario, MeshDensity density) {
  if (density != MeshDensity::kDense && scenario_needs_meshes(scenario)) {
    throw ValueError("mesh_density", scenario +
                                         " draws the given meshes as they are; only "
                                         "the primitive shapes of other scenarios can "
                                         "be sparse");
  }
}

SimSetup scenario_setup(const std::string& scenario, uint64_t seed,
                        const ScenarioOptions& options) {
  check_mesh_density(scenario, options.mesh_density);
  SimSetup setup = scenario_own_setup(scenario, seed, options);
  if (options.frame_rate_hz != 0.0) set_frame_rate(setup, options.frame_rate_hz);
  setup.mesh_density = options.mesh_density;
  return setup;
}

Scene generate_scene(const std::string& scenario, uint64_t seed) {
  return generate_scene(scenario, seed, ScenarioOptions{});
}

Scene generate_scene(const std::string& scenario, uint64_t seed, const ScenarioOptions& options) {
  return simulate(scenario_setup(scenario, seed, options));
}

}  // namespace dynscope
