// Scenario generators (setup builders) and the placement helpers they share; used by scenario.cpp.
#pragma once

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "engine/core/rng.h"
#include "engine/sim/simulation.h"

namespace dynscope::sim {

/// Uniformly distributed random rotation (Shoemake's method).
Quat random_rotation(Rng& rng);
/// Rotation by `radians` about the unit axis `axis`.
Quat axis_angle(const Vec3& axis, double radians);
/// Converts an sRGB colour in [0, 1] to the linear RGB stored in Object::color.
Vec3 srgb_to_linear(const Vec3& srgb);

/// A body with one unit primitive part (box half extent 1, sphere radius 1, cylinder radius 1 and
/// half height 1) and `scale` = its half sizes, so the stored mesh is the unit shape.
BodySpec primitive_body(int32_t id, const std::string& name, Role role, ShapeKind kind,
                        const Vec3& scale);
/// Sets the mass to `density` (kg/m³) times the body's volume.
void set_density(BodySpec& body, double density);
/// Moves the body vertically so that the bottom of its bounds is at `base_z`.
void rest_on(BodySpec& body, double base_z);

/// Kubric MOVi-A recipe (see SCENARIOS.md). `meshes` empty: cubes, cylinders and spheres;
/// otherwise MOVi-C-like objects drawn from `meshes` with convex-hull collision shapes.
SimSetup make_movi(uint64_t seed, const std::vector<Mesh>& meshes);
/// Recipe constants of make_movi for the dataset manifest.
nlohmann::json movi_parameters(bool user_meshes);

/// Physion-like "drop": the target falls onto the zone's floor, maybe deflected by an obstacle.
SimSetup make_drop(uint64_t seed);
/// Physion-like "collide": a probe knocks the resting target towards the zone.
SimSetup make_collide(uint64_t seed);
/// Physion-like "roll": the target rolls or slides down a ramp towards the zone.
SimSetup make_roll(uint64_t seed);
/// Physion-like "dominoes": a tipped row whose last domino (the target) may fall onto the zone.
SimSetup make_dominoes(uint64_t seed);
/// Physion-like "support": a leaning stack whose top block (the target) may fall onto the zone.
SimSetup make_support(uint64_t seed);
/// Physion-like "contain": the target is dropped or thrown at an open box floored by the zone.
SimSetup make_contain(uint64_t seed);
/// Physion-like "link": a ball-jointed chain slides off a table, its table end being the target.
SimSetup make_link(uint64_t seed);
/// Sampling ranges of the Physion-like scenario `name` for the dataset manifest; throws
/// ValueError for another name.
nlohmann::json physion_parameters(const std::string& name);

}  // namespace dynscope::sim
