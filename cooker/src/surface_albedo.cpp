#include "surface_albedo.h"

#include <algorithm>
#include <cmath>

namespace lightpatch::cooker {

glm::vec3 surface_albedo(const Scene& scene, const MeshInstance& mesh, uint32_t i0, uint32_t i1,
                         uint32_t i2, float u, float v) {
  glm::vec3 a(0.8f);
  if (mesh.material >= 0 && static_cast<size_t>(mesh.material) < scene.materials.size()) {
    const Material& m = scene.materials[static_cast<size_t>(mesh.material)];
    a = m.albedo;
    if (m.albedo_texture >= 0 && static_cast<size_t>(m.albedo_texture) < scene.textures.size() &&
        !mesh.uv0.empty()) {
      const Texture& tex = scene.textures[static_cast<size_t>(m.albedo_texture)];
      const glm::vec2 uv = mesh.uv0[i0] * (1.0f - u - v) + mesh.uv0[i1] * u + mesh.uv0[i2] * v;
      if (tex.width > 0 && tex.height > 0 && std::isfinite(uv.x) && std::isfinite(uv.y) &&
          tex.linear_rgb.size() == size_t(tex.width) * size_t(tex.height)) {
        const float fx = uv.x - std::floor(uv.x), fy = uv.y - std::floor(uv.y);
        const int x = std::min(tex.width - 1, static_cast<int>(fx * static_cast<float>(tex.width)));
        const int y =
            std::min(tex.height - 1, static_cast<int>(fy * static_cast<float>(tex.height)));
        a *= tex.linear_rgb[size_t(y) * size_t(tex.width) + size_t(x)];
      }
    }
  }
  for (int c = 0; c < 3; ++c) a[c] = a[c] > 0.0f ? std::min(a[c], 1.0f) : 0.0f;
  return a;
}

glm::vec3 surface_albedo(const Scene& scene, const Hit& hit) {
  const MeshInstance& mesh = scene.meshes[static_cast<size_t>(hit.mesh)];
  const size_t t = 3 * static_cast<size_t>(hit.triangle);
  return surface_albedo(scene, mesh, mesh.indices[t], mesh.indices[t + 1], mesh.indices[t + 2],
                        hit.u, hit.v);
}

}  // namespace lightpatch::cooker
