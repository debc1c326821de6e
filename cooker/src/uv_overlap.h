// Overlap test for 2D triangles (light-map UVs, chart projections): a sparse uniform grid of
// inserted triangles and a separating-axis test that lets triangles share edges and corners but
// not area.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <unordered_map>
#include <vector>

namespace lightpatch::cooker {

class UvOverlapGrid {
 public:
  // True if `tri` overlaps (in area, beyond a tolerance relative to the triangles' size) a
  // triangle inserted before; `*which` receives the insertion index of one such triangle.
  bool overlaps(const glm::vec2 tri[3], int* which = nullptr) const;
  void insert(const glm::vec2 tri[3]);

 private:
  struct Cell {
    int64_t x, y;
    bool operator==(const Cell& o) const { return x == o.x && y == o.y; }
  };
  struct CellHash {
    size_t operator()(const Cell& c) const {
      return static_cast<size_t>((uint64_t(c.x) * 0x9E3779B97F4A7C15ull) ^ uint64_t(c.y));
    }
  };
  // Cells [r0,r2]x[r1,r3] covered by the triangle's box; false if there are too many.
  bool cell_range(const glm::vec2 tri[3], int64_t r[4]) const;

  float cell_ = 0.0f;            // set from the first triangle's size
  std::vector<glm::vec2> tris_;  // 3 per inserted triangle
  std::unordered_map<Cell, std::vector<int>, CellHash> grid_;
  std::vector<int> big_;  // triangles too large for the grid
};

}  // namespace lightpatch::cooker
