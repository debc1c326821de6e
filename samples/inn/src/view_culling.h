// View culling: whether an axis-aligned box can show in a view, so that a pass draws only the
// world's chunks (World::chunks) it can see. llvmpipe shades every vertex it is given on one
// thread before clipping, so the camera pass over the whole inn cost more in vertices than in
// pixels.
#pragma once

#include <cmath>

#include <glm/glm.hpp>

namespace lightpatch::inn {

// False only when no point of the box [lo, hi] (world space) lies inside the clip volume of
// `view_projection` (-w <= x, y, z <= w): the box is wholly outside one of its six planes.
// Conservative: a box outside the volume but not outside any one plane (near a corner of the
// frustum) counts as visible, which costs a few triangles and never a missing one.
inline bool box_in_view(const glm::mat4& view_projection, glm::vec3 lo, glm::vec3 hi) {
  // Row r of the matrix (glm is column-major): clip coordinate r = dot(row_r, (p, 1)).
  auto row = [&](int r) {
    return glm::vec4(view_projection[0][r], view_projection[1][r], view_projection[2][r],
                     view_projection[3][r]);
  };
  const glm::vec4 x = row(0), y = row(1), z = row(2), w = row(3);
  const glm::vec4 planes[6] = {w + x, w - x, w + y, w - y, w + z, w - z};
  for (const glm::vec4& p : planes) {
    // The box's corner farthest along the plane's normal: if even it is outside, all are.
    const glm::vec3 far_corner(p.x >= 0.0f ? hi.x : lo.x, p.y >= 0.0f ? hi.y : lo.y,
                               p.z >= 0.0f ? hi.z : lo.z);
    // Outside by more than float rounding of the sum (relative to its terms' size).
    const glm::vec3 t = glm::vec3(p) * far_corner;
    const float sum = t.x + t.y + t.z + p.w;
    const float size = std::fabs(t.x) + std::fabs(t.y) + std::fabs(t.z) + std::fabs(p.w);
    if (sum < -1.0e-5f * size) return false;
  }
  return true;
}

// False only when the clip volumes of two views have no point in common: the corners of one lie
// wholly outside one of the other's six planes (either way round). Conservative as box_in_view:
// volumes that miss each other across an edge may still count as meeting. Corners are computed
// in double precision (a far plane hundreds of metres out inverts badly in float).
inline bool views_meet(const glm::mat4& a, const glm::mat4& b) {
  auto separated = [](const glm::mat4& planes_of, const glm::mat4& corners_of) {
    const glm::dmat4 m(planes_of);
    const glm::dmat4 inverse = glm::inverse(glm::dmat4(corners_of));
    glm::dvec3 corner[8];
    for (int k = 0; k < 8; ++k) {
      const glm::dvec4 c =
          inverse * glm::dvec4(k & 1 ? 1.0 : -1.0, k & 2 ? 1.0 : -1.0, k & 4 ? 1.0 : -1.0, 1.0);
      corner[k] = glm::dvec3(c) / c.w;
    }
    auto row = [&](int r) { return glm::dvec4(m[0][r], m[1][r], m[2][r], m[3][r]); };
    const glm::dvec4 x = row(0), y = row(1), z = row(2), w = row(3);
    const glm::dvec4 planes[6] = {w + x, w - x, w + y, w - y, w + z, w - z};
    for (const glm::dvec4& p : planes) {
      bool all_outside = true;
      for (int k = 0; k < 8 && all_outside; ++k) {
        const double v = glm::dot(glm::dvec3(p), corner[k]) + p.w;
        const double size = glm::dot(glm::abs(glm::dvec3(p)), glm::abs(corner[k])) + std::fabs(p.w);
        all_outside = v < -1.0e-9 * size;
      }
      if (all_outside) return true;
    }
    return false;
  };
  return !separated(a, b) && !separated(b, a);
}

}  // namespace lightpatch::inn
