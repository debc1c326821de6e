// Shape helpers: tessellated primitives for building scenes by code. All sizes in metres; every
// shape has unit normals and no texture coordinates unless the function says otherwise. Position
// a shape with Geometry::transform() or Geometry::append(other, matrix).
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "lightpatch/scenegen/geometry.h"

namespace lightpatch::scenegen {

enum class Facing {
  kOutward,  // normals point out of the solid (furniture, props)
  kInward,   // normals point into the box (a room seen from inside)
};

// Axis-aligned box from `min` to `max`; each face split into `subdivisions` × `subdivisions`
// quads (≥ 1). 12 · subdivisions² triangles.
Geometry make_box(glm::vec3 min, glm::vec3 max, Facing facing = Facing::kOutward,
                  int subdivisions = 1);

// Box with rounded edges and corners of radius `bevel` (clamped to half the smallest side),
// `segments` (≥ 1) quads across each rounded edge. 12 · (2·segments + 1)² triangles.
Geometry make_rounded_box(glm::vec3 min, glm::vec3 max, float bevel, int segments = 2);

// Quad p0 p1 p2 p3 (counter-clockwise seen from the front), split into `nu` × `nv` quads. Normal
// from the winding. With `with_uv`, uv0 runs 0..1 from p0 (u along p0→p1, v along p0→p3).
Geometry make_quad(glm::vec3 p0, glm::vec3 p1, glm::vec3 p2, glm::vec3 p3, int nu = 1, int nv = 1,
                   bool with_uv = false);

// Horizontal plane at y = 0 centred on the origin, `size_x` × `size_z`, facing +Y.
Geometry make_plane(float size_x, float size_z, int nx = 1, int nz = 1, bool with_uv = false);

// Cylinder around the +Y axis from y = 0 to y = height, `segments` (≥ 3) around, `rings` (≥ 1)
// along; caps are triangle fans. Smooth side normals.
Geometry make_cylinder(float radius, float height, int segments = 16, int rings = 1,
                       bool caps = true);

// Cone/frustum around +Y from radius `r0` at y = 0 to `r1` at y = height (r1 may be 0).
Geometry make_frustum(float r0, float r1, float height, int segments = 16, bool caps = true);

// UV sphere centred on the origin, `segments` (≥ 3) around, `rings` (≥ 2) pole to pole.
Geometry make_sphere(float radius, int segments = 12, int rings = 8);

// Surface of revolution around +Y of a profile of (radius, y) points, `segments` (≥ 3) around.
// The profile runs bottom to top for an outward-facing surface; a radius of 0 closes the end.
// Normals come from the profile's tangents (smooth). Good for dishes, cups, bottles, candles.
Geometry make_lathe(const std::vector<glm::vec2>& profile, int segments = 16);

// Torus around +Y centred on the origin (ring radius `major`, tube radius `minor`).
Geometry make_torus(float major, float minor, int segments = 16, int tube_segments = 8);

}  // namespace lightpatch::scenegen
