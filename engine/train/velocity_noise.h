// Training's input noise: the GNS random walk on the input velocities, shared between points as
// TrainOptions::noise_mode says.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/types.h"

namespace dynscope {

class Rng;

/// How training's input noise is shared between points (TrainOptions::noise_mode).
enum class NoiseMode {
  kPoint,    ///< "point": every point its own draw
  kObject,   ///< "object": one draw per object, shared by its points (objects stay rigid)
  kCentred,  ///< "centred": every point its own draw less its object's mean draw, so no object
             ///< as a whole moves (only the within-object jitter that rigid projection removes)
};
/// Parses "point", "object" or "centred"; throws ValueError("noise-mode", ...) otherwise.
NoiseMode parse_noise_mode(const std::string& name);

/// Training's input noise (GNS random walk): adds to the two input velocities `v_prev` and `v`
/// `[N,3]` increments of std σ/√2 (one to v_prev, that one plus a second to v), so that the noise
/// on v has std σ = `noise_std` (σ·√(1 − 1/n) for a point of an n-point object when centred),
/// shared between points as `mode` says. Throws ValueError on mismatched sizes.
void add_velocity_noise(double noise_std, NoiseMode mode, const std::vector<int32_t>& object_ids,
                        Points* v_prev, Points* v, Rng* rng);

}  // namespace dynscope
