// Seed derivation shared by the generator's parts: one independent stream per
// purpose and index (frame, object, ...), so a draw added in one place shifts
// no other and a value can be recomputed from its key alone.
#pragma once

#include <cstdint>

namespace semrec::synth {

/// A well-mixed 64-bit hash of (a, b).
inline uint64_t MixSeed(uint64_t a, uint64_t b) {
  uint64_t h = a * 0x9E3779B97F4A7C15ULL + b + 0x632BE59BD9B4E019ULL;
  h ^= h >> 31;
  h *= 0xBF58476D1CE4E5B9ULL;
  return h ^ (h >> 29);
}

/// A hash mapped to [0, 1) (53 bits).
inline double UnitFromHash(uint64_t h) {
  h ^= h >> 33;
  h *= 0xFF51AFD7ED558CCDULL;
  h ^= h >> 33;
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

}  // namespace semrec::synth
