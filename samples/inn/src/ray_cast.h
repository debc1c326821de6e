// Ray casting against the world's triangles (brute force: for the scripted run's camera placement
// and the light meter, a few dozen rays per step, never per frame).
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

#include "world.h"

namespace lightpatch::inn {

struct RayHit {
  float distance = 0.0f;     // along the (unit) direction, metres
  uint32_t triangle = 0;     // index into World::indices of the triangle's first vertex
  float u = 0.0f, v = 0.0f;  // barycentric weights of the second and third vertex
};

// Nearest hit of the ray within (0, max_distance] among the triangles of `range`. With
// `front_only`, triangles seen from behind are ignored.
bool cast_ray(const World& world, const IndexRange& range, glm::vec3 origin, glm::vec3 direction,
              float max_distance, bool front_only, RayHit* hit);

// Light-map UV at a hit (interpolated from the triangle's vertices).
glm::vec2 hit_lightmap_uv(const World& world, const RayHit& hit);

}  // namespace lightpatch::inn
