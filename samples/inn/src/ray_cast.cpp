#include "ray_cast.h"

#include <cmath>

namespace lightpatch::inn {
namespace {

glm::vec3 position_of(const World& w, uint32_t index) {
  const WorldVertex& v = w.vertices[index];
  return {v.position[0], v.position[1], v.position[2]};
}

}  // namespace

bool cast_ray(const World& world, const IndexRange& range, glm::vec3 origin, glm::vec3 dir,
              float max_distance, bool front_only, RayHit* hit) {
  bool found = false;
  float best = max_distance;
  for (uint32_t t = range.first; t + 2 < range.first + range.count; t += 3) {
    // Möller-Trumbore.
    const glm::vec3 a = position_of(world, world.indices[t]);
    const glm::vec3 e1 = position_of(world, world.indices[t + 1]) - a;
    const glm::vec3 e2 = position_of(world, world.indices[t + 2]) - a;
    if (front_only && glm::dot(glm::cross(e1, e2), dir) >= 0.0f) continue;
    const glm::vec3 pv = glm::cross(dir, e2);
    const float det = glm::dot(e1, pv);
    if (std::fabs(det) < 1e-12f) continue;
    const float inv = 1.0f / det;
    const glm::vec3 tv = origin - a;
    const float u = glm::dot(tv, pv) * inv;
    if (u < 0.0f || u > 1.0f) continue;
    const glm::vec3 qv = glm::cross(tv, e1);
    const float v = glm::dot(dir, qv) * inv;
    if (v < 0.0f || u + v > 1.0f) continue;
    const float d = glm::dot(e2, qv) * inv;
    if (d > 1e-4f && d <= best) {
      best = d;
      *hit = RayHit{d, t, u, v};
      found = true;
    }
  }
  return found;
}

glm::vec2 hit_lightmap_uv(const World& world, const RayHit& hit) {
  glm::vec2 uv(0.0f);
  const float w[3] = {1.0f - hit.u - hit.v, hit.u, hit.v};
  for (int k = 0; k < 3; ++k) {
    const WorldVertex& v = world.vertices[world.indices[hit.triangle + static_cast<uint32_t>(k)]];
    uv += w[k] * glm::vec2(v.lightmap_uv[0], v.lightmap_uv[1]);
  }
  return uv;
}

}  // namespace lightpatch::inn
