// Scene bounds and counts.
#include "lightpatch/cooker/scene.h"

#include <cmath>
#include <limits>

namespace lightpatch::cooker {

void Scene::compute_bounds() {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  glm::vec3 lo(kInf), hi(-kInf);
  bool any = false;
  for (const MeshInstance& m : meshes) {
    for (const glm::vec3& p : m.positions) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
      any = true;
    }
  }
  bounds_min = any ? lo : glm::vec3(0.0f);
  bounds_max = any ? hi : glm::vec3(0.0f);
}

float Scene::scale() const {
  // The diagonal of the bounds; a scene that is a single point (or empty) still gets a positive
  // scale so that epsilons derived from it are never zero.
  const float d = glm::length(bounds_max - bounds_min);
  if (!(d > 0.0f) || !std::isfinite(d)) return 1.0f;
  return d;
}

size_t Scene::triangle_count() const {
  size_t n = 0;
  for (const MeshInstance& m : meshes) n += m.indices.size() / 3;
  return n;
}

}  // namespace lightpatch::cooker
