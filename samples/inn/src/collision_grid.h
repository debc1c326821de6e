// CollisionGrid: what the player can walk on and bump into, derived from the inn's static
// geometry. The floor plan is cut into square cells; each cell keeps the vertical extents
// [y0, y1] (merged where they overlap) of the triangles whose footprint touches it. A walker is a
// vertical cylinder: it is blocked where any extent in its cells reaches into the band between
// its knees (feet + step) and the top of its head, and it stands on the highest extent top at
// most one step above its feet. The inn's walls and furniture are axis-aligned, so a triangle's
// footprint bounding box is a tight enough stand-in for the triangle.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

namespace lightpatch::inn {

struct World;

class CollisionGrid {
 public:
  // `cell`: edge of a cell in metres.
  CollisionGrid(const World& world, float cell);

  // True when a cylinder of `radius` standing at `feet` overlaps geometry between
  // feet.y + step and feet.y + height.
  bool blocked(glm::vec3 feet, float radius, float step, float height) const;
  // Top of the highest surface under `feet` (within `radius`) in [feet.y - drop, feet.y + step].
  std::optional<float> floor_at(glm::vec3 feet, float radius, float step, float drop) const;

 private:
  struct Span {
    float y0, y1;
  };
  // Cells whose squares meet the disc's bounding square, clamped to the grid; false if none.
  bool cell_range(glm::vec3 p, float radius, int* x0, int* z0, int* x1, int* z1) const;

  float cell_ = 0.1f;
  glm::vec2 origin_{0.0f};
  int nx_ = 0, nz_ = 0;
  std::vector<uint32_t> first_;  // [nx*nz + 1] offsets into spans_ (CSR)
  std::vector<Span> spans_;
};

}  // namespace lightpatch::inn
