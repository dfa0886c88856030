// Seeded, platform-independent random numbers (no std distributions, whose output varies).
#pragma once

#include <cstdint>

namespace dynscope {

/// SplitMix64-seeded xoshiro256** generator; the same seed gives the same stream everywhere.
class Rng {
 public:
  explicit Rng(uint64_t seed = 0);

  /// Next raw 64-bit value.
  uint64_t next_u64();
  /// Uniform double in [0, 1).
  double uniform();
  /// Uniform double in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform integer in [lo, hi] (inclusive); throws ValueError if hi < lo.
  int64_t uniform_int(int64_t lo, int64_t hi);
  /// Standard normal sample (Box-Muller).
  double normal();
  /// Normal sample with the given mean and standard deviation.
  double normal(double mean, double stddev) { return mean + stddev * normal(); }
  /// A new generator whose stream is independent of this one (for per-item seeding).
  Rng split();

 private:
  uint64_t s_[4];
  bool has_spare_ = false;
  double spare_ = 0.0;
};

/// Mixes a base seed with an index into a new well-spread seed (e.g. one per scene).
uint64_t derive_seed(uint64_t base, uint64_t index);

}  // namespace dynscope
