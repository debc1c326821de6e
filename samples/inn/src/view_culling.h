// View culling: whether an axis-aligned box can show in a view, so that a pass draws only the
// world's chunks (World::chunks) it can see. llvmpipe shades every vertex it is given on one
// thread before clipping, so the camera pass over the whole inn cost more in vertices than in
// pixels.
#pragma once

#include <array>
#include <cmath>

#include <glm/glm.hpp>

namespace lightpatch::inn {

namespace view_culling_detail {

// The six planes of a view-projection's clip volume (-w <= x, y, z <= w), as (normal, offset):
// a point p is inside a plane where dot(normal, p) + offset >= 0. glm is column-major, so row r
// of the matrix gives clip coordinate r.
template <typename Mat>
std::array<typename Mat::col_type, 6> clip_planes(const Mat& m) {
  using V4 = typename Mat::col_type;
  auto row = [&](int r) { return V4(m[0][r], m[1][r], m[2][r], m[3][r]); };
  const V4 x = row(0), y = row(1), z = row(2), w = row(3);
  return {w + x, w - x, w + y, w - y, w + z, w - z};
}

// Whether `point` lies outside `plane` by more than the rounding of the plane's sum, taken as
// `tolerance` times the size of its terms.
template <typename V4, typename V3>
bool outside(const V4& plane, const V3& point, typename V3::value_type tolerance) {
  const V3 t = V3(plane) * point;
  const auto sum = t.x + t.y + t.z + plane.w;
  const auto size = std::abs(t.x) + std::abs(t.y) + std::abs(t.z) + std::abs(plane.w);
  return sum < -tolerance * size;
}

}  // namespace view_culling_detail

// False only when no point of the box [lo, hi] (world space) lies inside the clip volume of
// `view_projection`: the box is wholly outside one of its six planes. Conservative: a box outside
// the volume but not outside any one plane (near a corner of the frustum) counts as visible,
// which costs a few triangles and never a missing one.
inline bool box_in_view(const glm::mat4& view_projection, glm::vec3 lo, glm::vec3 hi) {
  for (const glm::vec4& p : view_culling_detail::clip_planes(view_projection)) {
    // The box's corner farthest along the plane's normal: if even it is outside, all are.
    const glm::vec3 far_corner(p.x >= 0.0f ? hi.x : lo.x, p.y >= 0.0f ? hi.y : lo.y,
                               p.z >= 0.0f ? hi.z : lo.z);
    if (view_culling_detail::outside(p, far_corner, 1.0e-5f)) return false;
  }
  return true;
}

// False only when the clip volumes of two views have no point in common: the corners of one lie
// wholly outside one of the other's six planes (either way round). Conservative as box_in_view:
// volumes that miss each other across an edge may still count as meeting. In double precision (a
// far plane hundreds of metres out inverts badly in float).
inline bool views_meet(const glm::mat4& a, const glm::mat4& b) {
  auto separated = [](const glm::mat4& planes_of, const glm::mat4& corners_of) {
    const glm::dmat4 inverse = glm::inverse(glm::dmat4(corners_of));
    glm::dvec3 corner[8];
    for (int k = 0; k < 8; ++k) {
      const glm::dvec4 c =
          inverse * glm::dvec4(k & 1 ? 1.0 : -1.0, k & 2 ? 1.0 : -1.0, k & 4 ? 1.0 : -1.0, 1.0);
      corner[k] = glm::dvec3(c) / c.w;
    }
    for (const glm::dvec4& p : view_culling_detail::clip_planes(glm::dmat4(planes_of))) {
      bool all_outside = true;
      for (int k = 0; k < 8 && all_outside; ++k)
        all_outside = view_culling_detail::outside(p, corner[k], 1.0e-9);
      if (all_outside) return true;
    }
    return false;
  };
  return !separated(a, b) && !separated(b, a);
}

}  // namespace lightpatch::inn
