// Deterministic random numbers keyed by what they sample (seed, texel, light, sample index), so a
// cook gives the same bits for any thread count. Inline: callers in sample loops hash a key whose
// first parts do not change from sample to sample, and the compiler computes those parts once.
#pragma once

#include <cmath>
#include <cstdint>
#include <utility>

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

// Low-discrepancy steps (Roberts' R_d sequences): R2's two dimensions (1/g, 1/g^2 with
// g^3 = g + 1), and R4's last two (1/g^3, 1/g^4 with g^5 = g + 1). The two pairs are rationally
// independent, so R2 and kR4Last at one index make a low-discrepancy sequence of four dimensions.
inline constexpr double kR2[2] = {0.7548776662466927, 0.5698402909980532};
inline constexpr double kR4Last[2] = {0.6287067210378086, 0.5385972572236101};

// The two offsets (Cranley-Patterson rotation) of a 2-D sequence drawn from `rng`: the same for
// every k of one key, different between keys, so neighbours do not share a pattern.
inline std::pair<double, double> rotation_of(uint64_t rng) {
  return {hash_to_unit(rng), hash_to_unit(sample_hash(rng, 1, 2, 3))};
}

// Element k of the sequence with step `alpha`, rotated by `offset` (Cranley-Patterson): in [0, 1).
inline double kronecker(double offset, double alpha, int k) {
  const double x = offset + alpha * double(k + 1);
  return x - std::floor(x);
}

}  // namespace lightpatch::cooker
