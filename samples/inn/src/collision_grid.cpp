#include "collision_grid.h"

#include <algorithm>
#include <cmath>

#include "world.h"

namespace lightpatch::inn {

CollisionGrid::CollisionGrid(const World& world, float cell) : cell_(cell) {
  origin_ = glm::vec2(world.bounds_min.x, world.bounds_min.z) - glm::vec2(cell);
  nx_ = static_cast<int>(std::ceil((world.bounds_max.x - origin_.x) / cell)) + 2;
  nz_ = static_cast<int>(std::ceil((world.bounds_max.z - origin_.y) / cell)) + 2;
  struct Entry {
    uint32_t cell;
    Span span;
  };
  std::vector<Entry> entries;
  const IndexRange r = world.static_range;
  for (uint32_t t = r.first; t + 2 < r.first + r.count; t += 3) {
    glm::vec3 lo(1e30f), hi(-1e30f);
    for (int k = 0; k < 3; ++k) {
      const WorldVertex& v = world.vertices[world.indices[t + static_cast<uint32_t>(k)]];
      const glm::vec3 p(v.position[0], v.position[1], v.position[2]);
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    int x0, z0, x1, z1;
    // Shrink a hair so a wall exactly on a cell border marks one row of cells, not two.
    const glm::vec3 mid = 0.5f * (lo + hi);
    const glm::vec3 half = glm::max(0.5f * (hi - lo) - glm::vec3(1e-4f), glm::vec3(0.0f));
    x0 = static_cast<int>(std::floor((mid.x - half.x - origin_.x) / cell_));
    x1 = static_cast<int>(std::floor((mid.x + half.x - origin_.x) / cell_));
    z0 = static_cast<int>(std::floor((mid.z - half.z - origin_.y) / cell_));
    z1 = static_cast<int>(std::floor((mid.z + half.z - origin_.y) / cell_));
    x0 = std::clamp(x0, 0, nx_ - 1);
    x1 = std::clamp(x1, 0, nx_ - 1);
    z0 = std::clamp(z0, 0, nz_ - 1);
    z1 = std::clamp(z1, 0, nz_ - 1);
    for (int z = z0; z <= z1; ++z)
      for (int x = x0; x <= x1; ++x)
        entries.push_back({static_cast<uint32_t>(z * nx_ + x), {lo.y, hi.y}});
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return a.cell != b.cell ? a.cell < b.cell : a.span.y0 < b.span.y0;
  });
  first_.assign(static_cast<size_t>(nx_) * static_cast<size_t>(nz_) + 1, 0);
  // Merge overlapping extents cell by cell (entries are sorted by cell, then by bottom).
  constexpr float kJoin = 0.01f;
  size_t i = 0;
  for (uint32_t c = 0; c + 1 < first_.size(); ++c) {
    first_[c] = static_cast<uint32_t>(spans_.size());
    const size_t cell_begin = spans_.size();
    for (; i < entries.size() && entries[i].cell == c; ++i) {
      const Span s = entries[i].span;
      if (spans_.size() > cell_begin && s.y0 <= spans_.back().y1 + kJoin) {
        spans_.back().y1 = std::max(spans_.back().y1, s.y1);
      } else {
        spans_.push_back(s);
      }
    }
  }
  first_.back() = static_cast<uint32_t>(spans_.size());
}

bool CollisionGrid::cell_range(glm::vec3 p, float radius, int* x0, int* z0, int* x1,
                               int* z1) const {
  *x0 = std::max(0, static_cast<int>(std::floor((p.x - radius - origin_.x) / cell_)));
  *x1 = std::min(nx_ - 1, static_cast<int>(std::floor((p.x + radius - origin_.x) / cell_)));
  *z0 = std::max(0, static_cast<int>(std::floor((p.z - radius - origin_.y) / cell_)));
  *z1 = std::min(nz_ - 1, static_cast<int>(std::floor((p.z + radius - origin_.y) / cell_)));
  return *x0 <= *x1 && *z0 <= *z1;
}

bool CollisionGrid::blocked(glm::vec3 feet, float radius, float step, float height) const {
  int x0, z0, x1, z1;
  if (!cell_range(feet, radius, &x0, &z0, &x1, &z1)) return true;  // outside the inn
  const float lo = feet.y + step, hi = feet.y + height;
  for (int z = z0; z <= z1; ++z) {
    for (int x = x0; x <= x1; ++x) {
      // Only cells that meet the disc (closest point of the cell's square within the radius).
      const float cx = std::clamp(feet.x, origin_.x + static_cast<float>(x) * cell_,
                                  origin_.x + static_cast<float>(x + 1) * cell_);
      const float cz = std::clamp(feet.z, origin_.y + static_cast<float>(z) * cell_,
                                  origin_.y + static_cast<float>(z + 1) * cell_);
      if ((cx - feet.x) * (cx - feet.x) + (cz - feet.z) * (cz - feet.z) > radius * radius) continue;
      const size_t c = static_cast<size_t>(z) * static_cast<size_t>(nx_) + static_cast<size_t>(x);
      for (uint32_t s = first_[c]; s < first_[c + 1]; ++s) {
        if (spans_[s].y1 > lo && spans_[s].y0 < hi) return true;
      }
    }
  }
  return false;
}

std::optional<float> CollisionGrid::floor_at(glm::vec3 feet, float radius, float step,
                                             float drop) const {
  int x0, z0, x1, z1;
  if (!cell_range(feet, radius, &x0, &z0, &x1, &z1)) return std::nullopt;
  std::optional<float> best;
  for (int z = z0; z <= z1; ++z) {
    for (int x = x0; x <= x1; ++x) {
      const size_t c = static_cast<size_t>(z) * static_cast<size_t>(nx_) + static_cast<size_t>(x);
      for (uint32_t s = first_[c]; s < first_[c + 1]; ++s) {
        const float top = spans_[s].y1;
        if (top <= feet.y + step && top >= feet.y - drop && (!best || top > *best)) best = top;
      }
    }
  }
  return best;
}

}  // namespace lightpatch::inn
