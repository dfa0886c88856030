// Seeded, deterministic ground-truth scenario generators (Bullet): movi-a and Physion-like scenes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/scene/scene.h"

namespace dynscope {

/// Names of every scenario generate_scene() accepts ("movi-a", "drop", "collide", ...).
std::vector<std::string> scenario_names();

/// Simulates one trial of `scenario` with `seed`. The same arguments always give the same scene.
/// Throws ValueError for an unknown scenario (listing the known ones).
Scene generate_scene(const std::string& scenario, uint64_t seed);

}  // namespace dynscope
