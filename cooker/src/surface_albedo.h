// The albedo light meets where a ray hits a surface: what every integrator reflects with.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>

#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/tracer.h"

namespace lightpatch::cooker {

// The base colour factor times the base colour texture at TEXCOORD_0 (nearest texel, repeat
// wrap, glTF's default sampler), each channel clamped to [0, 1] (above 1 would create energy;
// NaN reflects nothing). Meshes without a material get 0.8 grey. At the point of the triangle of
// vertices i0, i1, i2 of `mesh` with barycentrics u (of i1) and v (of i2); indices < vertex count.
glm::vec3 surface_albedo(const Scene& scene, const MeshInstance& mesh, uint32_t i0, uint32_t i1,
                         uint32_t i2, float u, float v);
// The same at a ray's hit. Precondition: `hit.hit`, its mesh and triangle in `scene`.
glm::vec3 surface_albedo(const Scene& scene, const Hit& hit);

}  // namespace lightpatch::cooker
