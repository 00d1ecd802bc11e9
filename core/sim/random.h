#pragma once
// Seeded random numbers for the simulator. Streams are derived from (seed, purpose, index) so
// that parallel loops draw the same numbers whatever the thread count.
#include <cstdint>
#include <random>

namespace bathyslam::sim {

// SplitMix64: decorrelates nearby seeds before they seed a generator.
inline uint64_t mix_seed(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

inline std::mt19937_64 make_rng(uint64_t seed, uint64_t stream, uint64_t index = 0) {
  return std::mt19937_64(mix_seed(mix_seed(mix_seed(seed) ^ stream) ^ index));
}

// Stream identifiers, one per use of randomness.
enum Stream : uint64_t {
  kTerrainStream = 1,
  kSonarNoiseStream = 2,
  kDriftStream = 3,
  kAttitudeStream = 4,
  kCompassStepStream = 5,
  kStartFixStream = 6,
};

}  // namespace bathyslam::sim
