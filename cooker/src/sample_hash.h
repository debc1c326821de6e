// Deterministic random numbers keyed by what they sample (seed, texel, light, sample index), so a
// cook gives the same bits for any thread count. Inline: callers in sample loops hash a key whose
// first parts do not change from sample to sample, and the compiler computes those parts once.
#pragma once

#include <cstdint>

namespace lightpatch::cooker {

// One round of splitmix64.
inline uint64_t splitmix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Deterministic per-(seed, texel, light, sample) random numbers in [0,1).
inline uint64_t sample_hash(uint64_t seed, uint64_t texel, uint64_t light, uint64_t sample) {
  return splitmix(splitmix(splitmix(splitmix(seed) ^ texel) ^ light) ^ sample);
}

inline float hash_to_unit(uint64_t h) {
  return static_cast<float>(h >> 40) * (1.0f / 16777216.0f);
}

}  // namespace lightpatch::cooker
