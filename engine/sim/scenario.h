// Seeded, deterministic ground-truth scenario generators (Bullet): movi-a and Physion-like scenes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/scene/scene.h"
#include "engine/sim/simulation.h"

namespace dynscope {

/// Inputs some scenarios need besides the seed.
struct ScenarioOptions {
  /// Object meshes for "movi-c" (any units; each is centred and normalised); unused elsewhere.
  std::vector<Mesh> meshes;
  /// Stored frames per second; 0 keeps the scenario's own rate. Other rates store the same
  /// simulation more or less densely (set_frame_rate).
  double frame_rate_hz = 0.0;
  /// Tessellation of the stored meshes of primitive shapes (SimSetup::mesh_density); "movi-c"
  /// draws user meshes and accepts kDense only.
  MeshDensity mesh_density = MeshDensity::kDense;
};

/// Names of every scenario generate_scene() accepts ("movi-a", "movi-c", "drop", "collide", ...).
std::vector<std::string> scenario_names();

/// True if `scenario` is one of scenario_names().
bool is_scenario(const std::string& scenario);

/// One line describing the scenario (for --help); throws ValueError for an unknown name.
std::string scenario_summary(const std::string& scenario);

/// True if the scenario labels target_contacting_zone (the Physion-like ones).
bool scenario_has_contact_label(const std::string& scenario);

/// True if the scenario needs ScenarioOptions::meshes ("movi-c").
bool scenario_needs_meshes(const std::string& scenario);

/// The scenario's recipe constants and sampling ranges as a JSON object text (for manifests).
/// Throws ValueError for an unknown name.
std::string scenario_parameters_json(const std::string& scenario);

/// Throws ValueError("mesh_density") unless the scenario's meshes can be stored at `density`
/// ("movi-c" draws the given meshes as they are: dense only).
void check_mesh_density(const std::string& scenario, MeshDensity density);

/// The Bullet setup (bodies, initial poses and velocities, rates) of one trial, before it is
/// simulated. Throws ValueError for an unknown scenario (listing the known ones), for "movi-c"
/// without meshes or for a frame rate that does not fit the scenario's physics steps.
SimSetup scenario_setup(const std::string& scenario, uint64_t seed,
                        const ScenarioOptions& options = {});

/// Simulates one trial of `scenario` with `seed`. The same arguments always give the same scene.
/// Throws ValueError for an unknown scenario (listing the known ones).
Scene generate_scene(const std::string& scenario, uint64_t seed);

/// As above, with the inputs in `options` (meshes for "movi-c").
Scene generate_scene(const std::string& scenario, uint64_t seed, const ScenarioOptions& options);

}  // namespace dynscope
